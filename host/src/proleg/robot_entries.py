"""The values a robot file's ``[transitions]`` holds, read the same way inline and in a CSV:
a state named by its label or ``@index``, finite numbers within their bounds, and those
bounds (``MAX_ENTRY``, ``MAX_DURATION_S``...). Errors are ``RobotFileError``s naming where."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

from . import states
from .errors import RobotFileError

#: The mark of a forbidden transition in a matrix ("x").
FORBIDDEN = "x"
#: The largest |entry| of the matrix, a CSV reward and the planar means, as ``[plant] true_matrix``:
#: a gait sums its entries, and 1e308 would overflow to inf and turn the gait search's answer.
MAX_ENTRY = 1e9
#: The largest planar variance (σ up to MAX_ENTRY) and the largest ``n_trials`` entry.
MAX_VARIANCE = MAX_ENTRY**2
MAX_TRIALS = 10**9
#: The longest duration of a transition (s), in ``durations_s``, a CSV's ``duration_s`` and
#: ``default_duration_s`` alike: a gait sums them, and 1e308 overflowed the sum (a traceback).
MAX_DURATION_S = 3600.0
#: The shortest (s), a microsecond (the fastest control tick is 100 µs): the speed objective divides
#: rewards by durations, and 1e9 in 1e-300 s is past float64 (numpy's overflow warnings, and
#: "no gait moves the robot" for a gait that plainly did). Within these bounds |J / T| ≤ 1e15.
MIN_DURATION_S = 1e-6
DURATION_RANGE = f"[{MIN_DURATION_S:g}, {MAX_DURATION_S:g}]"


def is_duration(v: Any) -> bool:
    """A transition's duration in seconds within [MIN_DURATION_S, MAX_DURATION_S]."""
    return is_number(v) and MIN_DURATION_S <= v <= MAX_DURATION_S


def state_ref(text: str, levels: tuple[int, ...], n: int, where: str, names: Sequence[str] = ()) -> int:
    """A state in a CSV row or a forbidden mark: a label (one digit per limb), or an index
    written ``@N``. A string of digits of another length is an error, never an index: a label
    with a digit missing or one too many would otherwise name a different state."""
    L = len(levels)
    expected = f"{where}: expected a state label of {L} digits or a state index @0..@{n - 1}, got {text!r}"
    if text.startswith("@"):
        index = text[1:]
        if index.isascii() and index.isdigit() and int(index) < n:  # "¹" and "١" are digits too
            return int(index)
        raise RobotFileError(expected)
    if len(text) == L:
        try:
            return states.index(text, levels, names)
        except ValueError as e:
            raise RobotFileError(f"{expected} ({e})") from None
    if text.isascii() and text.isdigit():
        raise RobotFileError(f"{where}: {text!r} is not a state label of {L} digits (one per limb, e.g. "
                             f"{states.label(0, levels)}; a state index is written @0..@{n - 1})")
    raise RobotFileError(expected)


def is_number(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def in_range(v: Any, lo: float, hi: float) -> bool:
    return is_number(v) and lo <= v <= hi
