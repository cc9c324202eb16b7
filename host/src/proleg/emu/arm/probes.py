"""Probes into the running firmware, for tests and measurements on the arm-emu board.

``FirmwareProbes`` is a part of ``ArmEmuBoard`` (board.py): call a firmware function,
record a function's returns, or add up the time spent in it.
"""

from __future__ import annotations

from unicorn import UC_HOOK_CODE
from unicorn import arm_const as A

from ...errors import SimError
from .fpec import PAGE_SIZE as NV_PAGE_SIZE
from .memmap import FLASH_BASE, FLASH_SIZE


class FirmwareProbes:
    """``call``, ``watch_returns`` and ``time_in`` of ``ArmEmuBoard``."""

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
