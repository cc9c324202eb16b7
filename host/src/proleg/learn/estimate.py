"""Per-transition statistics from trials, their confidence, and what to measure next.

For each allowed transition with n trials of a component (Δx, Δy or Δθ): the sample mean
x̄, the unbiased sample variance s² (ddof = 1), and the two-sided confidence interval
x̄ ± t_{(1+c)/2, n−1} · s/√n (Student t; c = 0.95 by default), which assumes independent
trials with roughly normal noise. A transition with fewer than ``min_samples`` trials
(default 2: no variance without two) is flagged. To reach a half-width h, the fewest extra
trials m are the smallest m ≥ 0 with t_{(1+c)/2, n+m−1} · s/√(n+m) ≤ h, taking today's s as
the noise level (with fewer than two trials s is unknown and ``min_samples`` − n is asked).
The penalised score mean − λ·σ (σ = √s²) prefers transitions that move reliably.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np

from ..transitions import TransitionTable
from .measure import Trial
from .stats import t_quantile

COMPONENTS = ("dx", "dy", "dtheta_deg")


@dataclass(frozen=True)
class Component:
    """One component's statistics per allowed transition (arrays aligned with table.src);
    NaN where there are too few trials."""

    n: np.ndarray
    mean: np.ndarray
    var: np.ndarray
    half_width: np.ndarray

    @property
    def low(self) -> np.ndarray:
        return self.mean - self.half_width

    @property
    def high(self) -> np.ndarray:
        return self.mean + self.half_width


@dataclass(frozen=True, eq=False)
class Estimates:
    table: TransitionTable
    confidence: float
    min_samples: int
    components: dict[str, Component]
    #: mean time each transition took (s, aligned with table.src), NaN where none was timed;
    #: None when the trials carry no times
    duration_s: np.ndarray | None = None

    @property
    def dx(self) -> Component:
        return self.components["dx"]

    @property
    def n(self) -> np.ndarray:
        return self.dx.n

    def flagged(self) -> list[str]:
        """Labels ``a->b`` of transitions with too few Δx trials."""
        t = self.table
        return [f"{t.label(a)}->{t.label(b)}" for a, b, k in zip(t.src, t.dst, self.dx.n) if k < self.min_samples]

    def extra_trials(self, half_width: float, component: str = "dx") -> np.ndarray:
        """Fewest extra trials per transition to bring the CI half-width to ``half_width``."""
        return extra_trials(self.components[component], half_width, self.confidence, self.min_samples)


def _component(values: list[list[float]], confidence: float, min_samples: int) -> Component:
    m = len(values)
    n = np.array([len(v) for v in values], dtype=np.int64)
    mean = np.full(m, np.nan)
    var = np.full(m, np.nan)
    hw = np.full(m, np.nan)
    q = (1.0 + confidence) / 2.0
    for e, v in enumerate(values):
        if len(v) >= 1:
            mean[e] = float(np.mean(v))
        if len(v) >= max(2, min_samples):
            var[e] = float(np.var(v, ddof=1))
            hw[e] = t_quantile(q, len(v) - 1) * math.sqrt(var[e] / len(v))
    return Component(n, mean, var, hw)


def estimate(table: TransitionTable, trials: Iterable[Trial], *, confidence: float = 0.95,
             min_samples: int = 2) -> Estimates:
    """Statistics per allowed transition of ``table`` from ``trials`` (others are ignored)."""
    per: dict[str, list[list[float]]] = {c: [[] for _ in range(table.n_transitions)] for c in COMPONENTS}
    took: list[list[float]] = [[] for _ in range(table.n_transitions)]
    for t in trials:
        try:
            e = table.lookup(table.index(t.src), table.index(t.dst))
        except (ValueError, KeyError):
            continue
        if e is None:
            continue
        for c in COMPONENTS:
            v = getattr(t, c)
            if v is not None:
                per[c][e].append(v)
        if t.duration_s is not None:
            took[e].append(t.duration_s)
    comps = {c: _component(per[c], confidence, min_samples) for c in COMPONENTS if any(per[c])}
    if "dx" not in comps:
        comps["dx"] = _component(per["dx"], confidence, min_samples)
    durations = np.array([float(np.mean(v)) if v else math.nan for v in took]) if any(took) else None
    return Estimates(table, confidence, min_samples, comps, durations)


def extra_trials(comp: Component, half_width: float, confidence: float = 0.95, min_samples: int = 2,
                 limit: int = 100_000) -> np.ndarray:
    """See the module docstring; ``limit`` caps the answer for a transition with huge noise."""
    if not half_width > 0:
        raise ValueError("the requested half-width must be > 0")
    q = (1.0 + confidence) / 2.0
    out = np.zeros(len(comp.n), dtype=np.int64)
    for e, (n, var) in enumerate(zip(comp.n.tolist(), comp.var.tolist())):
        if n < max(2, min_samples) or math.isnan(var):
            out[e] = max(2, min_samples) - n
            continue
        s = math.sqrt(var)

        def wide(m: int) -> bool:
            return t_quantile(q, n + m - 1) * s / math.sqrt(n + m) > half_width

        lo, hi = 0, limit  # half-width falls as m grows: bisect for the first m that is narrow enough
        if not wide(0):
            hi = 0
        while lo < hi:
            mid = (lo + hi) // 2
            if wide(mid):
                lo = mid + 1
            else:
                hi = mid
        m = hi
        out[e] = m
    return out


def penalised_table(est: Estimates, weight: float = 1.0, *, component: str = "dx",
                    fallback: TransitionTable | None = None) -> TransitionTable:
    """The transition table whose rewards are mean − λ·σ of ``component`` (λ = ``weight``),
    for ``proleg.gait.optimal_gaits``. Transitions without a variance use their mean (or, with
    no trial, ``fallback``'s reward, else 0) unpenalised; durations are kept."""
    t = est.table
    c = est.components[component]
    reward = np.where(np.isnan(c.mean), 0.0 if fallback is None else fallback.reward, c.mean)
    sigma = np.sqrt(np.where(np.isnan(c.var), 0.0, c.var))
    return TransitionTable(t.levels, t.src.copy(), t.dst.copy(), reward - weight * sigma,
                           None if t.duration is None else t.duration.copy())
