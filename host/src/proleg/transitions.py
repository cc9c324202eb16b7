"""The transition graph every gait algorithm works on.

Edges are the allowed transitions a → b (a ≠ b) with their reward T[a][b] and, when the
robot file gives them, their duration in seconds. Stored as sorted parallel arrays so
that a 2^16-state robot with a million transitions costs a few tens of megabytes.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from math import prod

import numpy as np

from . import states


#: Optional planar statistics per transition (issue 17): mean Δy (same units as the reward,
#: which is the mean Δx), mean Δθ in degrees, and the variances of Δx, Δy (units²) and Δθ (deg²).
PLANAR_FIELDS = ("dy", "dtheta_deg", "var_dx", "var_dy", "var_dtheta_deg")


@dataclass(frozen=True, eq=False)
class PlanarRewards:
    """Planar statistics aligned with a table's edges; a field is None when not given."""

    dy: np.ndarray | None = None
    dtheta_deg: np.ndarray | None = None
    var_dx: np.ndarray | None = None
    var_dy: np.ndarray | None = None
    var_dtheta_deg: np.ndarray | None = None

    def given(self) -> dict[str, np.ndarray]:
        return {k: getattr(self, k) for k in PLANAR_FIELDS if getattr(self, k) is not None}

    def reordered(self, order: np.ndarray) -> "PlanarRewards":
        return PlanarRewards(**{k: np.asarray(v, dtype=np.float64)[order] for k, v in self.given().items()})


@dataclass(frozen=True, eq=False)
class TransitionTable:
    levels: tuple[int, ...]
    src: np.ndarray
    dst: np.ndarray
    reward: np.ndarray
    duration: np.ndarray | None = None
    planar: PlanarRewards | None = None

    def __post_init__(self) -> None:
        m = len(self.src)
        if not (len(self.dst) == len(self.reward) == m):
            raise ValueError("src, dst and reward must have the same length")
        if self.planar is not None and any(len(v) != m for v in self.planar.given().values()):
            raise ValueError("planar statistics must have one entry per transition")
        if self.duration is not None and len(self.duration) != m:
            raise ValueError("duration must have one entry per transition")
        n = self.n_states
        if m and (self.src.min() < 0 or self.dst.min() < 0 or self.src.max() >= n or self.dst.max() >= n):
            raise ValueError(f"transition endpoint out of range 0..{n - 1}")
        if np.any(self.src == self.dst):
            raise ValueError("a state's transition to itself is not a transition")
        key = self.src * n + self.dst
        if m > 1 and np.any(np.diff(key) <= 0):
            raise ValueError("transitions must be sorted by (from, to) and given once each")

    @property
    def n_states(self) -> int:
        return prod(self.levels)

    @property
    def n_transitions(self) -> int:
        return len(self.src)

    @property
    def moves_in_plane(self) -> bool:
        """The table gives a planar motion (Δy or Δθ): a robot that steers, planar-4. Variances
        alone (``var_dx``, a learned file's) are no motion in the plane."""
        return self.planar is not None and (self.planar.dy is not None or self.planar.dtheta_deg is not None)

    def label(self, i: int) -> str:
        return states.label(i, self.levels)

    def index(self, text: str, names: Sequence[str] = ()) -> int:
        """The state labelled ``text`` (``names``: the limbs', for the error)."""
        return states.index(text, self.levels, names)

    def labels(self) -> list[str]:
        return [self.label(i) for i in range(self.n_states)]

    def sequence(self, text: str, names: Sequence[str] = ()) -> list[int]:
        """The states of a comma-separated list of labels (``00,10,11``); ValueError naming the
        entry that is empty or not a state (and the limb, by ``names`` where given)."""
        out = []
        for k, part in enumerate(text.split(","), 1):
            if not part.strip():
                raise ValueError(f"entry {k} of {text!r} is empty")
            out.append(self.index(part.strip(), names))
        return out

    def cycle(self, text: str, names: Sequence[str] = ()) -> list[int]:
        """The states of a gait typed as labels, once each around the cycle (the start not
        repeated): the closed spelling ``00,10,01,00`` and the open ``00,10,01`` both give
        ``[00, 10, 01]``. ValueError for what is neither: an entry ``sequence`` refuses,
        fewer than two states, or a state that follows itself (``11,11,10``; ``00,10,00,00``)."""
        out = self.sequence(text, names)
        if len(out) > 1 and out[0] == out[-1]:
            out = out[:-1]  # the closed spelling: the start repeated at the end
        if len(out) < 2:
            raise ValueError(f"{text!r} is not a gait: it needs at least two states, e.g. 00,10 (or 00,10,00)")
        for k, (a, b) in enumerate(zip(out, [*out[1:], out[0]]), 1):
            if a == b:
                raise ValueError(f"{self.label(a)} follows itself (entry {k + 1} of {text!r}); each step of a "
                                 "gait changes the state")
        return out

    @classmethod
    def from_edges(
        cls,
        levels: tuple[int, ...],
        src,
        dst,
        reward,
        duration=None,
        planar: PlanarRewards | None = None,
    ) -> "TransitionTable":
        """Build from unsorted edge arrays (each (from, to) pair at most once)."""
        src = np.asarray(src, dtype=np.int64)
        dst = np.asarray(dst, dtype=np.int64)
        reward = np.asarray(reward, dtype=np.float64)
        n = prod(levels)
        order = np.argsort(src * n + dst, kind="stable")
        dur = None if duration is None else np.asarray(duration, dtype=np.float64)[order]
        plan = None if planar is None else planar.reordered(order)
        return cls(tuple(levels), src[order], dst[order], reward[order], dur, plan)

    @classmethod
    def from_dense(cls, levels, reward_matrix, allowed=None, duration_matrix=None) -> "TransitionTable":
        """Build from an n×n reward matrix; ``allowed`` masks forbidden transitions."""
        r = np.asarray(reward_matrix, dtype=np.float64)
        n = prod(levels)
        if r.shape != (n, n):
            raise ValueError(f"reward matrix is {r.shape}, expected ({n}, {n})")
        mask = np.ones((n, n), dtype=bool) if allowed is None else np.asarray(allowed, dtype=bool).copy()
        np.fill_diagonal(mask, False)
        src, dst = np.nonzero(mask)
        dur = None if duration_matrix is None else np.asarray(duration_matrix, dtype=np.float64)[src, dst]
        return cls(tuple(levels), src.astype(np.int64), dst.astype(np.int64), r[src, dst], dur)

    def restricted(self, keep: np.ndarray) -> "TransitionTable":
        """This table with only the edges where ``keep`` (a boolean mask over them) is True."""
        return TransitionTable(self.levels, self.src[keep], self.dst[keep], self.reward[keep],
                               None if self.duration is None else self.duration[keep],
                               None if self.planar is None else self.planar.reordered(keep))

    def dense(self) -> tuple[np.ndarray, np.ndarray]:
        """(reward matrix with 0 where forbidden, allowed mask): for small robots only."""
        n = self.n_states
        r = np.zeros((n, n))
        allowed = np.zeros((n, n), dtype=bool)
        r[self.src, self.dst] = self.reward
        allowed[self.src, self.dst] = True
        return r, allowed

    def lookup(self, a: int, b: int) -> int | None:
        """Edge position of a → b, or None when that transition is forbidden."""
        key = a * self.n_states + b
        keys = self.src * self.n_states + self.dst
        pos = int(np.searchsorted(keys, key))
        if pos < len(keys) and keys[pos] == key:
            return pos
        return None
