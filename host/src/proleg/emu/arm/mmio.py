"""The core's peripheral register accesses on the arm-emu board, and its two fast paths.

``MmioAccess`` is a part of ``ArmEmuBoard`` (board.py): unicorn calls ``_mmio_read`` and
``_mmio_write`` for every access to a peripheral page; they bring the devices up to the
access's cycle and pass it to the device that owns the address. Two shortcuts keep the
emulation fast without changing what the firmware observes: a loop that polls a
peripheral whose state cannot change before the next event (the same status read again
with no write in between) jumps time forward to that event, at most ``POLL_SKIP_US`` at a
time, so that software timeouts still expire close to when they would on the chip
(``_poll``); and the core's tick wait (``wait_tick`` in core/main.c polling ``hal_micros``)
skips straight to the firmware's next tick when the symbols ``wait_tick`` and
``next_tick`` exist (``_wait_skip``), once the core's ``app_idle`` has run after the tick's
work and after the last skip (it begins work of its own, not only on events).
"""

from __future__ import annotations

import ctypes

from unicorn import UC_HOOK_CODE
from unicorn import arm_const as A
from unicorn.unicorn_py3.unicorn import uclib

from .clocks import NEVER
from .memmap import CYC_PER_US

POLL_SKIP_US = 20  # a poll loop with no peripheral event coming skips this much at a time
POLL_JUMP_US = 2000  # a peripheral event at most this far ahead is jumped to directly
POLL_WINDOW = 400  # cycles: two identical status reads closer than this are a poll loop
_PC, _LR = A.UC_ARM_REG_PC, A.UC_ARM_REG_LR
_I2C1_STATUS = {0x40005400, 0x40005414}  # CR1 (START/STOP cleared by hardware), SR1
_I2C2_STATUS = {0x40005800, 0x40005814}
_SIDE_EFFECT_READS = {0x40005410, 0x40005418, 0x40005810, 0x40005818, 0x40013804}  # I2C DR, SR2 (clears ADDR), USART1 DR
_USART_SR = 0x40013800
_TIME_REGS = {0xE000E010, 0xE000E018, 0xE000ED04}  # SYST_CSR, SYST_CVR, ICSR: reading them is not a poll


class MmioAccess:
    """Peripheral register accesses and the poll/tick-wait fast paths of ``ArmEmuBoard``."""

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

    def _watch_idle(self) -> None:
        """Note each entry to the core's ``app_idle``. On the chip the tick wait calls it over
        and over, and it begins work of its own (the next IMU read once the tick has taken
        the last, telemetry), not only in answer to a peripheral event; so the skip waits
        for one call after each tick's work and after each skip (``_wait_skip``)."""
        self._idle_ran = True
        self._idle_hook = None
        idle = self.elf.symbol("app_idle")
        if self._wait is None or idle is None or not idle.size:
            return
        self._idle_ran = False
        entry = idle.value & ~1

        def hook(uc, address, size, user) -> None:
            self._idle_ran = True

        self._idle_hook = self.uc.hook_add(UC_HOOK_CODE, hook, None, entry, entry)

    def _wait_skip(self) -> None:
        """In the tick wait: jump to just before the firmware's next tick (or the next event)."""
        pc = self._reg(_PC)
        lr = self._reg(_LR)
        w = self._wait
        if not (w.value <= pc < w.value + w.size or w.value <= (lr & ~1) < w.value + w.size):
            return
        if not self._idle_ran:
            return  # the idle loop has work of its own to begin (an IMU read, telemetry): run it once
        if any(i2c.core_has_work() for i2c in self._i2cs):
            return  # a flag the core's idle loop acts on (hal_i2c_poll): run it
        if self.scs.systick_pending:
            return  # a wrap whose interrupt is not taken yet: the firmware's ms_count lags (see below)
        now = self.native.cycles.value
        # Nothing the idle loop polls can change before the next peripheral event (an I2C
        # byte or STOP completing included): jump to it or to the firmware's next tick.
        # Never past a SysTick wrap (it is an event), and never while one is pending: a
        # jump from a pending wrap to the next would fold two wraps into one interrupt and
        # the firmware's clock (ms_count, counted in SysTick_Handler) would lose a ms. That
        # was the 0.59-0.8x slow clock below 500 Hz: hal_micros reads SYST_CVR a second
        # time after seeing PENDSTSET, and the skip on that read took ms_count, not yet
        # incremented, for the firmware's time, 1 ms behind.
        target = min(self._next_event(), self._end)
        if self._next_tick and self._ms_count:
            next_tick = self._word(self._next_tick.value)
            ms = self._word(self._ms_count.value)
            cvr = self.scs.cvr(now)  # as hal_micros: the count 0 is where the next ms starts
            fw_us = ms * 1000 + (self.scs.rvr + 1 - cvr if cvr else 0) // max(1, self.rcc.sysclk // 1_000_000)
            ahead = ((next_tick - fw_us + 2**31) % 2**32) - 2**31
            if ahead > 0:
                target = min(target, now + ahead * CYC_PER_US)
            else:
                return
        else:
            target = min(target, now + POLL_SKIP_US * CYC_PER_US)
        if target > now:
            self.native.cycles.value = target
            self._idle_ran = self._idle_hook is None
