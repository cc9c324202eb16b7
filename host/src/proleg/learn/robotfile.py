"""The learned robot file: the robot file the lab gave, with ``[transitions]`` replaced.

The new ``[transitions]`` holds the learned Δx means as ``matrix`` (in the trials' units,
stated in ``units``; forbidden entries stay ``"x"``; a transition never measured keeps its
previous value and is named in a comment, but one learning left out, never measured (``left_out``:
``makeable.not_asked``: the hardware cannot make it, the body cannot hold its state, or the robot
faulted making it), becomes ``"x"``, named in a comment too), the durations of the old table when it had
some, and beside it the learned statistics under issue 17's names — ``dy``,
``dtheta_deg``, ``var_dx``, ``var_dy``, ``var_dtheta_deg`` — and ``n_trials``, same shape as
``matrix``, ``"x"`` where forbidden, ``nan`` where unknown — real keys that the loader
(``proleg.robot``) reads: ``Robot.n_trials``, and the planar statistics that ``proleg gait``
weighs (``--variance-weight``). ``stats_as_keys=False`` writes them as comment lines
``#learned: key = [...]`` instead (for an older proleg); ``read_learned`` reads both. The previous ``[transitions]`` table is
kept below, commented out. Everything else in the file is copied unchanged but two keys
that the new matrix voids: ``[plant] step_mm`` when the unit turns to a length, and per-gait
``[control] max_climb_deg`` lists (the old gaits'; ``climb_for_new_gaits``). The text is
read back before it is written (valid TOML, only those changed) and written
atomically (``proleg.outputs.write_text_atomic``). Numbers are written so that they read
back exactly.
"""

from __future__ import annotations

import json
import math
import re
import tomllib
from datetime import datetime, timezone
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import ProlegError
from ..outputs import write_text_atomic
from ..robot import Robot
from ..robot_climb import ClimbLimit
from ..robot_transitions import UNIT_MM
from ..transitions import TransitionTable
from .estimate import Estimates
from .makeable import Left, file_comments

_KEY = r"""(?:[A-Za-z0-9_-]+|"[^"\n]*"|'[^'\n]*')"""  # a bare or quoted TOML key
HEADER_RE = re.compile(rf"^\s*\[\[?\s*{_KEY}(?:\s*\.\s*{_KEY})*\s*\]\]?\s*(#.*)?$")
PREFIX = "#learned: "


class LearnedFileError(ProlegError):
    """The robot file's ``[transitions]`` cannot be replaced as text (one line, exit 2)."""


STAT_KEYS = (("dy", "dy", "mean"), ("dtheta_deg", "dtheta_deg", "mean"), ("var_dx", "dx", "var"),
             ("var_dy", "dy", "var"), ("var_dtheta_deg", "dtheta_deg", "var"))


def _num(v: float) -> str:
    """``v`` as TOML that reads back as exactly ``v`` (a whole number without its ``.0``)."""
    if not math.isfinite(v):
        return "nan" if math.isnan(v) else ("inf" if v > 0 else "-inf")
    if v == int(v) and abs(v) < 1e15:
        return str(int(v))
    return repr(v)


def _matrix(name: str, values: np.ndarray, allowed: np.ndarray, prefix: str = "") -> list[str]:
    n = len(values)
    width = max(len(_num(float(v))) for v in values.ravel())
    lines = [f"{prefix}{name} = ["]
    for a in range(n):
        cells = []
        for b in range(n):
            cell = '"x"' if (a != b and not allowed[a, b]) else _num(float(values[a, b]))
            cells.append(cell.rjust(max(width, 3)))
        lines.append(f"{prefix}  [{', '.join(cells)}],")
    lines.append(f"{prefix}]")
    return lines


def _table_path(line: str) -> tuple[str, ...] | None:
    """The key path of a table header line (``[transitions]``, ``[ transitions ]``,
    ``["transitions"]``, ``[[limb]]``, ``[a . b]``), or None when the line is not one."""
    if not HEADER_RE.match(line):
        return None
    try:
        node = tomllib.loads(line.strip())
    except tomllib.TOMLDecodeError:
        return None
    path: list[str] = []
    while isinstance(node, dict) and len(node) == 1:
        key = next(iter(node))
        path.append(key)
        node = node[key][-1] if isinstance(node[key], list) else node[key]
    return tuple(path)


def _section_span(lines: list[str], name: str) -> tuple[int, int] | None:
    """Lines [start, end) of the table ``[name]`` (its header to the next header)."""
    start = None
    for i, ln in enumerate(lines):
        path = _table_path(ln)
        if path is None:
            continue
        if start is not None:
            return start, i
        if path == (name,):
            start = i
    return None if start is None else (start, len(lines))


def unit_factor(robot: Robot, units: str) -> float:
    """How many ``units`` one unit of ``robot``'s matrix is: a length unit's millimetres, or
    for ``steps`` the robot file's ``[plant] step_mm`` (what its plants take a step to be)."""
    if units == robot.units:
        return 1.0
    if units not in UNIT_MM:
        raise LearnedFileError(f"learn: cannot turn {robot.path}'s {robot.units!r} into {units!r}")
    return robot.plant.step_mm / UNIT_MM[units]  # step_mm is the unit's mm for a length unit too


def learned_transitions_text(robot: Robot, est: Estimates, *, units: str, stats_as_keys: bool = True,
                             note: str = "", left_out: dict[int, Left] | None = None,
                             header: list[str] | None = None) -> list[str]:
    table = robot.transitions
    n = table.n_states
    old, allowed = table.dense()
    dx = est.dx
    k = unit_factor(robot, units)
    new = old * k  # a transition not measured keeps its value, in the new unit
    missing = []
    forbidden: dict[int, Left] = {}  # not measured, and left out by learning (learn/makeable.py): "x" now
    for e, (a, b) in enumerate(zip(table.src.tolist(), table.dst.tolist())):
        if dx.n[e] >= 1:
            new[a, b] = dx.mean[e]
        elif left_out and e in left_out:
            allowed[a, b] = False
            forbidden[e] = left_out[e]
        else:
            missing.append(f"{table.label(a)}->{table.label(b)}")
    when = datetime.now(timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    out = [line.format(when=when, units=units) for line in header] if header is not None else [
        f"# [transitions] learned by proleg learn ({when}) from {int(dx.n.sum())} trials{note}.",
        f"# matrix: mean Δx per transition in {units}; var_*: sample variances (square of the unit, deg² for θ);",
        f"# n_trials: trials per transition; {int(est.confidence * 100)} % intervals are in the learn report.",
    ]
    if missing:
        kept = "previous value kept" + (f", × {k:g} from {robot.units} to {units}" if k != 1.0 else "")
        out.append(f"# not measured ({kept}): {', '.join(missing)}")
    out += file_comments(table, forbidden)
    out += ["[transitions]", f'units = "{units}"',
            "states = [" + ", ".join(f'"{table.label(i)}"' for i in range(n)) + "]"]
    out += _matrix("matrix", new, allowed)
    durations, said = _durations(table, est, allowed[table.src, table.dst])
    if durations is not None:
        dur = np.zeros((n, n))
        dur[table.src, table.dst] = durations
        out += said + _matrix("durations_s", dur, allowed)
    prefix = "" if stats_as_keys else PREFIX
    if not stats_as_keys:
        out.append(f"# Learned statistics beside the matrix, commented out for an older proleg: delete '{PREFIX}'")
        out.append("# to use them; `proleg.learn.robotfile.read_learned` reads them either way.")
    counts = np.zeros((n, n))
    counts[table.src, table.dst] = dx.n
    out += _matrix("n_trials", counts, allowed, prefix)
    given = table.planar.given() if table.planar is not None else {}
    for key, comp, what in STAT_KEYS:
        c = est.components.get(comp)
        if c is None and key not in given:
            continue
        m = np.full((n, n), np.nan)
        np.fill_diagonal(m, 0.0)
        # the file's own values, in the new unit, where nothing was measured (a plant without
        # y/θ, or a transition not tried), as for the matrix
        old_values = np.full(len(table.src), np.nan)
        if key in given:
            length = 0 if comp == "dtheta_deg" else (2 if what == "var" else 1)
            old_values = np.asarray(given[key], dtype=float) * k ** length
        if c is None:
            m[table.src, table.dst] = old_values
            out.append(f"# {key}: not learned here, the previous values kept")
        else:
            m[table.src, table.dst] = np.where(dx.n >= 1, getattr(c, what), old_values)
        out += _matrix(key, m, allowed, prefix)
    return out


def _durations(table: TransitionTable, est: Estimates, kept: np.ndarray) -> tuple[np.ndarray | None, list[str]]:
    """Each allowed transition's duration for ``durations_s`` (aligned with ``table.src``) and
    the comment lines that say where they come from: the mean time it took where it was timed,
    else the old table's duration, else the longest timed one (a guess that makes no untimed
    step look fast, nor safe from the state timeout). None when nothing was timed and the old
    table had no durations. ``kept``: the transitions the new table still allows (a left-out
    one is "x" and needs no duration)."""
    took = est.duration_s
    timed = np.zeros(len(table.src), dtype=bool) if took is None else np.isfinite(took) & kept
    if not timed.any():
        return (None if table.duration is None else table.duration.copy()), []
    said = ["# durations_s: the mean time each transition took, until its state was reached (s)"]
    untimed = [f"{table.label(a)}->{table.label(b)}" for a, b, ok, k in zip(table.src, table.dst, timed, kept)
               if k and not ok]
    if table.duration is not None:
        fill, how = table.duration, "the previous durations kept"
    else:
        longest = float(np.max(took[timed]))
        fill, how = np.full(len(timed), longest), f"the longest timed one, {longest:.3g} s, written"
    if untimed:
        said.append(f"# durations_s not timed ({how}): {', '.join(untimed)}")
    return np.where(timed, took, fill), said


def write_learned_robot(robot: Robot, est: Estimates, out: str | Path, *, units: str | None = None,
                        stats_as_keys: bool = True, note: str = "", left_out: dict[int, Left] | None = None,
                        header: list[str] | None = None, command: str = "learn") -> Path:
    """Write ``robot``'s file with the learned ``[transitions]`` (see the module docstring),
    atomically, after checking that the text reads back as the robot file with only
    ``[transitions]`` changed (``LearnedFileError`` otherwise: nothing is written).
    ``header``: the comment lines above the table (``{when}``, ``{units}`` filled in) in place
    of learning's; ``command``: what the messages name."""
    source = Path(robot.path).read_text(encoding="utf-8")
    units = units or robot.units
    new = learned_transitions_text(robot, est, units=units, stats_as_keys=stats_as_keys, note=note,
                                   left_out=left_out, header=header)
    lines = source.splitlines()
    # the matrix's unit fixes step_mm now (an unmeasured file's step_mm was not used: robot.py)
    if units in UNIT_MM and (units != robot.units or robot.unmeasured):
        lines = _drop_plant_key(lines, "step_mm", f"the matrix is in {units} now (learned)")
    climb = climb_for_new_gaits(robot)
    if climb is not None:
        lines = _set_control_key(lines, "max_climb_deg", str(climb), robot.path,
                                 "per-gait limits of the previous matrix's gaits: their smallest for every "
                                 "gait now (learned; proleg sim --measure-climb measures the new ones)")
    text = _replace_transitions(lines, new)
    doc = _check_learned(source, text, new, robot.path, control_changed=("max_climb_deg",) if climb else ())
    learned = _check_loads(doc, Path(out), robot.path)
    if climb is not None and learned.control.max_climb_deg != climb:
        raise LearnedFileError(f"learn: {robot.path}: [control] max_climb_deg would not read back as {climb} "
                               "in the learned file; nothing written")
    return write_text_atomic(out, text, command)


def measured_estimates(robot: Robot, measured: Any) -> Estimates:
    """``proleg sim --measure-matrix``'s ``MeasuredMatrix`` as the statistics a learned file is
    written from: per allowed transition its samples, their mean and sample variance (Δx only:
    the plant moves along x)."""
    from .estimate import Component

    t = robot.transitions
    src, dst = t.src, t.dst
    n = np.asarray(measured.samples)[src, dst].astype(np.int64)
    mean = np.where(n >= 1, np.asarray(measured.matrix_mm, dtype=float)[src, dst], np.nan)
    std = np.asarray(measured.std_mm, dtype=float)[src, dst]
    with np.errstate(divide="ignore", invalid="ignore"):
        var = np.where(n >= 2, std ** 2 * n / np.maximum(n - 1, 1), np.nan)  # np.std's ddof=0 → ddof=1
    took = np.where(n >= 1, np.asarray(measured.duration_s, dtype=float)[src, dst], np.nan)
    return Estimates(t, 0.95, 2, {"dx": Component(n, mean, var, np.full(len(n), np.nan))}, took)


def write_measured_robot(robot: Robot, measured: Any, out: str | Path) -> Path:
    """Write ``robot``'s file with the matrix ``proleg sim --measure-matrix`` measured (mm) as
    its ``[transitions]``, as ``write_learned_robot`` writes a learned one: the old table kept
    below in comments, a transition the simulated body did not make keeping its old value, or
    ``"x"`` where the old matrix was unmeasured (no value to keep), named in a comment; nothing
    written unless the file reads back."""
    header = [
        f"# [transitions] measured by proleg sim --measure-matrix ({{when}}) on the physical plant, "
        f"{int(np.asarray(measured.samples).sum())} samples; friction {'/'.join(measured.mechanisms)} "
        f"({measured.mechanism_source}).",
        "# matrix: mean Δx per transition in {units} (an idealised drive, true ψ); var_dx: sample variances;",
        "# n_trials: samples per transition. The simulated body, not the robot: learn it on the robot "
        "(proleg learn) to replace it.",
    ]
    est = measured_estimates(robot, measured)
    # an unmeasured file's 0 is no value to keep: a transition the body did not make is "x", as
    # learning writes one it left out (kept at 0, a gait went through a state the body cannot hold)
    left_out = ({int(e): Left("not_made", "not made on the simulated body") for e in np.flatnonzero(est.n == 0)}
                if robot.unmeasured else None)
    return write_learned_robot(robot, est, out, units="mm", header=header, command="sim --measure-matrix",
                               left_out=left_out)


def climb_for_new_gaits(robot: Robot) -> ClimbLimit | None:
    """``[control] max_climb_deg`` for the learned file when the robot's gives per-gait lists,
    else None. A list names the previous matrix's built-in gaits, gait 0 first; the learned
    matrix may rank other gaits first, so every gait takes the smallest of its way's list, as
    the gaits past a list already do (docs/robot-file.md)."""
    climb = robot.control.max_climb_deg
    if climb is None or not (climb.plus_x_gaits or climb.minus_x_gaits):
        return None
    return ClimbLimit(climb.plus_x, climb.minus_x)


def _set_control_key(lines: list[str], key: str, value: str, path: str | Path, why: str) -> list[str]:
    """The lines with ``[control]``'s one-line ``key = ...`` set to ``value``, the old line kept
    above it commented out, saying why. A key given another way (a dotted key, its own table)
    cannot be replaced as text: ``LearnedFileError``, nothing written."""
    span = _section_span(lines, "control")
    if span is not None:
        a, b = span
        for i in range(a + 1, b):
            if lines[i].split("=")[0].strip() == key:
                return lines[:i] + [f"# {lines[i].strip()}", f"{key} = {value}   # {why}"] + lines[i + 1:]
    raise LearnedFileError(f"learn: {path}: [control] {key} names gaits of the previous matrix and must change "
                           f"with it; give it on one line in [control] ({key} = ...) so that learn can replace "
                           "it; nothing written")


def _drop_plant_key(lines: list[str], key: str, why: str) -> list[str]:
    """The lines with ``[plant]``'s ``key = ...`` commented out, saying why."""
    span = _section_span(lines, "plant")
    if span is None:
        return lines
    a, b = span
    out = list(lines)
    for i in range(a + 1, b):
        if out[i].split("=")[0].strip() == key:
            out[i] = f"# {out[i].strip()}   # {why}"
    return out


def _check_loads(doc: dict, out: Path, source: str | Path) -> Robot:
    """The learned file (``doc``, its TOML read back) must load as a robot file, as it would
    from ``out`` (its CSVs and other paths relative to where it is written): nothing is
    written otherwise. Returns it loaded."""
    from ..robot import robot_from_dict

    try:
        return robot_from_dict(doc, out)
    except ProlegError as e:
        raise LearnedFileError(f"learn: the learned file from {source} would not load ({e}); nothing written") from None


def _replace_transitions(lines: list[str], new: list[str]) -> str:
    """The file's lines with ``[transitions]`` replaced by ``new``, the old table kept below
    it commented out (``new`` appended when the file has no such table)."""
    span = _section_span(lines, "transitions")
    if span is None:
        body = lines + [""] + new
    else:
        a, b = span
        old = lines[a:b]
        while old and not old[-1].strip():
            old.pop()
        kept = ["", "# previous [transitions] (before learning):"] + ["# " + ln if ln.strip() else "#" for ln in old] + [""]
        body = lines[:a] + new + kept + lines[b:]
    return "\n".join(body) + "\n"


def _check_learned(source: str, text: str, new: list[str], path: str | Path,
                   control_changed: tuple[str, ...] = ()) -> dict:
    """``text`` must be valid TOML whose ``[transitions]`` is ``new`` and whose every other
    table is as in ``source`` (but ``[control]``'s keys ``control_changed``, checked by the
    caller); returns it read back."""
    try:
        before, after = tomllib.loads(source), tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise LearnedFileError(f"learn: the learned file from {path} would not be valid TOML ({e}); "
                               "nothing written") from None
    before["transitions"] = tomllib.loads("\n".join(new))["transitions"]
    for key in control_changed:
        if key in after.get("control", {}):
            before["control"][key] = after["control"][key]
    if _canonical(before, "step_mm") != _canonical(after, "step_mm"):  # step_mm may go with the unit
        raise LearnedFileError(f"learn: cannot find where {path}'s [transitions] table ends to replace it "
                               "(nothing written); give it its own [transitions] header line")
    return after


def _canonical(doc: dict, *plant_keys_left_out: str) -> str:
    plant = {k: v for k, v in doc.get("plant", {}).items() if k not in plant_keys_left_out}
    doc = {**doc, "plant": plant} if "plant" in doc else doc
    return json.dumps(doc, sort_keys=True, default=str)  # NaN == NaN here, unlike in the dicts


def read_learned(path: str | Path) -> dict[str, np.ndarray]:
    """The learned statistics of a file written by ``write_learned_robot`` (commented or as
    keys): key → n×n array with NaN where forbidden or unknown."""
    text = Path(path).read_text(encoding="utf-8")
    commented = "\n".join(ln[len(PREFIX):] for ln in text.splitlines() if ln.startswith(PREFIX))
    doc = tomllib.loads(commented) if commented else tomllib.loads(text).get("transitions", {})
    out = {}
    for key in ("n_trials",) + tuple(k for k, _c, _w in STAT_KEYS):
        if key in doc:
            out[key] = np.array([[np.nan if v == "x" else float(v) for v in row] for row in doc[key]])
    return out
