"""The arm-emu core's exception entry and return against the ARMv7-M ARM (B1.5.6, B1.5.8):
an exception taken inside an IT block runs its handler with EPSR.IT cleared, and the return
restores the block's remaining conditions from the stacked xPSR.

Found on the bluepill image of robots/paper-r1-one-actuator.toml: USART1's interrupt arrived
inside uart_read_byte's ITTTT block, the handler inherited the block's conditions, its
push/pop went out of step and the core fetched from 0x00000026 (HardFault, then the IWDG reset
the board every 52 ms). The real Cortex-M3 clears IT on entry; the emulator did not."""

from __future__ import annotations

import struct

import pytest

pytest.importorskip("unicorn")

from unicorn import UC_ARCH_ARM, UC_MODE_MCLASS, UC_MODE_THUMB, Uc  # noqa: E402
from unicorn import arm_const as A  # noqa: E402

from proleg.emu.arm.core import SYSTICK, XPSR_IT, CortexM  # noqa: E402

CODE, HANDLER, RAM = 0x1000, 0x2000, 0x20000000

# cmp r0, r1; itte ne; movne r2, #1; movne r3, #1; moveq r5, #1; b .
THREAD = [0x4288, 0xBF1A, 0x2201, 0x2301, 0x2501, 0xE7FE]
# movs r4, #7; movs r6, #9; bx lr (lr = EXC_RETURN)
ISR = [0x2407, 0x2609, 0x4770]


def _core() -> tuple[Uc, CortexM]:
    uc = Uc(UC_ARCH_ARM, UC_MODE_THUMB | UC_MODE_MCLASS)
    uc.mem_map(0, 0x10000)
    uc.mem_map(RAM, 0x10000)
    uc.mem_write(CODE, struct.pack(f"<{len(THREAD)}H", *THREAD))
    uc.mem_write(HANDLER, struct.pack(f"<{len(ISR)}H", *ISR))
    cpu = CortexM(uc, lambda exc: HANDLER | 1)
    uc.reg_write(A.UC_ARM_REG_SP, RAM + 0x1000)
    uc.reg_write(A.UC_ARM_REG_R0, 1)
    uc.reg_write(A.UC_ARM_REG_R1, 2)  # r0 != r1: the block's "ne" slots run, its "eq" slot does not
    return uc, cpu


def test_an_exception_inside_an_it_block_runs_its_handler_unconditionally_and_returns_into_the_block():
    uc, cpu = _core()
    # Stop before movne r3 (as the board's deadline hook stops a run): two conditional slots left.
    uc.emu_start(CODE | 1, CODE + 6, 100_000, 0)
    assert cpu.pc == CODE + 6 and uc.reg_read(A.UC_ARM_REG_XPSR) & XPSR_IT
    cpu.enter(SYSTICK)
    assert uc.reg_read(A.UC_ARM_REG_XPSR) & XPSR_IT == 0  # the handler runs outside the block
    cpu.run()
    assert cpu.exc_exit and cpu.fault is None
    assert (uc.reg_read(A.UC_ARM_REG_R4), uc.reg_read(A.UC_ARM_REG_R6)) == (7, 9)  # both handler moves ran
    cpu.exit()
    assert cpu.pc == CODE + 6 and uc.reg_read(A.UC_ARM_REG_XPSR) & XPSR_IT  # back inside the block
    uc.emu_start(cpu.pc | 1, CODE + 10, 100_000, 0)  # movne r3 (runs), moveq r5 (skipped)
    regs = (uc.reg_read(A.UC_ARM_REG_R2), uc.reg_read(A.UC_ARM_REG_R3), uc.reg_read(A.UC_ARM_REG_R5))
    assert regs == (1, 1, 0)
