"""The CLI's number parsers: argparse ``type=`` functions for numeric options.

Each takes the option's text and returns the number, or raises ``argparse.ArgumentTypeError``
with one line saying what was expected (argparse prints it after the option's name and exits 2):
``proleg sim R1 --duration 0`` → ``argument --duration: expected a number above 0, got 0``.
"""

from __future__ import annotations

import argparse
import math

from ..protocol.definition import GAIT_USER
from ..typed import typed_float, typed_int


def positive_int(text: str) -> int:
    """A whole number ≥ 1 (``--max-transitions``, ``--cycles``, ``--repeats``...)."""
    v = _int(text, "a whole number")
    if v < 1:
        raise argparse.ArgumentTypeError(f"expected at least 1, got {v}")
    return v


def max_transitions(text: str) -> int:
    """``--max-transitions``: the longest gait, 2 .. ``MAX_GAIT_TRANSITIONS`` (a gait has at least
    two transitions; a longer bound makes the search run for hours)."""
    from ..gait.library import MAX_GAIT_TRANSITIONS

    v = _int(text, "a whole number")
    if not 2 <= v <= MAX_GAIT_TRANSITIONS:
        raise argparse.ArgumentTypeError(f"expected a whole number of transitions in 2..{MAX_GAIT_TRANSITIONS} "
                                         f"(a gait has at least 2), got {v}")
    return v


#: ``gait --cycles``: at most this many passes in the composed path (each pass is one point per
#: transition in the path, the JSON and the plot; 1e9 never finished).
MAX_CYCLES = 10_000


def _at_most(text: str, cap: int, what: str) -> int:
    """A whole number 1 .. ``cap``; ``what``: what it counts, for the refusal."""
    v = positive_int(text)
    if v > cap:
        raise argparse.ArgumentTypeError(f"expected at most {cap:,} {what}, got {v}")
    return v


def cycles(text: str) -> int:
    """``--cycles``: passes in the composed path, 1 .. ``MAX_CYCLES``."""
    return _at_most(text, MAX_CYCLES, "passes")


#: The longest ``proleg sim`` run and ``run --sim`` run flat out (simulated seconds): an hour
#: takes about a minute on host-sim (the emulated boards are slower); 1e12 never finished.
#: ``sim --pty`` and ``run --sim --speed`` are paced in real time, unbounded.
MAX_SIM_S = 3600.0


#: ``check --rows``: at most this many random rows (an hour or more of CPU).
MAX_CHECK_ROWS = 1000


def check_rows(text: str) -> int:
    """``check --rows``: random rows to run, 1 .. ``MAX_CHECK_ROWS``."""
    return _at_most(text, MAX_CHECK_ROWS, "rows")


#: ``learn --repeats``: at most this many trials of each transition, as many as ``--half-width``
#: ever plans (``learn.estimate.extra_trials``' limit): a robot's trial takes a second or more,
#: so more is days a transition; 999999999 was taken and its header said 11999999988 trials.
MAX_REPEATS = 100_000


def repeats(text: str) -> int:
    """``learn --repeats``: trials per transition, 1 .. ``MAX_REPEATS``."""
    return _at_most(text, MAX_REPEATS, "trials per transition")


#: ``check --jobs`` and ``sim --jobs``: at most this many worker processes. Each is a whole
#: simulated robot (a Python process with its plant and firmware, 100-200 MB): 1000 of them
#: exhausted a lab machine's memory long before any row ran.
MAX_JOBS = 64


def worker_jobs(text: str) -> int:
    """``--jobs``: worker processes, 1 .. ``MAX_JOBS``."""
    return _at_most(text, MAX_JOBS, "worker processes")


def gait_index(text: str) -> int:
    """A gait table index ≥ 0, or ``user`` for the LOAD_GAIT sequence (``GAIT_USER``)."""
    if text.strip().lower() == "user":
        return GAIT_USER
    v = _int(text, "a gait index or 'user'")
    if v < 0:
        raise argparse.ArgumentTypeError(f"expected a gait index ≥ 0, got {v}")
    return v


def param_index(text: str) -> int:
    """``set-param --index``: 0..255 (SET_PARAM's index is one byte)."""
    return _int_in(text, 0, 255, "an index")


def gait_number(text: str) -> int:
    """A gait table index ≥ 0 (``sim --gait``: the built-in gaits, no user gait)."""
    v = _int(text, "a gait index")
    if v < 0:
        raise argparse.ArgumentTypeError(f"expected a gait index ≥ 0, got {v}")
    return v


def int_auto(text: str) -> int:
    """An integer in any base Python reads (``16``, ``0x10``, ``0o20``): CAN node ids and ids."""
    try:
        return typed_int(text, 0)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer (0x.. for hex), got {text!r}") from None


def baudrate(text: str) -> int:
    """``--baudrate``: a serial baud rate, 1 .. ``MAX_BAUDRATE`` (12 Mbaud)."""
    from ..link.serial_link import MAX_BAUDRATE

    return _int_in(text, 1, MAX_BAUDRATE, "a baud rate")


def can_bitrate(text: str) -> int:
    """``--bitrate``: a CAN bit rate, 1 .. 1,000,000 bit/s (classic CAN)."""
    return _int_in(text, 1, 1_000_000, "a CAN bit rate in bit/s")


def can_node(text: str) -> int:
    """``--node``: a CAN node id, 0 .. 15 (any base Python reads: ``0x0f``)."""
    from ..protocol.can import MAX_NODE

    v = int_auto(text)
    if not 0 <= v <= MAX_NODE:
        raise argparse.ArgumentTypeError(f"expected a CAN node id in 0..{MAX_NODE}, got {text}")
    return v


def finite_float(text: str) -> float:
    """Any finite number (not ``nan``/``inf``)."""
    v = _float(text, "a number")
    if not math.isfinite(v):
        raise argparse.ArgumentTypeError(f"expected a finite number, got {text!r}")
    return v


def tracker_offset(text: str) -> float:
    """``learn --tracker-offset``: tracker time − firmware time, in seconds within ±1e9 (the
    bound of a track's own times, ``proleg.learn.tracker.MAX_ABS``)."""
    v = _float(text, "seconds")
    if not abs(v) <= 1e9:
        raise argparse.ArgumentTypeError(f"expected seconds within ±1e9 (the track's times), got {text!r}")
    return v


def non_negative_float(text: str) -> float:
    """A finite number ≥ 0."""
    v = finite_float(text)
    if v < 0:
        raise argparse.ArgumentTypeError(f"expected a number >= 0, got {text!r}")
    return v


def positive_float(text: str) -> float:
    """A finite number > 0 (durations, periods, speed factors): ``inf`` would run for ever."""
    v = _float(text, "a number")
    if not (v > 0 and math.isfinite(v)):
        raise argparse.ArgumentTypeError(f"expected a finite number above 0, got {text}")
    return v


def speed_factor(text: str) -> float:
    """``--speed``: times real time, at least ``link.sim_link.MIN_SPEED`` (finite: as fast as
    the host can goes past any pace there is)."""
    from ..link.sim_link import MIN_SPEED

    v = positive_float(text)
    if v < MIN_SPEED:
        raise argparse.ArgumentTypeError(f"expected at least {MIN_SPEED:g} times real time (a simulated second in "
                                         f"{1 / MIN_SPEED / 60:.0f} minutes), got {text}")
    return v


#: The shortest ``run --progress`` period: a line per tenth of a second of the run at most (a
#: shorter period printed the same line once per pass of the receive loop: 10,002 lines for
#: ``--progress 0.00001 --duration 0.1``).
MIN_PROGRESS_S = 0.1


def _seconds_from(text: str, least: float, expected: str) -> float:
    """A finite number of seconds of at least ``least``; below it ``expected at least … s
    <expected>, got …``."""
    v = positive_float(text)
    if v < least:
        raise argparse.ArgumentTypeError(f"expected at least {least:g} s {expected}, got {text}")
    return v


def progress_period(text: str) -> float:
    """``run --progress``: seconds between progress lines, at least ``MIN_PROGRESS_S``."""
    return _seconds_from(text, MIN_PROGRESS_S, "between progress lines")


#: The shortest reply timeout the CLI takes: a reply frame takes a few ms at 115200 baud
#: (the simulated board answers within a tick or two), so a shorter one could never succeed.
MIN_REPLY_TIMEOUT_S = 0.01


#: The longest: a board that has not answered in a minute will not (it reset, or its link is
#: gone); 1e9 was taken, and a board that stopped answering kept the command waiting 31 years.
MAX_REPLY_TIMEOUT_S = 60.0


def reply_timeout(text: str) -> float:
    """``--timeout``: seconds to wait for a command's reply, ``MIN_REPLY_TIMEOUT_S`` ..
    ``MAX_REPLY_TIMEOUT_S``."""
    v = _seconds_from(text, MIN_REPLY_TIMEOUT_S, "(a reply takes a few ms)")
    if v > MAX_REPLY_TIMEOUT_S:
        raise argparse.ArgumentTypeError(f"expected at most {MAX_REPLY_TIMEOUT_S:g} s (a reply takes a few ms; a board "
                                         f"silent for a minute will not answer), got {text}")
    return v


def heading_deg(text: str) -> float:
    """A heading in degrees within ±``proleg.gait.library.MAX_HEADING_DEG`` (0 = +x, 90 = +y),
    as ``--library`` takes them."""
    from ..gait.library import MAX_HEADING_DEG  # here: the gait engine is not loaded for every command

    v = _float(text, "a heading in degrees")
    if not math.isfinite(v) or abs(v) > MAX_HEADING_DEG:
        raise argparse.ArgumentTypeError(f"expected a heading in degrees within ±{MAX_HEADING_DEG:g}, got {text}")
    return v


def _float(text: str, expected: str) -> float:
    try:
        return typed_float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected {expected}, got {text!r}") from None


def _int_in(text: str, lo: int, hi: int, what: str) -> int:
    v = _int(text, f"{what} (a whole number)")
    if not lo <= v <= hi:
        raise argparse.ArgumentTypeError(f"expected {what} in {lo:,}..{hi:,}, got {text}")
    return v


def param_value(text: str) -> int:
    """``set-param``'s VALUE: a whole number of either sign (ψ* may be negative) that SET_PARAM's
    32-bit field carries. A larger one was refused after the port was opened (a Nano resets
    then), in the codec's words: "SET_PARAM.value: 99999999999 outside -2147483648..2147483647"."""
    v = _int(text, "a whole number")
    if not -2**31 <= v < 2**31:
        raise argparse.ArgumentTypeError(f"expected a whole number in -2,147,483,648..2,147,483,647 (SET_PARAM's "
                                         f"32-bit value; each parameter's range: docs/control.md), got {v}")
    return v


def _int(text: str, expected: str) -> int:
    try:
        return typed_int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected {expected}, got {text!r}") from None
