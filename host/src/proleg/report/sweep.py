"""The firmware under random operating conditions: ``proleg check`` and ``bench/bench_sweep.py``.

A fixed grid of conditions (the claim bench's) can be fitted without anyone meaning to, and a
lab's robot meets conditions nobody listed. So each *row* here is ``KEYS_PER_ROW`` keys of the
physical plant (docs/plant.md, "Conditions") drawn at random from ``DRAWS``' ranges, which span
the claim grid's mild and strong strengths and go a little past the strong ones, never into what
the grid calls impossible (a supply collapse, a dead coil). Per-limb keys name a limb drawn from
the ones given (the robot's limbs; the bench keeps the grid's ``rear``/``front``). For each row,
as in the claim bench (``report.claim``):

- the idealised drive (true ψ and ψ*, the firmware's envelope) says whether the coils can
  complete the gait under it at all, and how fast it walks;
- the firmware walks the gait on the simulated board (host-sim, or the exact MCU image on an
  emulated one), started as a user starts it (a flat calibration, then the condition's ground),
  for the run length the nominal gait needs.

A row is **missed** when the idealised drive walks it and the firmware does not complete it (a
fault stop, the wrong way, or a coil past 120 °C), and a **hot stop** when neither walks it and
the firmware's stop heated a coil past 120 °C. Either fails the check. The draws are seeded: the
same rows every run, other rows with another seed.
"""

from __future__ import annotations

import dataclasses
import random
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass
from typing import Any

from ..physics.materials import NITI_OVERHEAT_C
from . import claim
from .claim_summary import IDEALISED_FLOOR

KEYS_PER_ROW = 3

#: key -> a draw of its value's text, from (rng, the limb names a per-limb key may name). The
#: ranges span the claim grid's mild and strong strengths (``claim.MODES``).
DRAWS: dict[str, Callable[[random.Random, Sequence[str]], str]] = {
    "power": lambda r, _: f"{r.uniform(0.7, 1.3):.2f}",
    "ambient_c": lambda r, _: f"{r.uniform(5, 38):.0f}",
    "convection": lambda r, _: f"{r.uniform(0.6, 1.6):.2f}",
    "supply_ohm": lambda r, _: f"{r.uniform(0, 8):.1f}",
    "coil_mismatch": lambda r, _: f"{r.uniform(0, 0.3):.2f}",
    "power_scale": lambda r, limbs: f"{r.choice(limbs)}:{r.uniform(0.7, 1.0):.2f}",
    "overlap_mm": lambda r, limbs: f"{r.choice(limbs)}:{r.uniform(4, 16):.0f}",
    "fatigue_cycles": lambda r, _: f"{r.uniform(0, 30000):.0f}",
    "imu_offset_deg": lambda r, limbs: f"{r.choice(limbs)}:{r.uniform(-8, 8):.1f}",
    "imu_bias_deg": lambda r, limbs: f"{r.choice(limbs)}:{r.uniform(-6, 6):.1f}",
    "imu_noise_deg": lambda r, _: f"{r.uniform(0, 1.5):.2f}",
    "psi_star_shift_deg": lambda r, limbs: f"{r.choice(limbs)}:{r.uniform(-6, 6):.1f}",
    "mass_g": lambda r, _: f"{r.uniform(3, 8):.1f}",
}

#: Keys that say what the robot is (its mass, its coils' overlap, how worn they are) rather than
#: what it meets: a robot file whose ``[plant]`` gives one is checked as that robot, the key held
#: at the file's value and not drawn (the draws are absolute values about the paper robot's: a
#: 15 g robot drew rows of 3–8 g, a coil worn 25,000 cycles rows of less wear).
ROBOT_KEYS = ("mass_g", "overlap_mm", "fatigue_cycles")

#: The limb names of the bench's draws: the claim grid's (the first and last limb).
GRID_LIMBS = ("rear", "front")


def draw_rows(n: int, seed: int, limbs: Sequence[str] = GRID_LIMBS,
              leave_out: Sequence[str] = ()) -> list[tuple[str, ...]]:
    """``n`` rows of ``KEYS_PER_ROW`` distinct keys each (none of ``leave_out``), drawn with
    ``seed``; a per-limb key names one of ``limbs``."""
    keys = sorted(k for k in DRAWS if k not in leave_out)
    per_row = min(KEYS_PER_ROW, len(keys))
    rng = random.Random(seed)
    rows = []
    for _ in range(n):
        picked = rng.sample(keys, per_row)
        rows.append(tuple(f"{k}={DRAWS[k](rng, tuple(limbs))}" for k in picked))
    return rows


@dataclass(frozen=True)
class Row:
    """One row: its conditions, the idealised drive's verdict and the firmware's run."""

    conditions: tuple[str, ...]
    possible: bool
    why_not: str
    idealised_mm_s: float | None
    completed: bool
    speed_mm_s: float
    fault: str
    note: str
    coil_peak_c: float
    reported: str
    #: the idealised drive makes less than ``BARELY`` of the nominal row's speed here (set by
    #: ``barely_moving``, which knows the nominal row)
    barely_moves: bool = False

    @property
    def hot(self) -> bool:
        return self.coil_peak_c > NITI_OVERHEAT_C

    @property
    def drifted(self) -> bool:
        """The gait barely moves the robot here, and the firmware walked it without a fault and
        cool but drifted the other way: not a miss (which way a gait that does not carry the
        robot drifts is its plant's, not its controller's)."""
        return (self.possible and self.barely_moves and not self.completed and not self.fault and not self.hot
                and self.note.startswith("walks the wrong way"))

    @property
    def missed(self) -> bool:
        """The coils can walk it (the idealised drive does) and the firmware did not complete it."""
        return self.possible and not self.completed and not self.drifted

    @property
    def hot_stop(self) -> bool:
        """Nothing walks it, and the firmware's stop heated a coil past 120 °C."""
        return not self.possible and not self.completed and self.hot

    @property
    def failed(self) -> bool:
        return self.missed or self.hot_stop

    @property
    def verdict(self) -> str:
        """ok, missed, drifted (``drifted``), clean stop (nothing walks it, the firmware stopped
        cool), hot stop, or walked (the firmware walked where the idealised drive did not: it is
        not a ceiling)."""
        if self.possible:
            return "ok" if self.completed else "drifted" if self.drifted else "missed"
        if self.completed:
            return "walked"
        return "hot stop" if self.hot else "clean stop"

    def what_happened(self) -> str:
        """The firmware's run in a few words: its fault, its note, or the speed it walked."""
        if self.completed:
            tail = f" ({self.reported} reported)" if self.reported else ""
            return f"{self.speed_mm_s:+.3f} mm/s{tail}"
        return self.fault or self.note or "did not complete"

    def to_json(self) -> dict[str, Any]:
        d = asdict(self)
        d["conditions"] = list(self.conditions)
        d["idealised_mm_s"] = None if self.idealised_mm_s is None else round(self.idealised_mm_s, 4)
        d["speed_mm_s"] = round(self.speed_mm_s, 4)
        d["coil_peak_c"] = round(self.coil_peak_c, 1)
        d.update(verdict=self.verdict, missed=self.missed, hot_stop=self.hot_stop)
        return d


def run_row(robot: Any, conditions: Sequence[str], run_s: float, *, direction: str = "+x",
            gait: int | Sequence[int] = 0, name: str = "row", board: str = "host-sim",
            ideal: claim.IdealisedWalk | None = None) -> Row:
    """The idealised drive and the firmware (on the simulated ``board``) under ``conditions``,
    each from a cold robot. ``ideal``: the idealised drive's walk under these conditions where
    the caller already has it (the nominal row's, from ``run_length``)."""
    point = claim.GridPoint(name, (), "random", tuple(conditions), ())
    if ideal is None:
        ideal = claim.idealised_walk(robot, point, direction, gait)
    fb = claim.feedback_run(robot, point, direction=direction, gait=gait, duration_s=run_s, board=board)
    return Row(tuple(conditions), ideal.possible, ideal.why_not, ideal.speed_mm_s, fb.completed,
               fb.speed_mm_s, fb.fault, fb.note, fb.coil_peak_c, fb.reported)


def run_length(robot: Any, *, direction: str = "+x", gait: int | Sequence[int] = 0,
               base: Sequence[str] = ()) -> tuple[float, claim.IdealisedWalk]:
    """The run length of every row (``claim.run_length`` of the idealised drive's walk under
    ``base`` alone), and that walk."""
    nominal = claim.idealised_walk(robot, claim.GridPoint("nominal", (), "none", tuple(base)), direction, gait)
    return claim.run_length(nominal), nominal


#: A row whose idealised drive makes less than this share of the nominal row's speed (the
#: right way) barely moves (the claim bench's ``IDEALISED_FLOOR``): +0.001 mm/s against a nominal
#: 0.4 is the plant's noise, and a firmware run that drifts −0.001 mm/s there is not a miss.
BARELY = IDEALISED_FLOOR


def barely_moving(rows: Sequence[Row], nominal_mm_s: float | None, direction: str = "+x") -> list[Row]:
    """``rows`` with ``barely_moves`` set against the idealised drive's nominal speed."""
    sign = 1 if direction == "+x" else -1
    if not nominal_mm_s or sign * nominal_mm_s <= 0:
        return list(rows)
    floor = BARELY * abs(nominal_mm_s)
    return [dataclasses.replace(r, barely_moves=r.possible and r.idealised_mm_s is not None
                                and sign * r.idealised_mm_s < floor) for r in rows]


def summary(rows: Sequence[Row]) -> dict[str, Any]:
    possible = [r for r in rows if r.possible]
    impossible = [r for r in rows if not r.possible]
    return {
        "rows": len(rows), "possible": len(possible),
        "completed_where_possible": sum(r.completed for r in possible),
        "missed": sum(r.missed for r in rows),
        "drifted": sum(r.drifted for r in rows),
        "impossible": len(impossible),
        "impossible_completed_by_the_firmware": sum(r.completed for r in impossible),
        "impossible_stopped_below_120c": sum(not r.completed and not r.hot for r in impossible),
        "hot_stops": sum(r.hot_stop for r in rows),
        "overheated": sum(r.hot for r in rows),
        "hottest_c": None if not rows else round(max(r.coil_peak_c for r in rows), 1),
    }
