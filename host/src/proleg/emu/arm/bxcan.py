"""bxCAN (RM0008 rev 21, chapter 24) on one bus shared with the host, enough for the
firmware's CAN link (hal/stm32f1/can_stm32f1.c) and for tests of the controller itself.

Modelled:
- modes (§24.4): reset leaves the controller asleep (MCR = 0x00010002, MSR SLAK);
  INRQ enters initialisation at once (INAK: the bus is idle between frames); clearing
  INRQ leaves it after 11 recessive bit times (the controller synchronises on the bus,
  §24.4.2); BTR is writable only in initialisation (§24.9.2);
- bit timing (§24.7.7): a bit is BRP × (1 + TS1 + TS2) PCLK1 periods; a frame takes
  ``FRAME_BITS`` bits (an 8-byte data frame with typical bit stuffing and the
  interframe space);
- transmit (§24.7.1): three mailboxes (TIxR, TDTxR, TDLxR, TDHxR); TXRQ queues a
  mailbox; the next one on the bus is the oldest request with TXFP, else the lowest
  identifier (lowest mailbox on a tie); completion sets RQCPx and TXOKx and frees the
  mailbox (TMEx); TSR.CODE names the lowest free mailbox; ABRQx aborts a queued one;
  RQCPx are write-1-to-clear and take TXOK/ALST/TERR with them. The host acknowledges
  every frame (no error states);
- receive (§24.7.4, §24.7.5): a frame from the host passes the filter banks (FINIT
  set: no reception; active banks in 32- or 16-bit, mask or list mode; bank assigned
  to FIFO 1 (FFA1R): the frame is taken but FIFO 1 is not modelled); FIFO 0 holds three
  messages (FMP0, FULL0); a fourth with RFLM clear overwrites the last and sets FOVR0;
  RFOM0 releases the output mailbox (RI0R...RDH0R show the oldest);
- one frame at a time on the bus; when the host and the controller both have a frame
  waiting, the lower identifier wins arbitration;
- interrupts (§24.8): TX = TMEIE·(RQCP0|RQCP1|RQCP2); RX0 = FMPIE0·(FMP0≠0) |
  FFIE0·FULL0 | FOVIE0·FOVR0.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable

from .clocks import CPU_HZ, NEVER

TX_IRQ, RX0_IRQ = 19, 20  # USB_HP_CAN_TX, USB_LP_CAN_RX0 (RM0008 Table 63)
FRAME_BITS = 125  # 111 bits of an 8-byte standard frame with its interframe space, + typical stuffing
JOIN_BITS = 11

MCR_INRQ, MCR_SLEEP, MCR_TXFP, MCR_RFLM = 1 << 0, 1 << 1, 1 << 2, 1 << 3
MSR_INAK, MSR_SLAK = 1 << 0, 1 << 1
RF_FULL, RF_FOVR, RF_RFOM = 1 << 3, 1 << 4, 1 << 5
IER_TMEIE, IER_FMPIE0, IER_FFIE0, IER_FOVIE0 = 1 << 0, 1 << 1, 1 << 2, 1 << 3
TIR_TXRQ, IR_RTR, IR_IDE = 1 << 0, 1 << 1, 1 << 2
FMR_FINIT = 1 << 0
N_BANKS = 14  # STM32F103 (not a connectivity line device)


def _rqcp(m: int) -> int:
    return 1 << (8 * m)


def _txok(m: int) -> int:
    return 1 << (8 * m + 1)


def _tme(m: int) -> int:
    return 1 << (26 + m)


class BxCan:
    BASE = 0x40006400

    def __init__(self, pclk1: Callable[[], int]):
        self.pclk1 = pclk1
        self.host_rx: deque[tuple[int, bytes]] = deque()  # frames the host puts on the bus, not yet sent
        self.host_tx: list[tuple[int, bytes]] = []  # frames the controller sent, acknowledged by the host
        self.reset()

    # -- state --------------------------------------------------------------------------
    def reset(self) -> None:
        self.mcr = 0x00010002
        self.msr = 0x00000C02
        self.tsr_flags = 0  # RQCPx, TXOKx, ALSTx, TERRx
        self.ier = 0
        self.btr = 0x01230000
        self.mail = [[0, 0, 0, 0] for _ in range(3)]  # TIR, TDTR, TDLR, TDHR
        self.pending: list[tuple[int, int]] = []  # (request order, mailbox)
        self._order = 0
        self.fifo0: deque[tuple[int, int, int, int]] = deque()  # RIR, RDTR, RDLR, RDHR
        self.fifo1_taken = 0
        self.rf0_flags = 0  # FULL0, FOVR0
        self.fmr = 0x2A1C0E01
        self.fm1r = self.fs1r = self.ffa1r = self.fa1r = 0
        self.fr = [[0, 0] for _ in range(N_BANKS)]
        self.join_at = NEVER
        self.on_bus = False
        self.bus_until = NEVER
        self.on_wire: tuple[str, object] | None = None  # ("tx", mailbox) or ("rx", (id, data))
        self.dropped_by_filter = 0

    # -- timing -------------------------------------------------------------------------
    def bit_cycles(self) -> int:
        brp = (self.btr & 0x3FF) + 1
        quanta = 1 + ((self.btr >> 16) & 0xF) + 1 + ((self.btr >> 20) & 0x7) + 1
        return max(1, CPU_HZ * brp * quanta // max(1, self.pclk1()))

    @property
    def bitrate(self) -> float:
        return CPU_HZ / self.bit_cycles()

    def next_event(self) -> int:
        return min(self.join_at, self.bus_until)

    # -- the bus ------------------------------------------------------------------------
    def _next_tx(self) -> int | None:
        if not self.pending:
            return None
        if self.mcr & MCR_TXFP:
            return min(self.pending)[1]
        return min(self.pending, key=lambda p: ((self.mail[p[1]][0] >> 21) & 0x7FF, p[1]))[1]

    def _start(self, now: int) -> None:
        """Put the next frame on an idle bus (arbitration: the lower identifier)."""
        if not self.on_bus or self.on_wire is not None:
            return
        mb = self._next_tx()
        mine = (self.mail[mb][0] >> 21) & 0x7FF if mb is not None else None
        theirs = self.host_rx[0][0] if self.host_rx else None
        if mine is None and theirs is None:
            return
        if theirs is None or (mine is not None and mine < theirs):
            self.pending = [p for p in self.pending if p[1] != mb]
            self.on_wire = ("tx", mb)
        else:
            self.on_wire = ("rx", self.host_rx.popleft())
        self.bus_until = now + FRAME_BITS * self.bit_cycles()

    def kick(self, now: int) -> None:
        self._start(now)

    def advance(self, now: int) -> None:
        while self.next_event() <= now:
            if self.join_at <= self.bus_until:
                t = self.join_at
                self.join_at = NEVER
                self.msr &= ~MSR_INAK
                self.on_bus = True
            else:
                t = self.bus_until
                self.bus_until = NEVER
                kind, what = self.on_wire  # type: ignore[misc]
                self.on_wire = None
                if kind == "tx":
                    self._sent(int(what))  # type: ignore[arg-type]
                else:
                    self._received(*what)  # type: ignore[misc]
            self._start(t)
        self._start(now)

    def _sent(self, mb: int) -> None:
        tir, tdtr, tdlr, tdhr = self.mail[mb]
        dlc = min(8, tdtr & 0xF)
        data = (tdlr | tdhr << 32).to_bytes(8, "little")[:dlc]
        if not tir & IR_IDE:
            self.host_tx.append(((tir >> 21) & 0x7FF, data))
        self.mail[mb][0] &= ~TIR_TXRQ
        self.tsr_flags |= _rqcp(mb) | _txok(mb)

    def _received(self, arbitration_id: int, data: bytes) -> None:
        rir = (arbitration_id & 0x7FF) << 21
        fifo = self._accept(rir)
        if fifo is None:
            self.dropped_by_filter += 1
            return
        if fifo == 1:
            self.fifo1_taken += 1
            return
        d = bytes(data[:8]).ljust(8, b"\0")
        entry = (rir, min(8, len(data)) | fifo << 8, int.from_bytes(d[:4], "little"), int.from_bytes(d[4:], "little"))
        if len(self.fifo0) < 3:
            self.fifo0.append(entry)
        else:
            self.rf0_flags |= RF_FOVR
            if not self.mcr & MCR_RFLM:
                self.fifo0[-1] = entry
        if len(self.fifo0) == 3:
            self.rf0_flags |= RF_FULL

    # -- filters (§24.7.4) ---------------------------------------------------------------
    def _accept(self, rir: int) -> int | None:
        """The FIFO an incoming frame goes to (0 or 1), None when no active bank passes it."""
        if self.fmr & FMR_FINIT:
            return None
        std = (rir >> 21) & 0x7FF
        rir16 = std << 5 | (rir & IR_RTR) << 3 | (rir & IR_IDE) << 1
        for bank in range(N_BANKS):
            bit = 1 << bank
            if not self.fa1r & bit:
                continue
            r1, r2 = self.fr[bank]
            if self.fs1r & bit:  # one 32-bit filter
                ok = (rir in (r1 & ~1, r2 & ~1)) if self.fm1r & bit else (rir & ~1 ^ r1) & r2 & ~1 == 0
            elif self.fm1r & bit:  # four 16-bit identifiers
                ok = rir16 in (r1 & 0xFFFF, r1 >> 16, r2 & 0xFFFF, r2 >> 16)
            else:  # two 16-bit id/mask pairs
                ok = any((rir16 ^ r) & (r >> 16) & 0xFFFF == 0 for r in (r1, r2))
            if ok:
                return 1 if self.ffa1r & bit else 0
        return None

    # -- interrupts ------------------------------------------------------------------
    def irqs(self) -> list[int]:
        out = []
        if self.ier & IER_TMEIE and self.tsr_flags & (_rqcp(0) | _rqcp(1) | _rqcp(2)):
            out.append(TX_IRQ)
        rf = self.rf0r
        if (self.ier & IER_FMPIE0 and rf & 3) or (self.ier & IER_FFIE0 and rf & RF_FULL) or (
                self.ier & IER_FOVIE0 and rf & RF_FOVR):
            out.append(RX0_IRQ)
        return out

    # -- registers --------------------------------------------------------------------
    @property
    def tsr(self) -> int:
        free = [m for m in range(3) if not self.mail[m][0] & TIR_TXRQ]
        v = self.tsr_flags
        for m in free:
            v |= _tme(m)
        return v | (free[0] if free else 0) << 24

    @property
    def rf0r(self) -> int:
        return len(self.fifo0) | self.rf0_flags

    def read(self, off: int, now: int) -> int:
        if off == 0x00:
            return self.mcr
        if off == 0x04:
            return self.msr
        if off == 0x08:
            return self.tsr
        if off == 0x0C:
            return self.rf0r
        if off == 0x14:
            return self.ier
        if off == 0x1C:
            return self.btr
        if 0x180 <= off < 0x1B0:
            return self.mail[(off - 0x180) >> 4][(off >> 2) & 3]
        if 0x1B0 <= off < 0x1C0:
            return self.fifo0[0][(off >> 2) & 3] if self.fifo0 else 0
        regs = {0x200: self.fmr, 0x204: self.fm1r, 0x20C: self.fs1r, 0x214: self.ffa1r, 0x21C: self.fa1r}
        if off in regs:
            return regs[off]
        if 0x240 <= off < 0x240 + 8 * N_BANKS:
            return self.fr[(off - 0x240) >> 3][(off >> 2) & 1]
        return 0

    def write(self, off: int, value: int, now: int) -> None:
        if off == 0x00:
            self._mcr(value, now)
        elif off == 0x08:
            self._tsr(value)
        elif off == 0x0C:
            if value & RF_RFOM and self.fifo0:
                self.fifo0.popleft()
                self.rf0_flags &= ~RF_FULL
            self.rf0_flags &= ~(value & (RF_FULL | RF_FOVR))
        elif off == 0x14:
            self.ier = value
        elif off == 0x1C:
            if self.msr & MSR_INAK:
                self.btr = value & 0xC37F03FF
        elif 0x180 <= off < 0x1B0:
            self._mailbox((off - 0x180) >> 4, (off >> 2) & 3, value)
        elif off == 0x200:
            self.fmr = (self.fmr & ~FMR_FINIT) | (value & FMR_FINIT)
        elif off in (0x204, 0x20C, 0x214, 0x21C):
            mask = (1 << N_BANKS) - 1
            if off == 0x21C:
                self.fa1r = value & mask
            elif self.fmr & FMR_FINIT:  # mode, scale and FIFO assignment only in filter initialisation
                setattr(self, {0x204: "fm1r", 0x20C: "fs1r", 0x214: "ffa1r"}[off], value & mask)
        elif 0x240 <= off < 0x240 + 8 * N_BANKS:
            bank = (off - 0x240) >> 3
            if self.fmr & FMR_FINIT or not self.fa1r >> bank & 1:  # §24.9.5: inactive bank or FINIT
                self.fr[bank][(off >> 2) & 1] = value
        self._start(now)

    def _mcr(self, value: int, now: int) -> None:
        self.mcr = value & 0x000180FF
        if value & MCR_INRQ:
            self.msr = (self.msr | MSR_INAK) & ~MSR_SLAK
            self.on_bus = False
            self.join_at = NEVER
            self.pending.clear()  # entering initialisation aborts what was queued
            for m in range(3):
                self.mail[m][0] &= ~TIR_TXRQ
        elif value & MCR_SLEEP:
            self.msr = (self.msr | MSR_SLAK) & ~MSR_INAK
            self.on_bus = False
        else:
            self.msr &= ~MSR_SLAK  # INAK stays until the controller has synchronised on the bus
            if not self.on_bus and self.join_at == NEVER:
                self.join_at = now + JOIN_BITS * self.bit_cycles()

    def _tsr(self, value: int) -> None:
        for m in range(3):
            if value & _rqcp(m):
                self.tsr_flags &= ~(0xF << (8 * m))  # RQCP, TXOK, ALST, TERR
            if value & (1 << (8 * m + 7)) and self.mail[m][0] & TIR_TXRQ and self.on_wire != ("tx", m):
                self.mail[m][0] &= ~TIR_TXRQ  # ABRQ: aborted before it reached the bus
                self.pending = [p for p in self.pending if p[1] != m]
                self.tsr_flags |= _rqcp(m)

    def _mailbox(self, m: int, reg: int, value: int) -> None:
        if self.mail[m][0] & TIR_TXRQ:
            return  # a queued mailbox is write-protected (§24.7.1)
        self.mail[m][reg] = value
        if reg == 0 and value & TIR_TXRQ:
            self._order += 1
            self.pending.append((self._order, m))
