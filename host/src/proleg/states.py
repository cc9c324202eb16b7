"""Robot state labels and indices.

A robot state is the tuple of limb states (S_1 ... S_N), written as a label with the
first limb leftmost. Its index is the label read as a mixed-radix number, first limb
most significant, so for two binary limbs "00"=0, "01"=1, "10"=2, "11"=3 (SPEC §1).
"""

from __future__ import annotations

from collections.abc import Sequence
from functools import lru_cache
from math import prod

from .names import counted

DIGITS = "0123456789abcdefghijklmnopqrstuvwxyz"


def state_count(levels: Sequence[int]) -> int:
    return prod(levels)


def label(index: int, levels: Sequence[int]) -> str:
    """The label of state ``index``: one digit per limb, first limb leftmost."""
    return _label(index, tuple(levels))


@lru_cache(maxsize=1 << 16)
def _label(index: int, levels: tuple[int, ...]) -> str:
    """``label``, remembered: gait reports name the same few hundred states millions of times."""
    if not 0 <= index < state_count(levels):
        raise ValueError(f"state index {index} out of range 0..{state_count(levels) - 1}")
    digits = []
    for k in reversed(levels):
        index, d = divmod(index, k)
        digits.append(DIGITS[d])
    return "".join(reversed(digits))


def index(text: str, levels: Sequence[int], names: Sequence[str] = ()) -> int:
    """The index of the state written as ``text``; ValueError says what is wrong (naming the
    limb by ``names``, the robot file's, where given; else by its place, ``limb #2``)."""
    if any(ch.lower() not in DIGITS for ch in text):
        example = "".join(DIGITS[i % 2] for i in range(len(levels)))
        what = f"one digit per limb, {counted(len(levels), 'digit')} (e.g. {example})"
        if any(ch.lower() in DIGITS for ch in text) and any(ch.isspace() or ch in ";|/" for ch in text):
            # "000 100 110": several states in one item ("has 11 digits" named neither)
            raise ValueError(f"{text!r} is not one state label: separate the states with commas ({what} each)")
        raise ValueError(f"{text!r} is not a state label: {what}")
    if len(text) != len(levels):
        raise ValueError(f"state label {text!r} has {counted(len(text), 'digit')}, expected {len(levels)} (one per limb)")
    value = 0
    for i, (ch, k) in enumerate(zip(text, levels)):
        d = DIGITS.find(ch.lower())
        if not 0 <= d < k:  # on a robot of mixed levels the digit's place says which limb's range
            limb = f"limb {names[i]!r}" if i < len(names) else f"limb #{i + 1}"
            raise ValueError(f"state label {text!r}: digit {i + 1} ({ch!r}) is not a level of {limb}, 0..{k - 1}")
        value = value * k + d
    return value


def limb_levels(index_: int, levels: Sequence[int]) -> tuple[int, ...]:
    """The per-limb levels (S_1 ... S_N) of a state index."""
    return _limb_levels(index_, tuple(levels))


@lru_cache(maxsize=1 << 16)
def _limb_levels(index_: int, levels: tuple[int, ...]) -> tuple[int, ...]:
    out = []
    for k in reversed(levels):
        index_, d = divmod(index_, k)
        out.append(d)
    return tuple(reversed(out))


def place_values(levels: Sequence[int]) -> tuple[int, ...]:
    """Each limb's place value in a state index: the product of the levels of the limbs after it
    (two binary limbs: (2, 1))."""
    out, m = [], 1
    for k in reversed(levels):
        out.append(m)
        m *= k
    return tuple(reversed(out))


def classify(psi: Sequence[float], thresholds: Sequence[Sequence[float]], places: Sequence[int]) -> int:
    """The state index of limbs at contact angles ``psi``: a limb's level is how many of its
    ascending thresholds (ψ*) its ψ has reached; ``places`` from ``place_values``."""
    idx = 0
    for p, ths, m in zip(psi, thresholds, places):
        lvl = 0
        for th in ths:
            if p >= th:
                lvl += 1
        idx += lvl * m
    return idx


def opposing_steps(states: Sequence[int], levels: Sequence[int]) -> list[int]:
    """Indices t of the steps states[t] → states[t+1] that raise one limb while lowering
    another.

    An SMA robot heats to raise a limb and cools to lower one, and the two take different
    times, so such a step is hard to make as one transition: the controller synchronises
    the crossings as well as it can, but a robot may pass through an intermediate state."""
    out = []
    for t, (a, b) in enumerate(zip(states, states[1:])):
        la, lb = limb_levels(a, levels), limb_levels(b, levels)
        if any(y > x for x, y in zip(la, lb)) and any(y < x for x, y in zip(la, lb)):
            out.append(t)
    return out
