"""Scoring a closed walk: canonical rotation, primitivity, and user-typed sequences."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from ..errors import GaitError
from ..transitions import TransitionTable
from .result import Gait


def canonical_rotation(cycle: Sequence[int]) -> tuple[int, ...]:
    """Rotate an open cycle (s0 .. s(N-1), without the repeated start) to its canonical start.

    Among the rotations that start at the lowest state index, the lexicographically smallest.
    """
    cyc = tuple(cycle)
    low = min(cyc)
    return min(cyc[i:] + cyc[:i] for i, s in enumerate(cyc) if s == low)


def is_primitive(cycle: Sequence[int]) -> bool:
    """False when the open cycle is u^k (k >= 2) for a shorter u."""
    cyc = tuple(cycle)
    n = len(cyc)
    for p in range(1, n // 2 + 1):
        if n % p == 0 and cyc == cyc[p:] + cyc[:p]:
            return False
    return True


def edge_positions(table: TransitionTable, states: Sequence[int]) -> np.ndarray:
    """Edge positions of consecutive transitions (int64; -1 where forbidden or a == b)."""
    a = np.asarray(states[:-1], dtype=np.int64)
    b = np.asarray(states[1:], dtype=np.int64)
    n = table.n_states
    keys = table.src * n + table.dst
    want = a * n + b
    pos = np.searchsorted(keys, want)
    pos_c = np.minimum(pos, max(len(keys) - 1, 0))
    ok = (pos < len(keys)) & (keys[pos_c] == want) if len(keys) else np.zeros(len(want), bool)
    return np.where(ok, pos_c, -1)


def make_gait(table: TransitionTable, closed: Sequence[int]) -> Gait:
    """The Gait of a valid closed walk (states[0] == states[-1]); no validation."""
    pos = edge_positions(table, closed)
    reward = math.fsum(table.reward[pos].tolist())
    duration = None if table.duration is None else math.fsum(table.duration[pos].tolist())
    cyc = canonical_rotation(closed[:-1])
    n = len(cyc)
    return Gait(states=cyc + (cyc[0],), reward=reward, transitions=n, rate=reward / n, duration=duration)


def evaluate_sequence(table: TransitionTable, states: Sequence[int | str]) -> Gait:
    """Score a closed walk a user typed: J, N, J/N and, when known, its duration.

    ``states`` are state indices or labels ("10"), closed: the last equals the first. The
    result is rotated to the canonical start. A walk that repeats a shorter one is scored
    as typed (it is simply not listed by ``optimal_gaits``). Raises GaitError naming the
    first problem: a too-short sequence, an unknown state, a sequence that does not return
    to its start, or the first transition that is forbidden or does not change state.
    """
    seq = list(states)
    if len(seq) < 3:
        raise GaitError(
            f"a gait needs at least 2 transitions (3 states, the last equal to the first), got {len(seq)} state(s)"
        )
    n = table.n_states
    idx: list[int] = []
    for k, s in enumerate(seq):
        if isinstance(s, str):
            try:
                idx.append(table.index(s))
            except ValueError as exc:
                raise GaitError(f"state {k + 1} of the sequence: {exc}") from None
        else:
            try:
                i = int(s)  # accepts numpy integers
            except (TypeError, ValueError):
                raise GaitError(f"state {k + 1} of the sequence: {s!r} is not a state index or label") from None
            if i != s or not 0 <= i < n:
                raise GaitError(f"state {k + 1} of the sequence: {s!r} is not a state index 0..{n - 1}")
            idx.append(i)
    if idx[0] != idx[-1]:
        raise GaitError(
            f"sequence must return to its start: it starts at {table.label(idx[0])} and ends at {table.label(idx[-1])}"
        )
    pos = edge_positions(table, idx)
    for k in range(len(idx) - 1):
        a, b = table.label(idx[k]), table.label(idx[k + 1])
        if idx[k] == idx[k + 1]:
            raise GaitError(f"transition {a} -> {b} does not change state, so it is not a transition (step {k + 1})")
        if pos[k] < 0:
            raise GaitError(f"transition {a} -> {b} is forbidden (step {k + 1} of the sequence)")
    return make_gait(table, idx)
