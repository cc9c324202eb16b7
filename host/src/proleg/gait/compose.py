"""A gait's motion in the plane: its transitions composed in SE(2).

Each transition a → b moves the robot by its mean (Δx, Δy, Δθ) measured in the body frame
at a (the robot file's ``matrix``, ``dy`` and ``dtheta_deg``; a missing Δy or Δθ counts as
0). Composing them in order — the pose (x, y, θ) becomes

    x += cos θ·Δx − sin θ·Δy,   y += sin θ·Δx + cos θ·Δy,   θ += Δθ

— gives the net motion of one pass in the start frame, and repeating the pass the path of
N cycles. A gait whose ΣΔθ is not zero walks in a circle: its per-pass Δθ is what the
rotation cap bounds, and the path is what a lab sees on the table.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..errors import GaitError
from ..transitions import TransitionTable
from .evaluate import edge_positions


@dataclass(frozen=True)
class Pose:
    """x, y in the table's length unit, θ in degrees (counter-clockwise from +x)."""

    x: float
    y: float
    theta_deg: float


def body_steps(table: TransitionTable, states: Sequence[int]) -> np.ndarray:
    """[(Δx, Δy, Δθ°)] of each transition of the closed walk ``states`` (start repeated at the
    end, or not: an open cycle is closed here)."""
    seq = list(states)
    if len(seq) < 2:
        raise GaitError("a gait has at least two states")
    if seq[0] != seq[-1]:
        seq.append(seq[0])
    pos = edge_positions(table, seq)
    if np.any(pos < 0):
        t = int(np.flatnonzero(pos < 0)[0])
        raise GaitError(f"{table.label(seq[t])} → {table.label(seq[t + 1])} is not an allowed transition")
    planar = table.planar
    zero = np.zeros(len(pos))
    dy = planar.dy[pos] if planar is not None and planar.dy is not None else zero
    dth = planar.dtheta_deg[pos] if planar is not None and planar.dtheta_deg is not None else zero
    return np.stack([np.asarray(table.reward, dtype=np.float64)[pos], dy, dth], axis=1)


def compose_path(steps: np.ndarray, cycles: int = 1, start: Pose = Pose(0.0, 0.0, 0.0)) -> list[Pose]:
    """The poses after each transition of ``cycles`` passes of ``steps``, ``start`` first."""
    x, y, th = start.x, start.y, math.radians(start.theta_deg)
    out = [start]
    for _ in range(int(cycles)):
        for dx, dy, dth in steps.tolist():
            c, s = math.cos(th), math.sin(th)
            x, y, th = x + c * dx - s * dy, y + s * dx + c * dy, th + math.radians(dth)
            out.append(Pose(x, y, math.degrees(th)))
    return out


def net_motion(table: TransitionTable, states: Sequence[int]) -> Pose:
    """The SE(2)-composed motion of one pass, in the start frame."""
    return compose_path(body_steps(table, states))[-1]


def gait_path(table: TransitionTable, states: Sequence[int], cycles: int) -> list[Pose]:
    """The path of ``cycles`` passes from the origin (one pose per transition, start first)."""
    return compose_path(body_steps(table, states), cycles)
