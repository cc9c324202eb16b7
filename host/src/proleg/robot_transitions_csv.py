"""A ``[transitions] file = "..."`` table: the reward matrix as a CSV of ``from,to,reward[,duration_s]``
rows beside the robot file (a first row that starts with no state is a header), read with
every problem a ``RobotFileError`` naming the file, the line and what was expected
(``read_csv``, called by ``robot_transitions.transitions_section``)."""

from __future__ import annotations

import csv
from collections.abc import Sequence
from pathlib import Path

from . import states
from .errors import RobotFileError
from .names import counted
from .paths import not_a_regular_file
from .robot_entries import DURATION_RANGE, MAX_ENTRY, in_range, is_duration, state_ref
from .typed import typed_float

#: A transition CSV larger than this is refused before it is read.
MAX_CSV_BYTES = 256 * 1024 * 1024


def read_csv(path: Path, name: str, levels: tuple[int, ...], names: Sequence[str] = ()):
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
    odd = not_a_regular_file(csv_path)
    if odd:
        raise RobotFileError(f"{path}: transitions.file: cannot open {csv_path}: {odd}")
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
    a = state_ref(cells[0], levels, n, f"{where}: from", names)
    b = state_ref(cells[1], levels, n, f"{where}: to", names)
    if a == b:
        raise RobotFileError(f"{where}: a transition from a state to itself is not a transition")
    try:
        r = typed_float(cells[2])
    except ValueError:
        raise RobotFileError(f"{where}: reward: expected a number, got {cells[2]!r}") from None
    if not in_range(r, -MAX_ENTRY, MAX_ENTRY):
        raise RobotFileError(f"{where}: reward: expected a number in [{-MAX_ENTRY:g}, {MAX_ENTRY:g}], "
                             f"got {cells[2]!r}")
    return a, b, r


def _csv_duration(text: str, where: str) -> float:
    try:
        d = typed_float(text)
    except ValueError:
        d = -1.0
    if not is_duration(d):
        raise RobotFileError(f"{where}: duration_s: expected a number in {DURATION_RANGE} seconds, got {text!r}")
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
