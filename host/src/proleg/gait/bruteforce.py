"""Brute-force oracle for tiny tables: list every closed walk, score it, keep the best.

Deliberately naive and independent of the engine's algorithms (no pruning, no cycle
theory, only the definitions in SPEC §1–2), so tests can check the engine against it and
the benchmark can show how quickly it stops being an option. Exponential: keep n·K small.
"""

from __future__ import annotations

import itertools
import math

import numpy as np

from ..transitions import TransitionTable
from .result import RELATIVE_TOLERANCE, reward_scale, speed_scale


def _canonical(cycle: tuple[int, ...]) -> tuple[int, ...]:
    rotations = [cycle[i:] + cycle[:i] for i in range(len(cycle))]
    return min(r for r in rotations if r[0] == min(cycle))


def _primitive(cycle: tuple[int, ...]) -> bool:
    return all(cycle[i:] + cycle[:i] != cycle for i in range(1, len(cycle)))


def closed_walks(table: TransitionTable, max_transitions: int, simple: bool) -> list[tuple[int, ...]]:
    """Every primitive closed walk (or simple cycle) of 2..max_transitions transitions, once,
    as an open tuple in canonical rotation."""
    _, allowed = table.dense()
    n = table.n_states
    found: set[tuple[int, ...]] = set()
    if simple:
        for length in range(2, min(max_transitions, n) + 1):
            for perm in itertools.permutations(range(n), length):
                if perm[0] == min(perm) and all(allowed[perm[i], perm[(i + 1) % length]] for i in range(length)):
                    found.add(perm)
        return sorted(found)
    prefixes = [(s,) for s in range(n)]
    for length in range(1, max_transitions + 1):
        for p in prefixes:
            if length >= 2 and allowed[p[-1], p[0]] and _primitive(p):
                found.add(_canonical(p))
        if length == max_transitions:
            break
        prefixes = [p + (b,) for p in prefixes for b in range(n) if allowed[p[-1], b]]
    return sorted(found)


def score(table: TransitionTable, cycle: tuple[int, ...], objective: str, max_transitions: int | None = None) -> float:
    """J, J/N or J/seconds of an open cycle, summed straight from the dense matrices. For
    ``total`` with a bound N, J of the closed walk that repeats the cycle as often as fits in
    N transitions (⌊N / len⌋ times) when J > 0: a repeated walk is a walk the firmware runs."""
    reward, _ = table.dense()
    steps = list(zip(cycle, cycle[1:] + cycle[:1]))
    j = math.fsum(float(reward[a, b]) for a, b in steps)
    if objective == "total":
        repeats = 1 if max_transitions is None else max_transitions // len(cycle)
        return j * repeats if j > 0 else j
    if objective == "rate":
        return j / len(cycle)
    dur = np.zeros_like(reward)
    assert table.duration is not None
    dur[table.src, table.dst] = table.duration
    return j / math.fsum(float(dur[a, b]) for a, b in steps)


def brute_force_gaits(
    table: TransitionTable, objective: str = "total", direction: str = "+x", max_transitions: int | None = None
) -> tuple[float | None, set[tuple[int, ...]]]:
    """(optimal value, set of optimal gaits as closed canonical state tuples), by listing all."""
    n = table.n_states
    simple = objective != "total"
    bound = max_transitions if max_transitions is not None else n
    sign = 1.0 if direction == "+x" else -1.0
    w = sign * np.asarray(table.reward, dtype=np.float64)
    longest = bound if not simple else min(bound, n)
    if objective == "speed":
        assert table.duration is not None
        scale = speed_scale(w, table.duration, longest)
    else:
        scale = reward_scale(w, longest)
    tol = RELATIVE_TOLERANCE * scale
    scored = [(sign * score(table, c, objective), c) for c in closed_walks(table, bound, simple)]
    if objective == "total":  # repeats count in the direction the walk moves
        scored = [(v * (bound // len(c)) if v > 0 else v, c) for v, c in scored]
    scored = [(v, c) for v, c in scored if v > tol]
    if not scored:
        return None, set()
    best = max(v for v, _ in scored)
    return sign * best, {c + (c[0],) for v, c in scored if v >= best - tol}


def brute_force_max_cycle_mean(n: int, src, dst, weight) -> float | None:
    """Largest mean weight over simple cycles (the maximum over all cycles is reached on one)."""
    w = {(int(a), int(b)): float(x) for a, b, x in zip(src, dst, weight)}
    best = None
    for length in range(1, n + 1):
        for perm in itertools.permutations(range(n), length):
            if perm[0] != min(perm):
                continue
            edges = list(zip(perm, perm[1:] + perm[:1]))
            if all(e in w for e in edges):
                mean = math.fsum(w[e] for e in edges) / length
                best = mean if best is None else max(best, mean)
    return best
