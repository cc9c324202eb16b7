"""``ArmEmuBoard``: the exact bluepill ``firmware.elf`` on an emulated STM32F103.

The same interface as ``proleg.sim.board.SimBoard`` (reset, run_ticks, tick_us,
time_us, pwm, write/read, the IMU truth and fault injections), so the plant and the
hil_tests can drive either. Time is the emulated core's: cycles at 72 MHz, counted per
executed block (see ``timing.py``). Two shortcuts keep it fast without changing what
the firmware observes: a `b .` loop jumps to the next event (``cycles.c``), and a loop
that polls a peripheral whose state cannot change before the next event (the same
status read again with no write in between) jumps time forward to that event, at most
``POLL_SKIP_US`` at a time, so that software timeouts still expire close to when they
would on the chip. The core's tick wait (``wait_tick`` in core/main.c polling
``hal_micros``) skips straight to the firmware's next tick when the symbols ``wait_tick``
and ``next_tick`` exist. A tick's busy time runs from the firmware's ``hal_tick_mark(1)``
to its ``hal_tick_mark(0)``: stores to BKP_DR1 (``bkp.py``).
"""

from __future__ import annotations

import ctypes
import re
import time
from dataclasses import dataclass
from pathlib import Path

from unicorn import UC_ARCH_ARM, UC_HOOK_BLOCK, UC_HOOK_CODE, UC_MODE_MCLASS, UC_MODE_THUMB, UC_PROT_ALL, Uc
from unicorn import arm_const as A
from unicorn.unicorn_py3.unicorn import uc_hook_h, uclib

from ...errors import SimError
from ...firmware.families import hal_root
from .bkp import Bkp
from .bxcan import BxCan
from .clocks import CPU_HZ, NEVER, Iwdg, Rcc
from .core import HARDFAULT, SYSTICK, CortexM
from .elf import read_elf
from .fpec import PAGE_SIZE as NV_PAGE_SIZE, Fpec
from .gpio import Gpio
from .i2c import Bus, BusDevices, I2c
from .native import Native
from .scs import Scs
from .tim import Timer
from .timing import cycle_table
from .usart import Usart

IMU_FAULTS = {"ok": 0, "no-ack": 1, "stuck": 2, "garbage": 3}
FLASH_BASE, FLASH_SIZE = 0x08000000, 0x10000
RAM_BASE, RAM_SIZE = 0x20000000, 0x5000
USART1_IRQ = 37
POLL_SKIP_US = 20  # a poll loop with no peripheral event coming skips this much at a time
POLL_JUMP_US = 2000  # a peripheral event at most this far ahead is jumped to directly
POLL_WINDOW = 400  # cycles: two identical status reads closer than this are a poll loop
CYC_PER_US = CPU_HZ // 1_000_000
_PC, _LR = A.UC_ARM_REG_PC, A.UC_ARM_REG_LR
_I2C1_STATUS = {0x40005400, 0x40005414}  # CR1 (START/STOP cleared by hardware), SR1
_I2C2_STATUS = {0x40005800, 0x40005814}
_SIDE_EFFECT_READS = {0x40005410, 0x40005418, 0x40005810, 0x40005818, 0x40013804}  # I2C DR, SR2 (clears ADDR), USART1 DR
_USART_SR = 0x40013800
_TIME_REGS = {0xE000E010, 0xE000E018, 0xE000ED04}  # SYST_CSR, SYST_CVR, ICSR: reading them is not a poll


@dataclass(frozen=True)
class TickBudget:
    """Busy time per control tick (app_tick entry to the next wait), µs."""

    tick_period_us: int
    ticks: int
    mean: float
    p99: float
    max: float

    def as_dict(self) -> dict:
        return {"tick_period_us": self.tick_period_us, "tick_busy_us": {
            "ticks": self.ticks, "mean": round(self.mean, 1), "p99": round(self.p99, 1), "max": round(self.max, 1)}}


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


class ArmEmuBoard:
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
            size = 0x1000 if d is self.scs else 0x400
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

    # -- MMIO -----------------------------------------------------------------------
    def _device(self, addr: int):
        return self._by_addr.get(addr & ~0x3FF) or self._by_addr.get(addr & ~0xFFF)

    def _word(self, addr: int) -> int:
        """A RAM word, read through the C API (the binding's mem_read costs more than the read)."""
        uclib.uc_mem_read(self.uc._uch, addr, self._membuf, 4)
        return int.from_bytes(self._membuf.raw, "little")

    def _reg(self, reg_id: int) -> int:
        uclib.uc_reg_read(self.uc._uch, reg_id, ctypes.byref(self._regbuf))
        return self._regbuf.value

    def _mmio_read(self, uc, offset: int, size: int, page: int) -> int:
        if page == 0xE000E000 and self.trace is None:  # SysTick/NVIC/SCB: the clock, never a poll (fast path)
            if offset == 0x18 and self._wait is not None:
                self._wait_skip()
            now = self.native.cycles.value
            if now >= self._soonest:
                self._advance(now)
            return (self.scs.read(offset & ~3, now) >> (8 * (offset & 3))) & ((1 << (8 * size)) - 1)
        addr = page + offset
        if addr == 0xE000E018 and self._wait is not None:
            self._wait_skip()  # before the read: the firmware sees the time it skipped to
        now = self.native.cycles.value
        if now >= self._soonest:
            self._advance(now)
        d = self._device(addr)
        if d is None:
            return self._unmodelled.get(addr & ~3, 0)
        reg = addr - d.BASE
        v = d.read(reg & ~3, now) >> (8 * (reg & 3))
        if d is self.i2c1 or d is self.i2c2 or d is self.usart:  # a read may start a byte (DR, SR2)
            self._soonest = min(self._soonest, d.next_event())
        if addr not in _TIME_REGS and addr not in _SIDE_EFFECT_READS and self._poll(addr, v):
            now = self.native.cycles.value  # jumped to where the loop would see a change:
            self._advance(now)  # read again (these registers have no read side effects)
            v = d.read(reg & ~3, now) >> (8 * (reg & 3))
        if self.trace is not None:
            self.trace.append((now, "R", addr, v))
        return v & ((1 << (8 * size)) - 1)

    def _mmio_write(self, uc, offset: int, size: int, value: int, page: int) -> None:
        addr = page + offset
        now = self.native.cycles.value
        self._advance(now)
        self._poll_seen.clear()
        self._soonest = 0
        if self.trace is not None:
            self.trace.append((now, "W", addr, value))
        d = self._device(addr)
        if d is None:
            self._unmodelled[addr & ~3] = value
            return
        d.write((addr - d.BASE) & ~3, value, now)
        if d is self.i2c1 or d is self.i2c2:
            d.poll_blocked(now)
        if d is self.usart or d is self.scs or d is self.iwdg or d is self.rcc or d is self.can:
            self.native.deadline.value = min(self.native.deadline.value, now + 1)  # re-plan events

    def _poll(self, addr: int, value: int) -> bool:
        """A value read a third time, each read within POLL_WINDOW cycles of the last, with no
        write in between, is a polling loop: nothing it reads can change before the next
        event. For a status register with its transfer in flight, jump to the completion;
        otherwise POLL_SKIP_US at a time (so software timeouts expire close to when they
        would on the chip). Two reads are not enough: a loop may read a register twice per
        pass and leave on the second (i2c_wait checks SR1 for the flag, then for errors)."""
        key = (addr, value)
        now = self.native.cycles.value
        last, n = self._poll_seen.get(key, (0, 0))
        n = n + 1 if n and now - last <= POLL_WINDOW else 1
        self._poll_seen[key] = (now, n)
        if n < 3:  # code may read a value twice and act on it (the i2c_wait loop does): not a poll yet
            return False
        device = NEVER
        if addr in _I2C1_STATUS:
            device = self.i2c1.next_event()
        elif addr in _I2C2_STATUS:
            device = self.i2c2.next_event()
        elif addr == _USART_SR:
            device = self.usart.next_event()
        if device - now <= POLL_JUMP_US * CYC_PER_US:  # waiting for a transfer in flight
            target = min(device, self._next_interrupt(), self._end)
        else:
            target = min(self._next_interrupt(), self._end, now + POLL_SKIP_US * CYC_PER_US)
        if target > now:
            self.native.cycles.value = target
            self._poll_seen.clear()
            return True
        return False

    def _wait_skip(self) -> None:
        """In the tick wait: jump to just before the firmware's next tick (or the next event)."""
        pc = self._reg(_PC)
        lr = self._reg(_LR)
        w = self._wait
        if not (w.value <= pc < w.value + w.size or w.value <= (lr & ~1) < w.value + w.size):
            return
        if any(i2c.core_has_work() for i2c in self._i2cs):
            return  # a flag the core's idle loop acts on (hal_i2c_poll): run it
        now = self.native.cycles.value
        # Nothing the idle loop polls can change before the next peripheral event (an I2C
        # byte or STOP completing included): jump to it or to the firmware's next tick.
        target = min(self._next_event(), self._end)
        if self._next_tick and self._ms_count:
            next_tick = self._word(self._next_tick.value)
            ms = self._word(self._ms_count.value)
            fw_us = ms * 1000 + (self.scs.rvr - self.scs.cvr(now)) // max(1, self.rcc.sysclk // 1_000_000)
            ahead = ((next_tick - fw_us + 2**31) % 2**32) - 2**31
            if ahead > 0:
                target = min(target, now + ahead * CYC_PER_US)
            else:
                return
        else:
            target = min(target, now + POLL_SKIP_US * CYC_PER_US)
        if target > now:
            self.native.cycles.value = target

    # -- tick markers -----------------------------------------------------------------
    def _on_mark(self, busy: int, now: int) -> None:
        if busy:
            self._tick_start = now
        elif self._tick_start is not None:
            self.busy_us.append((now - self._tick_start) / CYC_PER_US)
            self._tick_start = None

    def stack_peak_bytes(self) -> int:
        """Deepest stack use since power-on: RAM is all zeros at reset, so the lowest
        non-zero byte between the end of static data and the initial SP marks the deepest
        point the stack wrote. A lower bound (zeros pushed at the very bottom do not show)."""
        sp0 = int.from_bytes(self._flash[0:4], "little")
        static_end = max((s.value + s.size for s in self.elf.symbols.values()
                          if RAM_BASE <= s.value < RAM_BASE + RAM_SIZE), default=RAM_BASE)
        ram = bytes(self.uc.mem_read(static_end, sp0 - static_end))
        for i, b in enumerate(ram):
            if b:
                return sp0 - (static_end + i)
        return 0

    def clear_ticks(self) -> None:
        """Start a new measurement window (e.g. after boot), as ``AvrEmuBoard.clear_ticks``."""
        self.busy_us.clear()

    def tick_budget(self) -> TickBudget:
        b = sorted(self.busy_us)
        if not b:
            return TickBudget(self.tick_us, 0, 0.0, 0.0, 0.0)
        p99 = b[min(len(b) - 1, int(0.99 * len(b)))]
        return TickBudget(self.tick_us, len(b), sum(b) / len(b), p99, b[-1])

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

    def call(self, function: str, *args: int, max_cycles: int = 1_000_000) -> int:
        """Call a firmware function now (interrupts held off) and return r0; the CPU state
        is restored afterwards. The cycles it takes pass in emulated time."""
        sym = self.elf.symbol(function)
        if sym is None or not sym.is_func:
            raise SimError(f"{self.elf.path}: no function {function!r} in the firmware")
        ctx = self.uc.context_save()
        for reg, v in zip((A.UC_ARM_REG_R0, A.UC_ARM_REG_R1, A.UC_ARM_REG_R2, A.UC_ARM_REG_R3), args):
            self.uc.reg_write(reg, v & 0xFFFFFFFF)
        sentinel = FLASH_BASE + FLASH_SIZE - NV_PAGE_SIZE - 16  # erased flash, never executed
        self.uc.reg_write(A.UC_ARM_REG_LR, sentinel | 1)
        self.native.deadline.value = self.cycles + max_cycles
        try:
            self.uc.emu_start(sym.value | 1, sentinel, 0, 0)
        except Exception as e:  # noqa: BLE001 - any unicorn error is a failed probe
            self.uc.context_restore(ctx)
            raise SimError(f"calling {function} in the emulated firmware failed: {e}") from None
        r0 = self.uc.reg_read(A.UC_ARM_REG_R0)
        if self.uc.reg_read(A.UC_ARM_REG_PC) != sentinel:
            self.uc.context_restore(ctx)
            raise SimError(f"{function} did not return within {max_cycles} cycles")
        self.uc.context_restore(ctx)
        return r0

    def watch_returns(self, function: str) -> list[tuple[int, int]]:
        """Record (time in cycles, r0) at every return of a firmware function from now on
        (a probe for tests: it hooks each instruction of that function, which is slow)."""
        sym = self.elf.symbol(function)
        if sym is None or not sym.is_func or not sym.size:
            raise SimError(f"{self.elf.path}: no function {function!r} in the firmware")
        out: list[tuple[int, int]] = []
        lo = sym.value - FLASH_BASE
        code = self._flash[lo : lo + sym.size]
        returns = set()
        for i in range(0, len(code) - 1, 2):
            hw = code[i] | code[i + 1] << 8
            hw2 = code[i + 2] | code[i + 3] << 8 if i + 3 < len(code) else 0
            if hw == 0x4770 or hw & 0xFF00 == 0xBD00 or (hw == 0xE8BD and hw2 & 0x8000):  # bx lr, pop {.., pc}
                returns.add(sym.value + i)

        def hook(uc, address, size, user):
            if address in returns:
                out.append((self.native.cycles.value, self._reg(A.UC_ARM_REG_R0)))
                for lst, fn in self._returns_sinks:
                    if lst is out:
                        fn(out[-1][0])

        self.uc.hook_add(UC_HOOK_CODE, hook, None, sym.value, sym.value + sym.size - 1)
        return out

    def time_in(self, function: str) -> list[int]:
        """Accumulate the cycles spent inside a firmware function (entry to return, callees
        and interrupts included) from now on: returns [total cycles, calls]."""
        sym = self.elf.symbol(function)
        if sym is None or not sym.is_func or not sym.size:
            raise SimError(f"{self.elf.path}: no function {function!r} in the firmware")
        acc = [0, 0]
        start: list[int] = []
        rets = self.watch_returns(function)

        def entry(uc, address, size, user):
            start.append(self.native.cycles.value)

        def on_return(t: int) -> None:
            if start:
                acc[0] += t - start.pop()
                acc[1] += 1

        self.uc.hook_add(UC_HOOK_CODE, entry, None, sym.value, sym.value)
        self._returns_sinks.append((rets, on_return))
        return acc

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
