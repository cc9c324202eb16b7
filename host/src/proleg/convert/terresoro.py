"""TerreSoRo motion-primitive data (a MATLAB .mat) → a proleg robot file with planar statistics.

The data: Mahendran, Freeman, Chang, McDougall, Vela & Vikas, "Multi-Gait Locomotion
Planning and Tracking for Tendon-Actuated Terrestrial Soft Robot (TerreSoRo)", IROS 2023,
doi:10.1109/IROS55552.2023.10341926; repository github.com/clfreeman7/Path_Planning, file
demos/data/experiment_2_motion_primitives.mat. This module carries none of that data or
code; it reads a copy the user fetched.

The file holds ``motion_primitive_data``: trials × 240 transitions × (Δx cm, Δy cm, Δθ rad),
body frame. Their state s = 1..16 is proleg's label ``format(s - 1, '04b')`` (motor 0 = the
leftmost limb); their transition k is the k-th ordered pair (i, j), i ≠ j, row by row. Per
transition the robot file gets the mean over trials (``matrix`` = Δx, ``dy``, ``dtheta_deg``)
and the sample variance (n − 1 in the denominator, as their synthesiser's cost reproduces:
0001→0011 costs 0.9745), Δθ converted to degrees.

    python -m proleg.convert.terresoro experiment_2_motion_primitives.mat terresoro.toml
"""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import RobotFileError

LIMBS = 4
N_STATES = 1 << LIMBS
#: Their transition k (0-based) → (from, to) state indices: ordered pairs i ≠ j, row by row.
PAIRS = [(i, j) for i in range(N_STATES) for j in range(N_STATES) if i != j]
VARIABLE = "motion_primitive_data"


@dataclass(frozen=True)
class PrimitiveStats:
    """Per transition (from, to): mean and sample variance over trials of Δx, Δy (cm) and
    Δθ (degrees), as 16 × 16 arrays (diagonal 0); ``trials`` the number averaged."""

    mean: np.ndarray  # [16, 16, 3]
    var: np.ndarray   # [16, 16, 3]
    trials: int


def read_terresoro(path: str | Path) -> PrimitiveStats:
    """Read a TerreSoRo motion-primitive .mat (RobotFileError with one line when it is not one)."""
    path = Path(path)
    try:
        from scipy.io import loadmat
    except ImportError:
        raise RobotFileError("reading a .mat needs scipy: pip install 'proleg[terresoro]'") from None
    try:
        doc = loadmat(str(path))
    except Exception as e:  # scipy raises many kinds (IndexError, ValueError, ...) on junk
        raise RobotFileError(f"{path}: not a MATLAB .mat file scipy can read ({e})") from None
    if VARIABLE not in doc:
        raise RobotFileError(f"{path}: no variable {VARIABLE!r} (expected trials × 240 × 3)")
    data = np.asarray(doc[VARIABLE], dtype=np.float64)
    if data.ndim != 3 or data.shape[1:] != (len(PAIRS), 3) or data.shape[0] < 2:
        raise RobotFileError(f"{path}: {VARIABLE} is {data.shape}, expected (trials >= 2, 240, 3)")
    if not np.all(np.isfinite(data)):
        raise RobotFileError(f"{path}: {VARIABLE} holds a value that is not a finite number")
    return stats_from_trials(data)


def stats_from_trials(data: np.ndarray) -> PrimitiveStats:
    """Means and sample variances from trials × 240 × (Δx cm, Δy cm, Δθ rad)."""
    deg = np.array([1.0, 1.0, 180.0 / math.pi])
    per = data * deg
    mean = np.zeros((N_STATES, N_STATES, 3))
    var = np.zeros((N_STATES, N_STATES, 3))
    src = np.array([p[0] for p in PAIRS])
    dst = np.array([p[1] for p in PAIRS])
    mean[src, dst] = per.mean(axis=0)
    var[src, dst] = per.var(axis=0, ddof=1)
    return PrimitiveStats(mean, var, int(data.shape[0]))


def _matrix_toml(key: str, m: np.ndarray, digits: int) -> str:
    rows = []
    for i in range(N_STATES):
        cells = ['"x"' if i == j else f"{round(float(m[i, j]), digits):.{digits}f}" for j in range(N_STATES)]
        rows.append("  [" + ", ".join(cells) + "],")
    return f"{key} = [\n" + "\n".join(rows) + "\n]\n"


def robot_toml(stats: PrimitiveStats, name: str = "terresoro", digits: int = 6, source: str = "") -> str:
    """A robot file for the 4-limb TerreSoRo with the planar statistics of ``stats``."""
    labels = [format(s, "04b") for s in range(N_STATES)]
    out = [
        "# TerreSoRo (4 tendon-driven limbs) motion primitives, converted by proleg.convert.terresoro.",
        "# Data: Mahendran, Freeman, Chang, McDougall, Vela & Vikas, IROS 2023,",
        "# doi:10.1109/IROS55552.2023.10341926; github.com/clfreeman7/Path_Planning,",
        f"# demos/data/experiment_2_motion_primitives.mat{(' (' + source + ')') if source else ''}.",
        "# Related: Freeman, Mahendran & Vikas, IEEE T-RO 2025 (four-limb robots, gait synthesis).",
        f"# Derived: per transition, the mean and the sample variance (n - 1) over the {stats.trials} trials",
        "# of Δx, Δy (cm) and Δθ (converted from rad to degrees), rounded; their transition k is",
        "# the k-th ordered pair (i, j), i != j, of their states 1..16 = labels format(s - 1, '04b').",
        "# Only these summary statistics are here: no raw trial data is redistributed.",
        "# The limbs' thresholds and the actuators below are placeholders: proleg's gait search",
        "# only uses [transitions]; give the real ones before building firmware.",
        "",
        "[robot]",
        f'name = "{name}"',
        'description = "TerreSoRo motion primitives (Mahendran et al., IROS 2023)"',
        "",
    ]
    for i in range(LIMBS):
        out += ["[[limb]]", f'name = "motor{i}"', "psi_star_deg = [20.0]", f'actuator = "motor{i}"', ""]
    for i in range(LIMBS):
        out += ["[[actuator]]", f'name = "motor{i}"', f"channel = {i}", ""]
    out += ["[transitions]", 'units = "cm"', "states = [" + ", ".join(f'"{s}"' for s in labels) + "]"]
    text = "\n".join(out) + "\n"
    text += _matrix_toml("matrix", stats.mean[:, :, 0], digits)
    text += _matrix_toml("dy", stats.mean[:, :, 1], digits)
    text += _matrix_toml("dtheta_deg", stats.mean[:, :, 2], digits)
    text += _matrix_toml("var_dx", stats.var[:, :, 0], digits)
    text += _matrix_toml("var_dy", stats.var[:, :, 1], digits)
    text += _matrix_toml("var_dtheta_deg", stats.var[:, :, 2], digits)
    return text


def main(argv: list[str] | None = None) -> int:
    args = sys.argv[1:] if argv is None else argv
    if len(args) != 2:
        print("usage: python -m proleg.convert.terresoro IN.mat OUT.toml", file=sys.stderr)
        return 2
    try:
        stats = read_terresoro(args[0])
    except RobotFileError as e:
        print(f"error: {e}", file=sys.stderr)
        return 1
    Path(args[1]).write_text(robot_toml(stats, source=Path(args[0]).name))
    print(f"{args[1]}: {N_STATES} states, {len(PAIRS)} transitions, {stats.trials} trials")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
