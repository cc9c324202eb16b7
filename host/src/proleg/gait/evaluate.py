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


def edge_positions(table: TransitionTable, states: Sequence[int], keys: np.ndarray | None = None) -> np.ndarray:
    """Edge positions of consecutive transitions (int64; -1 where forbidden or a == b).

    ``keys`` (src·n + dst, sorted) may be passed in when many walks are looked up."""
    n = table.n_states
    if keys is None:
        keys = table.src * n + table.dst
    a = np.asarray(states[:-1], dtype=np.int64)
    b = np.asarray(states[1:], dtype=np.int64)
    want = a * n + b
    if len(keys) == 0:
        return np.full(len(want), -1, dtype=np.int64)
    pos = np.minimum(np.searchsorted(keys, want), len(keys) - 1)
    return np.where(keys[pos] == want, pos, -1)


def make_gaits(table: TransitionTable, cycles: Sequence[Sequence[int]]) -> list[Gait]:
    """Gaits of valid open cycles (start not repeated); no validation, one batched lookup."""
    if not cycles:
        return []
    n = table.n_states
    keys = table.src * n + table.dst
    flat_a = np.fromiter((s for c in cycles for s in c), dtype=np.int64)
    flat_b = np.fromiter((s for c in cycles for s in (*c[1:], c[0])), dtype=np.int64)
    pos = np.searchsorted(keys, flat_a * n + flat_b).tolist()
    rewards = table.reward.tolist() if len(cycles) * 8 > len(keys) else None
    out = []
    k = 0
    for c in cycles:
        p = pos[k:k + len(c)]
        k += len(c)
        r = [rewards[i] for i in p] if rewards is not None else table.reward[p].tolist()
        reward = math.fsum(r)
        duration = None if table.duration is None else math.fsum(table.duration[p].tolist())
        cyc = canonical_rotation(c)
        out.append(Gait(states=cyc + (cyc[0],), reward=reward, transitions=len(c), rate=reward / len(c), duration=duration))
    return out


def make_gait(table: TransitionTable, closed: Sequence[int]) -> Gait:
    """The Gait of a valid closed walk (states[0] == states[-1]); no validation."""
    return make_gaits(table, [tuple(closed[:-1])])[0]


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
