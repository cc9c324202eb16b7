"""The ``arm-emu`` board: the exact bluepill firmware image on an emulated STM32F103.

``ArmEmuBoard`` runs a ``firmware.elf`` on the unicorn CPU emulator with Python models
of the peripherals the HAL uses; ``bluepill_elf`` builds (once, cached) the bluepill
image of a robot; ``ArmEmuRobot`` closes the loop with proleg's plant. See
docs/emulators-arm.md.
"""

from .board import ArmEmuBoard, TickBudget
from .firmware import bluepill_elf
from .robot import ArmEmuRobot

__all__ = ["ArmEmuBoard", "ArmEmuRobot", "TickBudget", "bluepill_elf"]
