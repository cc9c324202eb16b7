"""A robot file's [transitions]: the reward matrix inline or in an external CSV (read by
``robot_transitions_csv``), per-transition durations, the planar statistics of a learned file,
the forbidden-transition marks, an unmeasured matrix's allowed transitions. Every
problem is a RobotFileError naming the file, the field and what was expected
(``transitions_section``, called by ``proleg.robot.robot_from_dict``)."""

from __future__ import annotations

import logging
import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from . import states
from .errors import RobotFileError
from .robot_entries import (DURATION_RANGE, FORBIDDEN, MAX_DURATION_S, MAX_ENTRY, MAX_TRIALS, MAX_VARIANCE,
                            MIN_DURATION_S, in_range, is_duration, is_number, state_ref)
from .robot_fields import Fields, toml_text
from .robot_transitions_csv import read_csv
from .transitions import PLANAR_FIELDS, PlanarRewards, TransitionTable

log = logging.getLogger(__name__)



#: ``matrix = "unmeasured"``: a robot whose rewards are not known yet (every allowed transition
#: 0, to be measured by ``proleg learn`` or ``proleg sim --measure-matrix``), the transitions it
#: can make given by ``allow`` (one of ``ALLOW_RULES``) instead of written out: a 256-state
#: eight-limb robot's matrix has 65,280 entries.
UNMEASURED = "unmeasured"
#: Where an unmeasured robot's matrix comes from, as the messages that meet one say it ("learn
#: the matrix " + this): the commands, ready to run but for ROBOT and PORT.
HOW_TO_MEASURE = ("on the robot (proleg learn ROBOT --port PORT --source tracker --log TRIALS.jsonl --out "
                  "LEARNED.toml, or --source manual to give each trial by hand) or on the simulated body (proleg "
                  "learn ROBOT --sim --log TRIALS.jsonl --out LEARNED.toml, or proleg sim ROBOT --measure-matrix "
                  "--out MEASURED.toml)")
#: ``allow``: one-level (a step moves one limb by one level: the coils driven one at a time,
#: a multi-level pad passing through its middle levels), one-limb (one limb, by any number of
#: levels), any (every pair of different states).
ALLOW_RULES = ("one-level", "one-limb", "any")
#: The most transitions an unmeasured table may allow (``any`` on 2,048 states is 4.2 million).
MAX_UNMEASURED_EDGES = 1 << 22

#: What a matrix entry counts: steps (× ``[plant] step_mm`` on the table plant) or a length.
TRANSITION_UNITS = ("steps", "mm", "cm", "m")
#: Millimetres per entry for the length units.
UNIT_MM = {"mm": 1.0, "cm": 10.0, "m": 1000.0}


def transitions_section(path: Path, value: Any, levels: tuple[int, ...],
                        names: Sequence[str] = ()) -> tuple[TransitionTable, str]:
    """``[transitions]`` (``names``: the limbs', for an error about a state label's digit)."""
    f = Fields(
        path, "transitions", value,
        {"matrix", "file", "forbidden", "durations_s", "default_duration_s", "units", "states", "n_trials",
         "allow", *PLANAR_FIELDS},
    )
    unmeasured = is_unmeasured(value)
    # a misspelt "unmeasured" beside allow is the matrix's mistake: _matrix names it below
    if f.has("allow") and not unmeasured and not isinstance(value.get("matrix"), str):
        f.fail("allow", f'matrix = "{UNMEASURED}" beside it (allow says which transitions an unmeasured robot '
                        "can make; a matrix or a CSV says it by its \"x\" marks or rows)")
    # an unmeasured table has no steps to count: what learning measures is a length, by hand with a
    # ruler too (--source manual asked for "Δx [steps]" of such a robot)
    units = f.string("units", "mm" if unmeasured else "steps")
    if units not in TRANSITION_UNITS:
        f.fail("units", f"one of {', '.join(repr(u) for u in TRANSITION_UNITS)} (steps: × [plant] step_mm)", units)
    n = states.state_count(levels)
    if f.has("matrix") == f.has("file"):
        raise RobotFileError(f"{path}: transitions: expected exactly one of 'matrix' or 'file'")
    if f.has("states"):
        expected = [states.label(i, levels) for i in range(n)]
        if value["states"] != expected:
            f.fail("states", f"the state order {expected}", value["states"])

    if unmeasured:
        for key in ("durations_s", "n_trials", *PLANAR_FIELDS):
            if f.has(key):
                f.fail(key, f'no {key} beside matrix = "{UNMEASURED}": it has no entries for them to go with '
                            + ("(default_duration_s gives every transition a duration)" if key == "durations_s"
                               else "(proleg learn writes them with the learned matrix)"))
        rule = f.string("allow", "any")
        if rule not in ALLOW_RULES:
            f.fail("allow", f"one of {', '.join(repr(r) for r in ALLOW_RULES)}", rule)
        src, dst = _allowed_by_rule(path, rule, levels)
        src, dst = _without_forbidden(path, value.get("forbidden", []), levels, src, dst, names, rule)
        rew, dur, planar = np.zeros(len(src)), None, None
    elif f.has("matrix"):
        reward, allowed = _matrix(path, value["matrix"], n)
        src, dst = np.nonzero(allowed)
        rew = reward[src, dst]
        dur_matrix = _durations_matrix(path, value.get("durations_s"), n, allowed) if f.has("durations_s") else None
        dur = None if dur_matrix is None else dur_matrix[src, dst]
        planar = _planar(path, value, n, allowed)
    else:
        if f.has("durations_s"):
            f.fail("durations_s", "durations in the CSV's 4th column when the table is a file")
        for key in (*PLANAR_FIELDS, "n_trials"):
            if f.has(key):
                f.fail(key, "an inline 'matrix' (planar statistics are not read from a CSV table yet)")
        planar = None
        src, dst, rew, dur = read_csv(path, f.string("file"), levels, names)

    if f.has("forbidden") and not unmeasured:
        csv_file = None if f.has("matrix") else value["file"]
        _check_forbidden(path, value["forbidden"], levels, src, dst, rew, csv_file, names)

    if f.has("default_duration_s"):
        default = f.number("default_duration_s", None, MIN_DURATION_S, MAX_DURATION_S)
        if dur is None:
            dur = np.full(len(src), default)
        else:
            dur = np.where(np.isnan(dur), default, dur)
    if dur is not None and np.isnan(dur).any():
        raise RobotFileError(
            f"{path}: transitions: some allowed transitions have no duration (give them, or set default_duration_s)"
        )
    return TransitionTable.from_edges(levels, src, dst, rew, dur, planar), units


def _planar(path: Path, value: dict, n: int, allowed: np.ndarray) -> PlanarRewards | None:
    """dy, dtheta_deg (means) and var_dx, var_dy, var_dtheta_deg (variances, >= 0): n × n like
    the matrix, 'x' exactly where the matrix forbids a transition, the diagonal ignored.
    ``nan`` marks an allowed transition not measured (a learned file, ``proleg learn``): for
    gait selection a mean not measured counts as 0 and a variance not measured as the
    largest one measured for that key (an unknown transition is not taken for a sure one;
    0 when none is measured)."""
    given = {}
    src, dst = np.nonzero(allowed)
    for key in PLANAR_FIELDS:
        if key in value:
            variance = key.startswith("var_")
            m = _same_shape_matrix(path, f"transitions.{key}", value[key], n, allowed,
                                   "a variance" if variance else "a number", 0.0 if variance else -MAX_ENTRY,
                                   MAX_VARIANCE if variance else MAX_ENTRY, allow_nan=True)
            v = m[src, dst]
            known = v[~np.isnan(v)]
            fill = float(known.max()) if key.startswith("var_") and len(known) else 0.0
            given[key] = np.where(np.isnan(v), fill, v)
    return PlanarRewards(**given) if given else None


def n_trials_section(path: Path, value: dict, n: int, allowed: np.ndarray) -> np.ndarray | None:
    """``n_trials`` (a learned file): whole numbers >= 0 like the matrix, 'x' where forbidden."""
    if "n_trials" not in value:
        return None
    m = _same_shape_matrix(path, "transitions.n_trials", value["n_trials"], n, allowed, "a whole number of trials",
                           0, MAX_TRIALS, whole=True)
    src, dst = np.nonzero(allowed)
    return m[src, dst].astype(np.int64)


def _square(where: str, rows: Any, n: int, rows_are: str = "like the matrix") -> list[list[Any]]:
    """``rows`` checked to be n lists of n entries (RobotFileError naming the row otherwise)."""
    if not isinstance(rows, list) or len(rows) != n:
        got = len(rows) if isinstance(rows, list) else type(rows).__name__
        raise RobotFileError(f"{where}: expected {n} rows {rows_are}, got {got}")
    for a, row in enumerate(rows):
        if not isinstance(row, list) or len(row) != n:
            got = len(row) if isinstance(row, list) else type(row).__name__
            raise RobotFileError(f"{where}: row {a + 1}: expected {n} entries, got {got}")
    return rows


def _same_shape_matrix(path: Path, name: str, rows: Any, n: int, allowed: np.ndarray, what: str, lo: float,
                       hi: float, *, allow_nan: bool = False, whole: bool = False) -> np.ndarray:
    """An n × n matrix of ``what`` in [lo, hi] where ``allowed``, 'x' elsewhere (nan, when
    ``allow_nan``: not measured); ``whole``: whole numbers only."""
    where = f"{path}: {name}"
    expected = f"{what} in [{lo:g}, {hi:g}]"
    out = np.full((n, n), np.nan)
    for a, row in enumerate(_square(where, rows, n)):
        for b, v in enumerate(row):
            if a == b:
                continue  # the diagonal is not a transition
            cell = f"{where}[{a + 1}][{b + 1}]"
            if v == FORBIDDEN:
                if allowed[a, b]:
                    raise RobotFileError(f"{cell}: transition is allowed in the matrix, expected {expected}, got 'x'")
                continue
            unknown = allow_nan and isinstance(v, float) and math.isnan(v)
            if not unknown and (not in_range(v, lo, hi) or (whole and not float(v).is_integer())):
                raise RobotFileError(f"{cell}: expected {expected} or 'x', got {toml_text(v)}")
            if not allowed[a, b]:
                raise RobotFileError(f"{cell}: transition is forbidden in the matrix, expected 'x', got {toml_text(v)}")
            out[a, b] = float(v)
    return out


def is_unmeasured(value: Any) -> bool:
    """``[transitions]`` says ``matrix = "unmeasured"``."""
    return isinstance(value, dict) and value.get("matrix") == UNMEASURED


def allowed_count(rule: str, levels: tuple[int, ...]) -> int:
    """How many transitions ``allow = rule`` lets a robot of these limbs' levels make."""
    n = states.state_count(levels)
    if rule == "any":
        return n * (n - 1)
    if rule == "one-limb":
        return sum(n * (k - 1) for k in levels)                   # every other level of one limb
    return sum(n * 2 * (k - 1) // k for k in levels)              # one level up or down (one at the ends)


def _allowed_by_rule(path: Path, rule: str, levels: tuple[int, ...]) -> tuple[np.ndarray, np.ndarray]:
    """The (from, to) state indices ``allow = rule`` lets an unmeasured robot make, in the
    table's order (by from, then to)."""
    n = states.state_count(levels)
    place = states.place_values(levels)
    edges = allowed_count(rule, levels)
    if edges > MAX_UNMEASURED_EDGES:
        raise RobotFileError(
            f"{path}: transitions.allow: {rule!r} lets the robot's {n:,} states make {edges:,} transitions, more "
            f"than the {MAX_UNMEASURED_EDGES:,} an unmeasured table may hold; allow \"one-level\" (a step moves one "
            "limb by one level), or give the table as a CSV file")
    idx = np.arange(n)
    if rule == "any":
        src = np.repeat(idx, n)
        dst = np.tile(idx, n)
        keep = src != dst
        return src[keep], dst[keep]
    src_parts, dst_parts = [], []
    for i, k in enumerate(levels):
        level = (idx // place[i]) % k
        for d in range(1, 2 if rule == "one-level" else k):
            for sign in (1, -1):
                to = level + sign * d
                ok = (to >= 0) & (to < k)
                src_parts.append(idx[ok])
                dst_parts.append(idx[ok] + sign * d * place[i])
    src = np.concatenate(src_parts)
    dst = np.concatenate(dst_parts)
    order = np.lexsort((dst, src))
    return src[order], dst[order]


def _forbidden_marks(path: Path, marks: Any, levels: tuple[int, ...], names: Sequence[str]
                     ) -> list[tuple[int, str, int, int]]:
    """``forbidden``'s marks read: ``(k, mark, from, to)`` each, ``k`` counted from 1 in
    messages as the matrix's rows; a RobotFileError naming the mark otherwise."""
    where = f"{path}: transitions.forbidden"
    if not isinstance(marks, list) or not all(isinstance(m, str) for m in marks):
        raise RobotFileError(f"{where}: expected a list of transitions like \"01->11\"")
    n = states.state_count(levels)
    out = []
    for k, mark in enumerate(marks, 1):
        parts = [p.strip() for p in mark.split("->")]
        if len(parts) != 2:
            raise RobotFileError(f"{where}[{k}]: expected FROM->TO, got {mark!r}")
        a = state_ref(parts[0], levels, n, f"{where}[{k}]", names)
        b = state_ref(parts[1], levels, n, f"{where}[{k}]", names)
        if a == b:
            raise RobotFileError(f"{where}[{k}]: {mark} is a state to itself, never a transition (expected FROM->TO "
                                 "of two different states)")
        out.append((k, mark, a, b))
    return out


def _without_forbidden(path: Path, marks: Any, levels: tuple[int, ...], src: np.ndarray, dst: np.ndarray,
                       names: Sequence[str], rule: str) -> tuple[np.ndarray, np.ndarray]:
    """An unmeasured table's ``forbidden`` marks take those transitions out of what ``allow``
    lets it make (with a matrix or a CSV they are a check on the table instead)."""
    n = states.state_count(levels)
    marked = _forbidden_marks(path, marks, levels, names)
    out = {a * n + b for _k, _mark, a, b in marked}
    if not out:
        return src, dst
    keys = src * n + dst
    allowed = set(keys.tolist())
    for k, mark, a, b in marked:  # a typo's mark (000->020 for 000->010) would take nothing out unseen
        if a * n + b not in allowed:
            log.warning("warning: %s: transitions.forbidden[%d]: %s is not a transition allow = %r lets the robot "
                        "make, so the mark takes nothing out; check it names the transition you meant",
                        path, k, mark, rule)
    keep = ~np.isin(keys, np.fromiter(out, dtype=np.int64))
    return src[keep], dst[keep]


def _check_forbidden(path: Path, marks: Any, levels: tuple[int, ...], src, dst, rewards, csv_file: str | None,
                     names: Sequence[str] = ()) -> None:
    """``forbidden = ["01->11", ...]`` states what the robot cannot do; the table must agree:
    the matrix has "x" there, the CSV ``csv_file`` (None: the table is the matrix) no row."""
    where = f"{path}: transitions.forbidden"
    given = dict(zip(zip(np.asarray(src).tolist(), np.asarray(dst).tolist()), np.asarray(rewards).tolist()))
    for k, mark, a, b in _forbidden_marks(path, marks, levels, names):
        if (a, b) in given:
            there, fix = ((f"transitions.matrix[{a + 1}][{b + 1}]", 'write "x" there') if csv_file is None
                          else (f"the table {csv_file}", "delete its row"))
            raise RobotFileError(
                f"{where}[{k}]: {mark} is marked forbidden, but {there} gives it a reward ({given[a, b]:g}): "
                "forbidden lists the transitions the robot cannot make, to check that the table allows none "
                f"of them; {fix}, or drop the mark"
            )


def _matrix(path: Path, rows: Any, n: int) -> tuple[np.ndarray, np.ndarray]:
    where = f"{path}: transitions.matrix"
    if isinstance(rows, str):
        raise RobotFileError(f"{where}: expected {n} rows of {n} entries, or \"{UNMEASURED}\" (rewards not known "
                             f"yet: learn or measure them), got {toml_text(rows)}")
    reward = np.zeros((n, n))
    allowed = np.zeros((n, n), dtype=bool)
    for a, row in enumerate(_square(where, rows, n, f"(one per state, {n} = product of limb levels)")):
        for b, v in enumerate(row):
            if a == b:
                if not (v == FORBIDDEN or is_number(v)):
                    raise RobotFileError(f"{where}[{a + 1}][{b + 1}]: expected a number or 'x', got {toml_text(v)}")
                continue  # the diagonal is not a transition
            if v == FORBIDDEN:
                continue
            if not in_range(v, -MAX_ENTRY, MAX_ENTRY):
                raise RobotFileError(
                    f"{where}[{a + 1}][{b + 1}]: expected a number in [{-MAX_ENTRY:g}, {MAX_ENTRY:g}] or 'x' "
                    f"(forbidden), got {toml_text(v)}"
                )
            reward[a, b] = float(v)
            allowed[a, b] = True
    return reward, allowed


def _durations_matrix(path: Path, rows: Any, n: int, allowed: np.ndarray) -> np.ndarray:
    where = f"{path}: transitions.durations_s"
    out = np.full((n, n), np.nan)
    for a, row in enumerate(_square(where, rows, n)):
        for b, v in enumerate(row):
            if a == b:
                continue
            if v == FORBIDDEN:
                if allowed[a, b]:
                    raise RobotFileError(
                        f"{where}[{a + 1}][{b + 1}]: transition is allowed in the matrix, expected a duration > 0"
                    )
                continue
            if not is_duration(v):
                raise RobotFileError(f"{where}[{a + 1}][{b + 1}]: expected a duration in {DURATION_RANGE} seconds "
                                     f"or 'x', got {toml_text(v)}")
            if not allowed[a, b]:
                raise RobotFileError(
                    f"{where}[{a + 1}][{b + 1}]: transition is forbidden in the matrix, expected 'x', got {toml_text(v)}"
                )
            out[a, b] = float(v)
    return out
