"""Estimated Cortex-M3 cycles per Thumb-2 instruction, as a prefix sum over the flash image.

The block hook (``cycles.c``) adds, for every executed block, the cycles of the
instructions in it plus 2 for the taken branch that led there. Costs follow the
Cortex-M3 TRM (ARM DDI 0337, table 18-1 "Cortex-M3 instruction set summary"): data
processing 1, single load/store 2, LDM/STM/PUSH/POP 1+N, LDRD/STRD 3, MUL/MLA 1-2,
long multiply 4 (3-5), UDIV/SDIV 7 (2-12, data dependent), taken branch 1+P (P = 1-3
pipeline refill; 2 used). Flash wait states (2 at 72 MHz) are taken as hidden by the
prefetch buffer on straight-line code. Expect the estimate within about ±25 % of the
real chip on this firmware; it is deterministic.
"""

from __future__ import annotations

from itertools import accumulate


def instruction_cost(hw1: int, hw2: int) -> tuple[int, int]:
    """(cycles, length in halfwords) of the instruction whose first halfwords are given."""
    top5 = hw1 >> 11
    if top5 in (0b11101, 0b11110, 0b11111):  # 32-bit
        if hw1 & 0xFE40 == 0xE800 and hw1 & 0x0180 in (0x0080, 0x0100):  # LDM/STM (.W, PUSH.W, POP.W)
            return 1 + bin(hw2 & 0xDFFF).count("1"), 2
        if hw1 & 0xFE40 == 0xE840:  # LDRD/STRD, LDREX/STREX, TBB/TBH
            return 3, 2
        if hw1 >> 9 == 0b1111100:  # single loads and stores
            return 2, 2
        if hw1 & 0xFFF0 in (0xFB90, 0xFBB0):  # SDIV, UDIV
            return 7, 2
        if hw1 & 0xFF80 == 0xFB80:  # long multiplies
            return 4, 2
        if hw1 & 0xFF80 == 0xFB00:  # MUL, MLA, MLS
            return 2 if hw2 & 0xF000 != 0xF000 else 1, 2
        return 1, 2
    if 0b01100 <= top5 <= 0b10011 or top5 == 0b01001 or hw1 >> 12 == 0b0101:  # loads/stores
        return 2, 1
    if hw1 & 0xF600 == 0xB400:  # PUSH/POP
        return 1 + bin(hw1 & 0x1FF).count("1"), 1
    if top5 in (0b11000, 0b11001):  # LDM/STM
        return 1 + bin(hw1 & 0xFF).count("1"), 1
    return 1, 1


def cycle_table(image: bytes) -> list[int]:
    """cum[i] = estimated cycles of the instructions that start before halfword i."""
    n = len(image) // 2
    hws = [image[2 * i] | image[2 * i + 1] << 8 for i in range(n)] + [0]
    cost = [0] * n
    i = 0
    while i < n:
        c, length = instruction_cost(hws[i], hws[i + 1])
        cost[i] = c
        i += length
    return [0, *accumulate(cost)]
