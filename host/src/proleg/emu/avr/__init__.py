"""avr-emu: the exact arduino-nano firmware.elf on simavr (ATmega328P at 16 MHz) with
proleg's peripherals: UART link, register-level MPU-6050s on a datasheet TWI, PWM read
from the timer registers, and the tick budget measured in CPU cycles.

``AvrEmuBoard`` is the simulated board; ``AvrEmuRobot`` puts it in closed loop with the
plant; ``nano_elf`` builds (and caches) a robot's firmware. See docs/emulators-avr.md.
"""

from .board import AvrEmuBoard
from .budget import TickBudget
from .firmware import nano_build_dir, nano_elf
from .robot import AvrEmuRobot

__all__ = ["AvrEmuBoard", "AvrEmuRobot", "TickBudget", "nano_build_dir", "nano_elf"]
