"""The Cortex-M3 core on unicorn, with the M-profile exception model done here.

unicorn executes Thumb-2 (UC_MODE_MCLASS, CPU model Cortex-M3) but has no NVIC: this
module takes exceptions itself, between emulation runs. Entry (ARMv7-M ARM B1.5.6):
push r0-r3, r12, lr, return address and xPSR on the main stack (8-byte aligned, with
xPSR bit 9 recording the padding, CCR.STKALIGN = 1 as on r2p1), LR = EXC_RETURN
(0xFFFFFFF9 from thread mode, 0xFFFFFFF1 when nested), IPSR = exception number,
PC = the vector, the If-Then state cleared (it stays in the stacked xPSR). Return:
unicorn raises its EXCEPTION_EXIT interrupt when a handler branches to an EXC_RETURN
value; the frame is popped here. An exception preempts when
its priority is strictly higher (lower number) than the running one, PRIMASK blocks
all but HardFault, and among the pending ones the lowest priority number, then the
lowest exception number, wins. Only the main stack is used (the firmware never
switches to PSP). Faults that unicorn reports (undefined instruction, unmapped
access) become a HardFault, as they would escalate on the chip with no fault handlers
enabled.
"""

from __future__ import annotations

import struct

from unicorn import UC_HOOK_INTR, UcError
from unicorn import arm_const as A

HARDFAULT = 3
SYSTICK = 15
EXCP_EXCEPTION_EXIT = 8
#: EPSR.IT[1:0] (xPSR bits 26:25) and IT[7:2] (bits 15:10): the If-Then state of the code an
#: exception interrupts, kept in the stacked xPSR and cleared for the handler.
XPSR_IT = 0x0600FC00
_FRAME_REGS = (A.UC_ARM_REG_R0, A.UC_ARM_REG_R1, A.UC_ARM_REG_R2, A.UC_ARM_REG_R3, A.UC_ARM_REG_R12, A.UC_ARM_REG_LR)


class CortexM:
    def __init__(self, uc, read_vector) -> None:
        self.uc = uc
        self.read_vector = read_vector  # exception number -> handler address
        self.active: list[int] = []
        self.exc_exit = False
        self.fault: str | None = None
        self.exceptions_taken = 0
        uc.hook_add(UC_HOOK_INTR, self._on_intr)

    def _on_intr(self, uc, intno: int, user) -> None:
        if intno == EXCP_EXCEPTION_EXIT:
            self.exc_exit = True
        else:
            self.fault = f"cpu exception {intno} at {uc.reg_read(A.UC_ARM_REG_PC):#010x}"
        uc.emu_stop()

    def reset(self) -> None:
        uc = self.uc
        for r in range(A.UC_ARM_REG_R0, A.UC_ARM_REG_R12 + 1):
            uc.reg_write(r, 0)
        uc.reg_write(A.UC_ARM_REG_LR, 0xFFFFFFFF)
        uc.reg_write(A.UC_ARM_REG_PRIMASK, 0)
        uc.reg_write(A.UC_ARM_REG_XPSR, 1 << 24)
        uc.reg_write(A.UC_ARM_REG_SP, self.read_vector(0))
        uc.reg_write(A.UC_ARM_REG_PC, self.read_vector(1) & ~1)
        self.active = []
        self.exc_exit = False
        self.fault = None

    @property
    def pc(self) -> int:
        return self.uc.reg_read(A.UC_ARM_REG_PC)

    def primask(self) -> bool:
        return bool(self.uc.reg_read(A.UC_ARM_REG_PRIMASK) & 1)

    def running_priority(self, prio_of) -> int:
        p = min((prio_of(e) for e in self.active), default=256)
        if self.primask():
            p = min(p, 0)
        return p

    def enter(self, exc: int) -> None:
        uc = self.uc
        sp = uc.reg_read(A.UC_ARM_REG_SP)
        xpsr = uc.reg_read(A.UC_ARM_REG_XPSR) | (1 << 24)
        pad = sp & 4
        sp = (sp - 32 - pad) & 0xFFFFFFFF
        frame = [uc.reg_read(r) for r in _FRAME_REGS] + [self.pc, xpsr | (1 << 9 if pad else 0)]
        uc.mem_write(sp, struct.pack("<8I", *[v & 0xFFFFFFFF for v in frame]))
        uc.reg_write(A.UC_ARM_REG_SP, sp)
        uc.reg_write(A.UC_ARM_REG_LR, 0xFFFFFFF1 if self.active else 0xFFFFFFF9)
        # ExceptionTaken (ARMv7-M ARM B1.5.6): IPSR = the exception, EPSR.IT = 0. An exception
        # taken inside an IT block must not hand the block's remaining conditions to the handler
        # (its first instructions would run conditionally); the return restores them from the frame.
        uc.reg_write(A.UC_ARM_REG_XPSR, (xpsr & ~(0x1FF | XPSR_IT)) | exc)
        uc.reg_write(A.UC_ARM_REG_PC, self.read_vector(exc) & ~1)
        self.active.append(exc)
        self.exceptions_taken += 1

    def exit(self) -> None:
        uc = self.uc
        self.exc_exit = False
        sp = uc.reg_read(A.UC_ARM_REG_SP)
        r0, r1, r2, r3, r12, lr, pc, xpsr = struct.unpack("<8I", bytes(uc.mem_read(sp, 32)))
        sp += 32 + (4 if xpsr & (1 << 9) else 0)
        for reg, v in zip(_FRAME_REGS, (r0, r1, r2, r3, r12, lr)):
            uc.reg_write(reg, v)
        if self.active:
            self.active.pop()
        uc.reg_write(A.UC_ARM_REG_SP, sp)
        uc.reg_write(A.UC_ARM_REG_XPSR, (xpsr & ~(1 << 9)) | (1 << 24))
        uc.reg_write(A.UC_ARM_REG_PC, pc & ~1)

    def run(self) -> None:
        """Run from the current PC until the block hook or a hook stops the emulation."""
        try:
            self.uc.emu_start(self.pc | 1, 0, 0, 0)
        except UcError as e:
            self.fault = f"{e} at {self.pc:#010x}"
