"""How good a learned matrix is, against a known truth (the simulated proof and
``bench/bench_learn.py``; a lab has no truth and uses the intervals instead).

``accuracy(truth, est)`` compares the learned Δx of every allowed transition with the
truth: sign agreement where the truth moves (|truth| > ``moving_mm``; a learned mean of a
transition that truly moves nothing has no sign worth comparing), coverage (the share of
transitions whose truth lies inside the reported 95 % interval), RMSE, the widest interval,
and ``gait_ratio``: the speed, under the truth, of the gait that is rate-optimal for the
learned matrix, as a share of the true optimum's speed.

``effective_truth``: what the table plant really did per firmware transition. A firmware
transition that changes two limbs at once passes through an intermediate state in the
plant (the limbs never cross their thresholds in the same instant), and the plant adds up
the truth entries of every state change it sees; a limb that falls, rises again and falls
within one trial adds all three. For robots whose transitions change one limb at a time
this is the truth file's matrix up to such rare bounces.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import asdict, dataclass

import numpy as np

from ..transitions import TransitionTable
from .estimate import Estimates
from .measure import Trial

#: |truth| above which a transition counts as moving the robot (sign checks)
MOVING_MM = 1.0
#: a plant state change belongs to the trial whose window (t_start, t_end] shifted by this holds
#: its booking time: the explorer's settle_s, the wait between a STATE_REACHED event and the pose
WINDOW_SHIFT_S = 0.05


@dataclass(frozen=True)
class Accuracy:
    transitions: int        # allowed transitions compared
    trials: int
    sign: float             # share of moving transitions whose learned mean has the truth's sign
    coverage: float         # share of transitions whose truth lies inside the reported interval
    rmse_mm: float
    max_half_width_mm: float
    gait_ratio: float       # true speed of the learned matrix's best gait / the true optimum's

    def as_dict(self) -> dict[str, float]:
        return asdict(self)


def gait_ratio(truth: TransitionTable, learned_reward: np.ndarray, objective: str = "rate") -> float:
    """True rate of the ``objective``-optimal gait of ``learned_reward`` (aligned with
    ``truth.src``; NaN = unknown, taken as 0) over the true optimum's rate; 0 when the learned
    matrix has no gait, 1 when the truth has no moving gait either."""
    from ..gait import optimal_gaits
    from ..gait.evaluate import evaluate_sequence

    best = optimal_gaits(truth, objective).value
    learned = TransitionTable(truth.levels, truth.src, truth.dst, np.nan_to_num(learned_reward))
    res = optimal_gaits(learned, objective)
    if not res.gaits:
        return 0.0
    if not best or best <= 0:
        return 1.0
    g = res.gaits[0].states
    walk = list(g) + ([] if g[-1] == g[0] else [g[0]])
    return float(evaluate_sequence(truth, walk).rate / best)


def accuracy(truth: TransitionTable, est: Estimates, *, moving_mm: float = MOVING_MM) -> Accuracy:
    """``est`` (learned on ``truth``'s transitions, same order) against ``truth`` (mm)."""
    tv = np.asarray(truth.reward, dtype=float)
    mean, hw = est.dx.mean, est.dx.half_width
    moving = np.abs(tv) > moving_mm
    sign = float(np.mean(np.sign(mean[moving]) == np.sign(tv[moving]))) if moving.any() else 1.0
    with np.errstate(invalid="ignore"):
        inside = np.abs(mean - tv) <= hw
    return Accuracy(
        transitions=truth.n_transitions, trials=int(est.dx.n.sum()), sign=sign,
        coverage=float(np.mean(inside)),
        rmse_mm=float(np.sqrt(np.nanmean((mean - tv) ** 2))),
        max_half_width_mm=float(np.nanmax(hw)) if np.isfinite(hw).any() else float("inf"),
        gait_ratio=gait_ratio(truth, mean),
    )


def booked_at(change) -> float:
    """When a plant transition moved the robot: its ``t_booked_s`` (the table plant adds a
    change's motion once ``simultaneous_s`` has passed since its first limb crossed, a pass's
    when its last leg did), else ``t_s`` (a log without booking times)."""
    t = getattr(change, "t_booked_s", None)
    return change.t_s if t is None else t


def plant_changes(trials: Sequence[Trial], plant_transitions: Sequence) -> list[list]:
    """Per trial, the plant's transitions whose motion falls inside its pose window: booked
    (``booked_at``) after the trial's start and up to its end, each shifted by
    WINDOW_SHIFT_S (the explorer reads the pose ``settle_s`` after each STATE_REACHED event).
    Windowing by the first limb change instead (``t_s``) put a change that began just before
    a pose was read, and moved the robot just after, in the trial that did not measure it.
    ``plant_transitions``: the plant's log (``.t_s``, ``.t_booked_s``, ``.src``, ``.dst``), in
    any order; each trial's list keeps the log's objects, in booking order."""
    changes = sorted(plant_transitions, key=booked_at)
    times = np.array([booked_at(p) for p in changes])
    out = []
    for tr in trials:
        lo = np.searchsorted(times, tr.t_start + WINDOW_SHIFT_S, side="right")
        hi = np.searchsorted(times, tr.t_end + WINDOW_SHIFT_S, side="right")
        out.append(changes[lo:hi])
    return out


def effective_truth(table: TransitionTable, truth_mm: np.ndarray, trials: Sequence[Trial],
                    plant_transitions: Sequence) -> TransitionTable:
    """Noise-free mm per firmware transition as the table plant made them (module docstring):
    per trial the truth entries (``truth_mm``, n×n) of every plant state change whose motion
    its pose window holds (``plant_changes``), averaged over the transition's trials; a
    transition without trials keeps the direct entry. ``plant_transitions``: the plant's log."""
    sums: list[list[float]] = [[] for _ in range(table.n_transitions)]
    for tr, seen in zip(trials, plant_changes(trials, plant_transitions)):
        e = table.lookup(table.index(tr.src), table.index(tr.dst))
        if e is not None:
            sums[e].append(float(sum(truth_mm[p.src, p.dst] for p in seen)))
    direct = truth_mm[table.src, table.dst]
    eff = np.array([np.mean(s) if s else direct[e] for e, s in enumerate(sums)])
    return TransitionTable(table.levels, table.src, table.dst, eff, table.duration)
