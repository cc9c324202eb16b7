"""A robot file's [transitions]: the reward matrix inline or in an external CSV, per-transition
durations, the planar statistics of a learned file, the forbidden-transition marks. Every
problem is a RobotFileError naming the file, the field and what was expected
(``transitions_section``, called by ``proleg.robot.robot_from_dict``)."""

from __future__ import annotations

import csv
import logging
import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from . import states
from .errors import RobotFileError
from .names import counted
from .robot_fields import Fields, toml_text
from .transitions import PLANAR_FIELDS, PlanarRewards, TransitionTable

log = logging.getLogger(__name__)

#: The mark of a forbidden transition in a matrix ("x").
FORBIDDEN = "x"
#: A transition CSV larger than this is refused before it is read.
MAX_CSV_BYTES = 256 * 1024 * 1024
#: The largest |entry| of the matrix, a CSV reward and the planar means, as ``[plant] true_matrix``:
#: a gait sums its entries, and 1e308 would overflow to inf and turn the gait search's answer.
MAX_ENTRY = 1e9
#: The largest planar variance (σ up to MAX_ENTRY) and the largest ``n_trials`` entry.
MAX_VARIANCE = MAX_ENTRY**2
MAX_TRIALS = 10**9
#: The longest duration of a transition (s), in ``durations_s``, a CSV's ``duration_s`` and
#: ``default_duration_s`` alike: a gait sums them, and 1e308 overflowed the sum (a traceback).
MAX_DURATION_S = 3600.0


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
    units = f.string("units", "steps")
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
        src, dst, rew, dur = _csv(path, f.string("file"), levels, names)

    if f.has("forbidden") and not unmeasured:
        csv_file = None if f.has("matrix") else value["file"]
        _check_forbidden(path, value["forbidden"], levels, src, dst, rew, csv_file, names)

    if f.has("default_duration_s"):
        default = f.number("default_duration_s", None, 0.0, MAX_DURATION_S, open_lo=True)
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
            if not unknown and (not _in_range(v, lo, hi) or (whole and not float(v).is_integer())):
                raise RobotFileError(f"{cell}: expected {expected} or 'x', got {toml_text(v)}")
            if not allowed[a, b]:
                raise RobotFileError(f"{cell}: transition is forbidden in the matrix, expected 'x', got {toml_text(v)}")
            out[a, b] = float(v)
    return out


def is_unmeasured(value: Any) -> bool:
    """``[transitions]`` says ``matrix = "unmeasured"``."""
    return isinstance(value, dict) and value.get("matrix") == UNMEASURED


def _allowed_by_rule(path: Path, rule: str, levels: tuple[int, ...]) -> tuple[np.ndarray, np.ndarray]:
    """The (from, to) state indices ``allow = rule`` lets an unmeasured robot make, in the
    table's order (by from, then to)."""
    n = states.state_count(levels)
    place = states.place_values(levels)
    if rule == "any":
        edges = n * (n - 1)
    elif rule == "one-limb":
        edges = sum(n * (k - 1) for k in levels)                  # every other level of one limb
    else:
        edges = sum(n * 2 * (k - 1) // k for k in levels)         # one level up or down (one at the ends)
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
        a = _state_ref(parts[0], levels, n, f"{where}[{k}]", names)
        b = _state_ref(parts[1], levels, n, f"{where}[{k}]", names)
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
                if not (v == FORBIDDEN or _is_number(v)):
                    raise RobotFileError(f"{where}[{a + 1}][{b + 1}]: expected a number or 'x', got {toml_text(v)}")
                continue  # the diagonal is not a transition
            if v == FORBIDDEN:
                continue
            if not _in_range(v, -MAX_ENTRY, MAX_ENTRY):
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
            if not _is_number(v) or not 0 < v <= MAX_DURATION_S:
                raise RobotFileError(f"{where}[{a + 1}][{b + 1}]: expected a duration in (0, {MAX_DURATION_S:g}] seconds "
                                     f"or 'x', got {toml_text(v)}")
            if not allowed[a, b]:
                raise RobotFileError(
                    f"{where}[{a + 1}][{b + 1}]: transition is forbidden in the matrix, expected 'x', got {toml_text(v)}"
                )
            out[a, b] = float(v)
    return out


def _csv(path: Path, name: str, levels: tuple[int, ...], names: Sequence[str] = ()):
    csv_path = (path.parent / name).resolve()
    n = states.state_count(levels)
    src: list[int] = []
    dst: list[int] = []
    rew: list[float] = []
    dur: list[float] = []
    seen: set[tuple[int, int]] = set()
    has_duration = None
    header: list[str] = []
    with _open_csv(path, csv_path) as fh:
        for lineno, cells in _csv_rows(fh, csv_path, header):
            where = f"{csv_path}:{lineno}"
            if len(cells) not in (3, 4):
                raise RobotFileError(f"{where}: expected from,to,reward[,duration_s], got {counted(len(cells), 'field')}")
            if header and len(cells) != len(header):
                raise RobotFileError(f"{where}: expected {len(header)} fields as the header names "
                                     f"({','.join(header)}), got {len(cells)}")
            if has_duration is None:
                has_duration = len(cells) == 4
            elif has_duration != (len(cells) == 4):
                raise RobotFileError(f"{where}: every row must have a duration, or none")
            a, b, r = _csv_transition(cells, levels, n, where, names)
            if (a, b) in seen:
                raise RobotFileError(f"{where}: transition {cells[0]} -> {cells[1]} is given twice")
            seen.add((a, b))
            src.append(a)
            dst.append(b)
            rew.append(r)
            if has_duration:
                dur.append(_csv_duration(cells[3], where))
    if not src:
        raise RobotFileError(f"{csv_path}: no transitions (expected rows from,to,reward)")
    return src, dst, rew, (dur if dur else None)


def _open_csv(path: Path, csv_path: Path):
    """The CSV as text (a leading BOM, as Excel writes, dropped), refused if too large."""
    try:
        size = csv_path.stat().st_size
        fh = csv_path.open(newline="", encoding="utf-8-sig")
    except OSError as e:
        raise RobotFileError(f"{path}: transitions.file: cannot open {csv_path}: {e.strerror}") from None
    if size > MAX_CSV_BYTES:
        fh.close()
        raise RobotFileError(f"{path}: transitions.file: {csv_path} has {size:,} bytes, expected at most {MAX_CSV_BYTES:,}")
    return fh


def _csv_transition(cells: list[str], levels: tuple[int, ...], n: int, where: str,
                    names: Sequence[str] = ()) -> tuple[int, int, float]:
    a = _state_ref(cells[0], levels, n, f"{where}: from", names)
    b = _state_ref(cells[1], levels, n, f"{where}: to", names)
    if a == b:
        raise RobotFileError(f"{where}: a transition from a state to itself is not a transition")
    try:
        r = float(cells[2])
    except ValueError:
        raise RobotFileError(f"{where}: reward: expected a number, got {cells[2]!r}") from None
    if not _in_range(r, -MAX_ENTRY, MAX_ENTRY):
        raise RobotFileError(f"{where}: reward: expected a number in [{-MAX_ENTRY:g}, {MAX_ENTRY:g}], "
                             f"got {cells[2]!r}")
    return a, b, r


def _csv_duration(text: str, where: str) -> float:
    try:
        d = float(text)
    except ValueError:
        d = -1.0
    if not 0 < d <= MAX_DURATION_S:
        raise RobotFileError(f"{where}: duration_s: expected a number in (0, {MAX_DURATION_S:g}] seconds, got {text!r}")
    return d


def _csv_rows(fh, csv_path: Path, header: list[str]):
    """(line, stripped cells) of each data row: ``line`` is the file line the row starts on
    (a quoted cell may span lines); blank rows and ``#`` comments are skipped, and the header
    (a first row that starts with no state) must be ``from,to,reward[,duration_s]``: its
    cells go to ``header``. csv.reader's errors (NUL bytes, a field over its size limit,
    bytes that are not UTF-8) are RobotFileError naming the line."""
    reader = csv.reader(fh)
    first = True
    while True:
        start = reader.line_num + 1
        try:
            row = next(reader)
        except StopIteration:
            return
        except csv.Error as e:
            raise RobotFileError(f"{csv_path}:{reader.line_num}: not a readable CSV row: {e}") from None
        except UnicodeDecodeError as e:
            raise RobotFileError(f"{csv_path}:{_first_non_utf8_line(csv_path)}: not UTF-8 text ({e.reason}); "
                                 "save it as UTF-8") from None
        if not row or row[0].lstrip().startswith("#"):
            continue
        cells = [c.strip() for c in row]
        if len(cells) == 1 and (sep := next((c for c in ";\t" if c in row[0]), None)):
            # a spreadsheet in another locale (';', with decimal commas) or a tab-separated export
            raise RobotFileError(f"{csv_path}:{start}: fields separated by {sep!r}, not commas: the table takes "
                                 f"{','.join(CSV_COLUMNS[:3])}[,{CSV_COLUMNS[3]}] separated by commas, with '.' "
                                 f"as the decimal point (export it as CSV with commas), got {row[0]!r}")
        if first and not _looks_like_a_state(cells[0]):  # the header: checked, not just skipped
            if cells not in (CSV_COLUMNS[:3], CSV_COLUMNS):
                raise RobotFileError(f"{csv_path}:{start}: expected the header {','.join(CSV_COLUMNS[:3])}"
                                     f"[,{CSV_COLUMNS[3]}] (in this order), got {','.join(cells)!r}")
            header.extend(cells)
            first = False
            continue
        first = False
        yield start, cells


#: A CSV transition table's columns, in order; the last is optional.
CSV_COLUMNS = ["from", "to", "reward", "duration_s"]


def _looks_like_a_state(cell: str) -> bool:
    """A state label (digits) or index (@N): a first row starting otherwise is a header."""
    return cell.startswith("@") or (cell.isascii() and cell.isdigit())


def _first_non_utf8_line(csv_path: Path) -> int:
    """The line of the first bytes that are not UTF-8 (the text reader decodes in chunks,
    so csv.reader's line count does not say)."""
    with csv_path.open("rb") as fh:
        for lineno, raw in enumerate(fh, start=1):
            try:
                raw.decode("utf-8")
            except UnicodeDecodeError:
                return lineno
    return 1


def _state_ref(text: str, levels: tuple[int, ...], n: int, where: str, names: Sequence[str] = ()) -> int:
    """A state in a CSV row or a forbidden mark: a label (one digit per limb), or an index
    written ``@N``. A string of digits of another length is an error, never an index: a label
    with a digit missing or one too many would otherwise name a different state."""
    L = len(levels)
    expected = f"{where}: expected a state label of {L} digits or a state index @0..@{n - 1}, got {text!r}"
    if text.startswith("@"):
        index = text[1:]
        if index.isascii() and index.isdigit() and int(index) < n:  # "¹" and "١" are digits too
            return int(index)
        raise RobotFileError(expected)
    if len(text) == L:
        try:
            return states.index(text, levels, names)
        except ValueError as e:
            raise RobotFileError(f"{expected} ({e})") from None
    if text.isascii() and text.isdigit():
        raise RobotFileError(f"{where}: {text!r} is not a state label of {L} digits (one per limb, e.g. "
                             f"{states.label(0, levels)}; a state index is written @0..@{n - 1})")
    raise RobotFileError(expected)


def _is_number(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def _in_range(v: Any, lo: float, hi: float) -> bool:
    return _is_number(v) and lo <= v <= hi
