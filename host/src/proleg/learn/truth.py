"""A hidden truth for the learning proof: a robot file whose ``[transitions]`` matrix, in
mm, drives the simulator's table plant (``proleg learn ROBOT --sim --truth TRUTH.toml``).

``truth_text(robot)`` is ``robot``'s own file with every allowed entry of its matrix turned
into millimetres (× ``[plant] step_mm`` when the file counts in steps) and moved by up to
± ``jitter`` of itself (a fixed seed), ``units = "mm"``, and the plant's ``noise_mm`` (σ of
the Gaussian added to each transition) merged into the file's ``[plant]`` table — the
keys ``step_mm`` and ``noise_mm`` replaced where the file has them (a matrix in mm takes
``step_mm = 1``), the table added where it has none. Everything else is copied unchanged,
so the firmware built from ROBOT and the plant built from the truth agree on limbs,
actuators and states, and only the numbers differ.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..robot import Robot, load_robot
from .robotfile import _matrix, _section_span

#: keys of ``[plant]`` that ``truth_text`` sets (a matrix in mm moves the plant 1 mm per unit)
MERGED_KEYS = ("step_mm", "noise_mm")


def truth_matrix_mm(robot: Robot, *, jitter: float = 0.1, seed: int = 15) -> np.ndarray:
    """``robot``'s dense matrix in mm, each entry × (1 + U(−jitter, jitter)); NaN-free
    (forbidden entries keep the dense matrix's value, which the writer marks "x")."""
    reward, _allowed = robot.transitions.dense()
    step = float(robot.plant.step_mm)  # 1 for mm, 10 for cm… (robot_plant), the step for steps
    rng = np.random.default_rng(seed)
    return np.nan_to_num(reward) * step * (1.0 + jitter * rng.uniform(-1.0, 1.0, reward.shape))


def _merge_plant(lines: list[str], values: dict[str, float]) -> list[str]:
    span = _section_span(lines, "plant")
    new = [f"{k} = {v:g}" for k, v in values.items()]
    if span is None:
        return lines + ["", "[plant]", *new]
    a, b = span
    body = [ln for ln in lines[a + 1:b] if ln.split("=")[0].strip() not in values]
    return lines[:a + 1] + new + body + lines[b:]


def truth_text(robot: Robot | str | Path, *, jitter: float = 0.1, noise_mm: float = 0.5, seed: int = 15) -> str:
    """The truth file's text (module docstring)."""
    if not isinstance(robot, Robot):
        robot = load_robot(robot)
    table = robot.transitions
    _reward, allowed = table.dense()
    mm = truth_matrix_mm(robot, jitter=jitter, seed=seed)
    lines = Path(robot.path).read_text(encoding="utf-8").splitlines()
    section = ["[transitions]", 'units = "mm"',
               "states = [" + ", ".join(f'"{table.label(i)}"' for i in range(table.n_states)) + "]"]
    section += _matrix("matrix", np.round(mm, 3), allowed)
    if table.duration is not None:
        dur = np.zeros((table.n_states, table.n_states))
        dur[table.src, table.dst] = table.duration
        section += _matrix("durations_s", dur, allowed)
    span = _section_span(lines, "transitions")
    assert span is not None  # a loaded robot has one
    a, b = span
    lines = lines[:a] + section + [""] + lines[b:]
    lines = _merge_plant(lines, {"step_mm": 1.0, "noise_mm": noise_mm})
    return "\n".join(lines) + "\n"


def write_truth(robot: Robot | str | Path, out: str | Path, **kw) -> Path:
    """Write ``truth_text(robot, **kw)`` to ``out`` (checked by loading it back)."""
    out = Path(out)
    out.write_text(truth_text(robot, **kw), encoding="utf-8")
    load_robot(out)
    return out
