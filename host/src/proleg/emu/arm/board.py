"""``ArmEmuBoard``: the exact bluepill ``firmware.elf`` on an emulated STM32F103.

The same interface as ``proleg.sim.board.SimBoard`` (reset, run_ticks, tick_us,
time_us, pwm, write/read, the IMU truth and fault injections), so the plant and the
hil_tests can drive either. Time is the emulated core's: cycles at 72 MHz, counted per
executed block (see ``timing.py``); a `b .` loop jumps to the next event (``cycles.c``).
This file holds the machine (memory, peripherals, reset), the run loop with its
exceptions, and the board interface; the rest of the class is in its parts:
``mmio.py`` (peripheral accesses, and the poll and tick-wait fast paths), ``ticks.py``
(tick busy time from the firmware's ``hal_tick_mark``, stack use) and ``probes.py``
(calling and timing firmware functions).
"""

from __future__ import annotations

import ctypes
import re
import time
from pathlib import Path

from unicorn import UC_ARCH_ARM, UC_HOOK_BLOCK, UC_MODE_MCLASS, UC_MODE_THUMB, UC_PROT_ALL, Uc
from unicorn.unicorn_py3.unicorn import uc_hook_h, uclib

from ...errors import SimError
from ...firmware.families import hal_root
from .bkp import Bkp
from .bxcan import BxCan
from .clocks import CPU_HZ, RESET_FLAGS, Iwdg, Rcc
from .core import HARDFAULT, SYSTICK, CortexM
from .elf import read_elf
from .fpec import PAGE_SIZE as NV_PAGE_SIZE, Fpec
from .gpio import Gpio
from .i2c import Bus, BusDevices, I2c
from .memmap import CYC_PER_US, FLASH_BASE, FLASH_SIZE, RAM_BASE, RAM_SIZE, USART1_IRQ
from .mmio import MmioAccess
from .native import Native
from .probes import FirmwareProbes
from .scs import Scs
from .ticks import TickBudget, TickMarks
from .tim import Timer
from .timing import cycle_table
from .usart import Usart

__all__ = ["ArmEmuBoard", "TickBudget", "FLASH_BASE", "FLASH_SIZE", "RAM_BASE", "RAM_SIZE", "CYC_PER_US", "IMU_FAULTS"]

IMU_FAULTS = {"ok": 0, "no-ack": 1, "stuck": 2, "garbage": 3}


def _stm32_pwm() -> dict[str, tuple[int, ...]]:
    """The stm32f1 HAL's PWM pins: name -> (timer, channel, port 0=A 1=B, pin) (family.toml)."""
    import tomllib

    doc = tomllib.loads((hal_root() / "stm32f1" / "family.toml").read_text(encoding="utf-8"))
    return {str(k).upper(): tuple(v) for k, v in doc["pwm"]["pins"].items()}


_STM32_PWM = _stm32_pwm()


def _tick_us_from_build(elf: Path) -> int:
    cfg = elf.parent / "gen" / "robot_config.h"
    m = re.search(r"#define\s+CFG_TICK_US\s+(\d+)", cfg.read_text()) if cfg.exists() else None
    if not m:
        raise SimError(f"{cfg}: no CFG_TICK_US (pass tick_us, or use the build directory proleg build made)")
    return int(m.group(1))


class ArmEmuBoard(MmioAccess, TickMarks, FirmwareProbes):
    """One emulated bluepill running one firmware image."""

    def __init__(self, elf_path: str | Path, seed: int = 1, *, tick_us: int | None = None,
                 pwm_pins: tuple[str, ...] = ("PA0", "PA1", "PA2", "PA3"), imu_addresses=(0x68, 0x69),
                 imu_wiring: tuple[tuple[int, int, int, int], ...] | None = None):
        self.elf = read_elf(elf_path)
        self.tick_us = tick_us or _tick_us_from_build(self.elf.path)
        self.pwm_map = []
        for pin in pwm_pins:
            if pin.upper() not in _STM32_PWM:
                raise SimError(f"PWM pin {pin!r} is not a TIM2-TIM4 output (expected one of {sorted(_STM32_PWM)})")
            t, ch, port, p = _STM32_PWM[pin.upper()]
            self.pwm_map.append((t, ch, port, p))
        # The IMUs: model slot i is wired at imu_wiring[i] = (bus, address, multiplexer
        # address or 0, channel) and named by imu_addresses[i], host-sim's key for it
        # (proleg.firmware.placement.sim_imu_keys: the address on I2C1 directly, else
        # 0x80 | limb). Without a wiring, each of imu_addresses sits on I2C1 directly.
        self.imu_addresses = tuple(imu_addresses)
        self.imu_wiring = tuple(imu_wiring) if imu_wiring is not None else tuple((0, a, 0, 0) for a in self.imu_addresses)
        if len(self.imu_wiring) != len(self.imu_addresses):
            raise SimError(f"arm-emu: {len(self.imu_addresses)} IMU keys for {len(self.imu_wiring)} wired IMUs")
        self.imu_keymap: dict[int, int] = {k: slot for slot, k in enumerate(self.imu_addresses)}  # key -> model slot
        self.native = Native()
        self._flash = bytearray(FLASH_SIZE)
        for seg in self.elf.segments:
            if FLASH_BASE <= seg.paddr < FLASH_BASE + FLASH_SIZE:
                off = seg.paddr - FLASH_BASE
                self._flash[off : off + len(seg.data)] = seg.data
        self._build_machine()
        self.host_seconds = 0.0
        self.reset(seed)

    # -- construction ---------------------------------------------------------------
    def _build_machine(self) -> None:
        uc = Uc(UC_ARCH_ARM, UC_MODE_THUMB | UC_MODE_MCLASS)
        self.uc = uc
        uc.mem_map(FLASH_BASE, FLASH_SIZE - NV_PAGE_SIZE, UC_PROT_ALL)  # the last page: the FPEC's (fpec.py)
        uc.mem_write(FLASH_BASE, bytes(self._flash[:-NV_PAGE_SIZE]))
        uc.mem_map(RAM_BASE, RAM_SIZE, UC_PROT_ALL)
        self.rcc = Rcc()
        self.flash_acr = self.fpec = Fpec(self._stall)
        self.fpec.map(uc)
        self.iwdg = Iwdg()
        self.scs = Scs()
        bus1, bus2 = BusDevices(self.native, 0), BusDevices(self.native, 1)
        self.bus = Bus(bus1.stop)
        self.i2c1 = I2c(0x40005400, lambda: self.rcc.pclk1, self.bus, bus1)
        self.i2c2 = I2c(0x40005800, lambda: self.rcc.pclk1, Bus(bus2.stop), bus2)
        timclk = lambda: self.rcc.pclk1 * (2 if self.rcc.pclk1 != self.rcc.sysclk else 1)  # noqa: E731
        self.timers = {2: Timer(0x40000000, timclk), 3: Timer(0x40000400, timclk), 4: Timer(0x40000800, timclk)}
        self.gpioa = Gpio(0x40010800)
        self.gpiob = Gpio(0x40010C00, self._gpio_changed)
        self.gpiob.external = self._gpiob_level
        self.afio = Gpio(0x40010000)
        self.usart = Usart()
        self.bkp = Bkp(self._on_mark)
        self.can = BxCan(lambda: self.rcc.pclk1)
        self.devices = [self.rcc, self.flash_acr, self.iwdg, self.scs, self.i2c1, self.i2c2, *self.timers.values(),
                        self.gpioa, self.gpiob, self.afio, self.usart, self.bkp, self.can]
        self._i2cs = (self.i2c1, self.i2c2)
        self._stepped = [self.scs, self.usart, self.i2c1, self.i2c2, self.can]
        self._soonest = 0
        self._by_addr: dict[int, object] = {}
        pages = set()
        for d in self.devices:
            self._by_addr[d.BASE] = d
            pages.add(d.BASE & ~0xFFF)
        self._unmodelled: dict[int, int] = {}
        for page in sorted(pages):
            uc.mmio_map(page, 0x1000, self._mmio_read, page, self._mmio_write, page)
        # the cycle counter, natively
        table = cycle_table(bytes(self._flash))
        stop = ctypes.cast(uclib.uc_emu_stop, ctypes.c_void_p).value
        self.native.setup(table, FLASH_BASE, bytes(self._flash), stop)
        self._hook = uc_hook_h()
        err = uclib.uc_hook_add(uc._uch, ctypes.byref(self._hook), UC_HOOK_BLOCK,
                                ctypes.c_void_p(self.native.block_hook), None, 1, 0)
        if err:
            raise SimError(f"unicorn: cannot add the cycle-counting hook (error {err})")
        self.cpu = CortexM(uc, self._vector)
        self._regbuf = ctypes.c_uint32()
        self._membuf = ctypes.create_string_buffer(4)
        self._returns_sinks: list = []
        self.trace: list | None = None  # (cycle, "R"/"W", address, value) of every MMIO access when a list
        # tick markers and the tick-wait fast path
        sym = self.elf.symbol
        self._wait = sym("wait_tick")
        self._next_tick = sym("next_tick")
        self._ms_count = sym("ms_count")
        self._watch_idle()

    def _stall(self, cycles: int) -> None:
        """The CPU waits (a flash erase or program): its clock moves on."""
        self.native.cycles.value += cycles

    def _vector(self, n: int) -> int:
        vtor = self.scs.regs.get(0xD08, 0) or FLASH_BASE
        off = (vtor - FLASH_BASE) + 4 * n if vtor >= FLASH_BASE else 4 * n
        return int.from_bytes(self._flash[off : off + 4], "little")

    # -- time -----------------------------------------------------------------------
    @property
    def cycles(self) -> int:
        return self.native.cycles.value

    def reset(self, seed: int = 1) -> None:
        """Power-on reset: RAM cleared, peripherals and IMUs at their power-up state, time 0."""
        self.seed = seed
        self.native.cycles.value = 0
        self.native.lib.sim_mpu_power_on(seed & 0xFFFFFFFF)
        self.native.lib.emu_i2c_unwire()  # multiplexers too: power-on, no channel connected
        for slot, (bus, addr, mux, ch) in enumerate(self.imu_wiring):
            self.native.lib.emu_i2c_wire(slot, bus, addr, mux, ch)
        self.uc.mem_write(RAM_BASE, bytes(RAM_SIZE))
        self.rcc.csr_flags = 0
        self.usart.host_rx.clear()
        self.usart.host_tx.clear()
        self.can.host_rx.clear()
        self.can.host_tx.clear()
        self.bus.hold_bits = []
        self._system_reset("power-on")
        self.busy_us: list[float] = []
        self.resets: list[tuple[float, str]] = []

    def restart(self, cause: str = "external") -> None:
        """A reset that is not a power-on (``SimBoard.restart``): the NRST pin ("external"), the
        watchdog or a software reset; RAM keeps what it held, as the chip's does (on the
        STM32F103 a brown-out is a power-on reset: POR/PDR)."""
        causes = [c for c in RESET_FLAGS if c != "power-on"]
        if cause not in causes:
            raise ValueError(f"restart cause {cause!r}: expected one of {', '.join(causes)}")
        self.resets.append((self.cycles / CPU_HZ, cause))
        self._system_reset(cause)

    def _system_reset(self, cause: str) -> None:
        for d in self.devices:
            if d is self.rcc:
                d.system_reset(cause)
            elif hasattr(d, "reset"):
                d.reset()
        self.hardfault_pending = False
        self._tick_start: int | None = None
        self._poll_seen: dict = {}
        self._soonest = 0
        self.cpu.reset()

    def run_ticks(self, n: int) -> None:
        if n > 0:
            self.run_us(n * self.tick_us)

    def run_us(self, us: int) -> None:
        t0 = time.perf_counter()
        self._run_until(self.cycles + us * CYC_PER_US)
        self.host_seconds += time.perf_counter() - t0

    @property
    def time_us(self) -> int:
        return self.cycles // CYC_PER_US

    @property
    def time_s(self) -> float:
        return self.cycles / CPU_HZ

    # -- the run loop ---------------------------------------------------------------
    def _advance(self, now: int) -> None:
        if now < self._soonest:
            return
        for d in self._stepped:
            d.advance(now)
        self._soonest = self._next_event()
        if self.iwdg.next_event() <= now:
            self.resets.append((now / CPU_HZ, "watchdog"))
            self._system_reset("watchdog")
        elif self.scs.reset_request:
            self.resets.append((now / CPU_HZ, "software"))
            self._system_reset("software")

    def _replan(self) -> None:
        """Some device's next event may have moved: recompute at the next access."""
        self._soonest = 0

    def _next_event(self) -> int:
        return min(self.scs.next_event(), self.usart.next_event(), self.i2c1.next_event(), self.i2c2.next_event(),
                   self.iwdg.next_event(), self.can.next_event())

    def _next_interrupt(self) -> int:
        """The next event that can interrupt or reset the core (I2C is polled: not one)."""
        return min(self.scs.next_event(), self.usart.next_event(), self.iwdg.next_event(), self.can.next_event())

    def _pending(self) -> list[tuple[int, int]]:
        """(priority, exception number) of every pending exception."""
        out = []
        if self.hardfault_pending:
            out.append((-1, HARDFAULT))
        if self.scs.systick_pending:
            out.append((self.scs.systick_priority(), SYSTICK))
        usart = self.usart.irq() or self.scs.ispr[USART1_IRQ >> 5] >> (USART1_IRQ & 31) & 1
        if usart and self.scs.irq_enabled(USART1_IRQ):
            out.append((self.scs.irq_priority(USART1_IRQ), 16 + USART1_IRQ))
        for irq in self.can.irqs():  # bxCAN (bxcan.py): level lines, as USART1's
            if self.scs.irq_enabled(irq):
                out.append((self.scs.irq_priority(irq), 16 + irq))
        return out

    def _prio(self, exc: int) -> int:
        if exc == HARDFAULT:
            return -1
        if exc == SYSTICK:
            return self.scs.systick_priority()
        return self.scs.irq_priority(exc - 16)

    def _take_exception(self) -> bool:
        """Take the highest pending exception if it may preempt; True when one is masked."""
        pend = self._pending()
        if not pend:
            return False
        prio, exc = min(pend)
        if exc in self.cpu.active or prio >= self.cpu.running_priority(self._prio):
            return True
        if exc == HARDFAULT:
            self.hardfault_pending = False
        elif exc == SYSTICK:
            self.scs.systick_pending = False
        else:
            irq = exc - 16
            self.scs.ispr[irq >> 5] &= ~(1 << (irq & 31))
        self.cpu.enter(exc)
        self._poll_seen.clear()
        return False

    def _run_until(self, end: int) -> None:
        native = self.native
        self._end = end
        while True:
            now = native.cycles.value
            self._advance(now)
            if now >= end:
                return
            masked = self._take_exception()
            deadline = min(end, self._next_interrupt())
            if masked:
                deadline = min(deadline, now + 32)
            native.deadline.value = max(deadline, now + 1)
            self.cpu.run()
            if self.cpu.exc_exit:
                self.cpu.exit()
                self._poll_seen.clear()  # an interrupt returning is not a polling loop
            if self.cpu.fault:
                self.cpu.fault = None
                self.hardfault_pending = True
                if HARDFAULT in self.cpu.active:  # lockup: the chip stops until a reset
                    native.cycles.value = max(native.cycles.value, min(end, self._next_event()))

    # -- outputs --------------------------------------------------------------------
    def pwm_permyriad(self, channel: int) -> int:
        """MOSFET duty of a channel as the pin drives it (0 unless the pin is the timer's)."""
        if not 0 <= channel < len(self.pwm_map):
            return 0
        t, ch, port, pin = self.pwm_map[channel]
        gpio = self.gpiob if port else self.gpioa
        if not gpio.is_af_output(pin):
            return 10000 if gpio.is_gp_output(pin) and gpio.odr >> pin & 1 else 0
        return self.timers[t].duty_permyriad(ch - 1, self.native.cycles.value)

    def pwm(self, channel: int) -> float:
        return self.pwm_permyriad(channel) / 10000.0

    # -- host link (USART1) ---------------------------------------------------------
    def write(self, data: bytes) -> None:
        """Bytes from the host; they reach the firmware at the baud rate."""
        self.usart.host_rx.extend(data)
        self.usart.kick(self.native.cycles.value)
        self._soonest = 0

    def read(self) -> bytes:
        out = bytes(self.usart.host_tx)
        self.usart.host_tx.clear()
        return out

    # -- host link (bxCAN, images whose host link is CAN) -------------------------------
    has_can = True

    def can_write(self, arbitration_id: int, data: bytes) -> None:
        """A standard frame from the host onto the bus; it reaches the controller at the bit rate."""
        self.can.host_rx.append((arbitration_id & 0x7FF, bytes(data[:8])))
        self.can.kick(self.native.cycles.value)
        self._soonest = 0

    def can_read(self) -> list[tuple[int, bytes]]:
        """Frames the controller has sent since the last read: (identifier, data)."""
        out, self.can.host_tx[:] = list(self.can.host_tx), []
        return out

    # -- IMUs -----------------------------------------------------------------------
    # ``addr`` is the IMU's key (imu_addresses); a key no IMU has is ignored (reads 0xFF),
    # as on avr-emu and host-sim.
    def imu_truth(self, addr: int, psi_deg: float, dpsi_dps: float) -> None:
        if addr in self.imu_keymap:
            self.native.lib.sim_mpu_set_truth_slot(self.imu_keymap[addr], psi_deg, dpsi_dps)

    def imu_fault(self, addr: int, mode: str) -> None:
        if mode not in IMU_FAULTS:
            raise SimError(f"unknown IMU fault {mode!r} (expected one of: {', '.join(IMU_FAULTS)})")
        if addr in self.imu_keymap:
            self.native.lib.sim_mpu_set_fault_slot(self.imu_keymap[addr], IMU_FAULTS[mode])

    def imu_noise(self, addr: int, accel_ug_rthz: float, gyro_dps_rthz: float, accel_offset_mg: float) -> None:
        if addr in self.imu_keymap:
            self.native.lib.sim_mpu_set_noise_slot(self.imu_keymap[addr], accel_ug_rthz, gyro_dps_rthz, accel_offset_mg)

    def imu_startup(self, addr: int, us: float) -> None:
        """The IMU at key ``addr`` does not acknowledge until ``us`` after power-on (kept
        across resets; call ``reset()`` after it to boot with it), as avr-emu's."""
        if addr not in self.imu_keymap:
            raise SimError(f"arm-emu: no IMU at {addr:#04x} (IMUs: {', '.join(f'{k:#04x}' for k in self.imu_keymap)})")
        self.native.lib.emu_i2c_set_startup_us(self.imu_keymap[addr], max(0, round(us)))

    def imu_register(self, addr: int, reg: int) -> int:
        if addr not in self.imu_keymap:
            return 0xFF
        return int(self.native.lib.sim_mpu_peek_slot(self.imu_keymap[addr], reg))

    def mux_control(self, bus: int, addr: int) -> int:
        """The control register of the multiplexer at ``addr`` on ``bus`` (0 = I2C1); 0: none there."""
        return int(self.native.lib.sim_tca_control(bus, addr))

    def mux_active(self, bus: int, addr: int) -> int:
        """The channels that multiplexer connects now (its control register as of the last STOP)."""
        return int(self.native.lib.emu_i2c_mux_active(bus, addr))

    @property
    def mux_writes(self) -> int:
        """Control-register writes to every multiplexer since power-on (channel switches)."""
        return int(self.native.lib.sim_tca_writes())

    # -- emulator-only fault injection and probes -----------------------------------
    def i2c_hold_sda(self, byte: int = 0x00) -> None:
        """A slave stranded mid-byte (as after an aborted read): SDA follows ``byte``'s bits."""
        self.bus.strand(byte)

    def inject_hardfault(self) -> None:
        """The core faults (as on a wild pointer): HardFault is taken at once."""
        self.hardfault_pending = True

    @property
    def i2c_violations(self) -> int:
        return self.i2c1.violations

    @property
    def reset_flags_read(self) -> int:
        return self.rcc.csr_reads

    # -- bus lines ------------------------------------------------------------------
    def _gpiob_level(self, pin: int) -> int | None:
        for i2c, scl in ((self.i2c1, 6), (self.i2c2, 10)):
            if pin == scl + 1:
                driven = self.gpiob.is_gp_output(pin) and not self.gpiob.odr >> pin & 1
                return 0 if i2c.bus.sda_low or driven else 1
            if pin == scl:
                return 0 if self.gpiob.is_gp_output(pin) and not self.gpiob.odr >> pin & 1 else 1
        return None

    def _gpio_changed(self) -> None:
        g = self.gpiob
        for i2c, scl in ((self.i2c1, 6), (self.i2c2, 10)):
            i2c.bus.scl(0 if g.is_gp_output(scl) and not g.odr >> scl & 1 else 1)
            i2c.bus.sda_master(0 if g.is_gp_output(scl + 1) and not g.odr >> (scl + 1) & 1 else 1)
            i2c.poll_blocked(self.native.cycles.value)

    @property
    def speed(self) -> float:
        """Emulated seconds per host second so far."""
        return self.time_s / self.host_seconds if self.host_seconds else 0.0
