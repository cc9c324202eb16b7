"""Robot files: what a lab writes down about its robot.

A robot file (TOML, see docs/ARCHITECTURE.md and robots/*.toml) names the limbs in label
order, their friction levels and critical angles ψ*, the actuators that drive them, the
transition reward matrix (inline, or an external CSV for large robots), optional
per-transition durations, the safety envelope and the control settings. ``load_robot``
checks every field and raises ``RobotFileError`` with the file, the field and what was
expected; it never clamps or guesses.
"""

from __future__ import annotations

import csv
import logging
import math
import re
import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from . import states
from .errors import RobotFileError
from .robot_plant import (PlantSection, coupling_warnings, default_plant_section, limb_friction, plant_section,
                          unreachable_levels)
from .transitions import PLANAR_FIELDS, PlanarRewards, TransitionTable

log = logging.getLogger(__name__)

NAME_RE = re.compile(r"^[a-z0-9][a-z0-9-]{0,14}$")
#: Robot names may be longer than the 15 characters the firmware reports (GET_INFO's
#: robot_name field, protocol ROBOT_NAME_LEN 16 with its NUL): the firmware keeps the full
#: name in ROM and sends the first 15 characters. Published robots have longer names
#: (issue 17); 63 keeps build directory names reasonable.
ROBOT_NAME_RE = re.compile(r"^[a-z0-9][a-z0-9-]{0,62}$")
FORBIDDEN = "x"
MAX_LIMBS = 8
MAX_ACTUATORS = 8
#: A robot file larger than this is refused before it is parsed (an inline matrix of
#: 1,024 states takes about 5 MB); a transition CSV larger than MAX_CSV_BYTES likewise.
MAX_FILE_BYTES = 16 * 1024 * 1024
MAX_CSV_BYTES = 256 * 1024 * 1024
#: Brackets and braces nested deeper than this are refused before parsing (a robot file
#: needs 3: a matrix row inside the matrix inside a table); tomllib recurses per level.
MAX_NESTING = 32
#: At most this many states (product of limb levels): 2^20, 16 binary limbs and more.
MAX_STATES = 1 << 20


@dataclass(frozen=True)
class ImuSpec:
    """Where a limb's IMU sits, as the robot file says (every part optional; the build
    fills in the rest, see proleg.firmware.placement): the board's I2C bus by name, the
    TCA9548A/PCA9548A multiplexer's address (0x70..0x77) and channel (0..7) when the IMU
    sits behind one, and the IMU's 7-bit address (0x68 or 0x69 for an MPU-6050)."""

    bus: str | None = None
    mux: int | None = None
    channel: int | None = None
    address: int | None = None


#: A multiplexer's 7-bit addresses (TCA9548A/PCA9548A: A2..A0 select 0x70..0x77) and channels.
MUX_ADDRESSES = range(0x70, 0x78)
MUX_CHANNELS = 8


@dataclass(frozen=True)
class Limb:
    name: str
    levels: int
    psi_star_deg: tuple[float, ...]
    hysteresis_deg: float
    actuator: str
    imu: ImuSpec | None = None  # None: placed automatically by the build
    #: friction mechanism: "D1"/"D2" or one material per level (None: the plant infers it)
    friction: str | tuple[str, ...] | None = None


@dataclass(frozen=True)
class Actuator:
    name: str
    channel: int


@dataclass(frozen=True)
class Safety:
    max_on_ms: int = 3000
    min_cooldown_ms: int = 800
    max_duty: float = 0.8
    state_timeout_ms: int = 8000
    link_watchdog_ms: int = 2000  # on by default: a host that goes away stops the robot (docs/safety.md)


@dataclass(frozen=True)
class Control:
    tick_hz: int = 1000
    drive_duty: float = 0.6
    hold_duty: float = 0.25
    debounce_ticks: int = 5
    hold_ms: int = 100
    hold_margin_deg: float = 4.0
    telemetry_hz: int = 50
    overrun_fault: int = 10  # consecutive ticks whose work overran the period: fault TICK_OVERRUN
    fallback: bool = True  # firmware switches to a build-time fallback gait when it loses an actuator


@dataclass(frozen=True, eq=False)
class Robot:
    name: str
    path: Path
    description: str
    limbs: tuple[Limb, ...]
    actuators: tuple[Actuator, ...]
    transitions: TransitionTable
    units: str
    safety: Safety
    control: Control
    plant: PlantSection | None = None  # the checked [plant] table (defaults when absent)
    n_trials: np.ndarray | None = None  # learned file: trials per allowed transition (aligned with transitions.src)
    library: Any = None  # [gaits]: the gait library the firmware carries (proleg.gait.library.LibrarySpec), or None

    def __post_init__(self) -> None:
        if self.plant is None:
            object.__setattr__(self, "plant", default_plant_section(len(self.actuators), len(self.limbs)))

    @property
    def levels(self) -> tuple[int, ...]:
        return tuple(limb.levels for limb in self.limbs)

    @property
    def n_states(self) -> int:
        return self.transitions.n_states

    def actuator(self, name: str) -> Actuator:
        return next(a for a in self.actuators if a.name == name)


# ---------------------------------------------------------------------------------------
# Field checking: every helper raises RobotFileError naming file and field.


class _Fields:
    """Reads one TOML table, checking types and refusing keys it does not know."""

    def __init__(self, path: Path, where: str, table: Any, known: set[str], sep: str = "."):
        self.path, self.where, self.sep = path, where, sep
        if not isinstance(table, dict):
            self.fail("", "a table")
        unknown = sorted(set(table) - known)
        if unknown:
            raise RobotFileError(
                f"{path}: {where}: unknown key {unknown[0]!r} (expected one of: {', '.join(sorted(known))})"
            )
        self.table = table

    def fail(self, key: str, expected: str, got: Any = None) -> None:
        name = f"{self.where}{self.sep}{key}" if key else self.where
        shown = "" if got is None else f", got {got!r}"
        raise RobotFileError(f"{self.path}: {name}: expected {expected}{shown}")

    def has(self, key: str) -> bool:
        return key in self.table

    def string(self, key: str, default: str | None = None) -> str:
        if key not in self.table:
            if default is None:
                self.fail(key, "a string (required)")
            return default
        v = self.table[key]
        if not isinstance(v, str):
            self.fail(key, "a string", v)
        return v

    def integer(self, key: str, default: int, lo: int, hi: int) -> int:
        v = self.table.get(key, default)
        if isinstance(v, bool) or not isinstance(v, int) or not lo <= v <= hi:
            self.fail(key, f"an integer in {lo}..{hi}", v)
        return v

    def number(self, key: str, default: float | None, lo: float, hi: float, *, open_lo: bool = False) -> float:
        if key not in self.table and default is None:
            self.fail(key, "a number (required)")
        v = self.table.get(key, default)
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
            self.fail(key, "a number", v)
        if (v <= lo if open_lo else v < lo) or v > hi:
            self.fail(key, f"a number in {'(' if open_lo else '['}{lo}, {hi}]", v)
        return float(v)


def load_robot(path: str | Path) -> Robot:
    """Read and check a robot file; RobotFileError says what is wrong and where."""
    path = Path(path)
    text = _read_text(path, MAX_FILE_BYTES, "robot file")
    depth = nesting_depth(text)
    if depth > MAX_NESTING:
        raise RobotFileError(f"{path}: brackets nested {depth} deep, expected at most {MAX_NESTING}")
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise RobotFileError(f"{path}: not valid TOML: {e}") from None
    except RecursionError:  # nesting_depth missed a construct: still one line, never a traceback
        raise RobotFileError(f"{path}: not valid TOML: nested too deeply") from None
    return robot_from_dict(doc, path)


def _read_text(path: Path, limit: int, what: str) -> str:
    try:
        size = path.stat().st_size
        if size > limit:
            raise RobotFileError(f"{path}: {what} of {size:,} bytes, expected at most {limit:,}")
        with path.open("rb") as fh:
            data = fh.read(limit + 1)  # the file may have grown since stat
        if len(data) > limit:
            raise RobotFileError(f"{path}: {what} larger than {limit:,} bytes")
        return data.decode("utf-8")
    except FileNotFoundError:
        raise RobotFileError(f"{path}: no such {what}") from None
    except (OSError, UnicodeDecodeError) as e:
        raise RobotFileError(f"{path}: cannot read: {e}") from None


_STRINGS_AND_COMMENTS = re.compile(r'"""[\s\S]*?"""|\'\'\'[\s\S]*?\'\'\'|"(?:[^"\\\n]|\\.)*"|\'[^\'\n]*\'|#[^\n]*')


def nesting_depth(text: str) -> int:
    """The deepest nesting of [ ] and { } outside strings and comments (no recursion)."""
    code = _STRINGS_AND_COMMENTS.sub("", text).encode("utf-8")
    b = np.frombuffer(code, dtype=np.uint8)
    step = np.zeros(len(b), dtype=np.int64)
    step[(b == ord("[")) | (b == ord("{"))] = 1
    step[(b == ord("]")) | (b == ord("}"))] = -1
    return int(np.cumsum(step).max(initial=0))


def robot_from_dict(doc: dict[str, Any], path: Path) -> Robot:
    top = _Fields(path, "robot file", doc, {"robot", "limb", "actuator", "transitions", "safety", "control", "plant",
                                            "gaits"})
    for key in ("robot", "limb", "actuator", "transitions"):
        if not top.has(key):
            raise RobotFileError(f"{path}: missing [{key}]{' entries' if key in ('limb', 'actuator') else ''}")

    head = _Fields(path, "robot", doc["robot"], {"name", "description"})
    name = head.string("name")
    if not ROBOT_NAME_RE.match(name):
        head.fail("name", "lowercase letters, digits and '-', 1 to 63 characters", name)
    description = head.string("description", "")

    actuators = _actuators(path, doc["actuator"])
    limbs = _limbs(path, doc["limb"], {a.name for a in actuators})
    used = {limb.actuator for limb in limbs}
    for a in actuators:
        if a.name not in used:
            raise RobotFileError(f"{path}: actuator {a.name!r} drives no limb (name it in a [[limb]] actuator field)")

    levels = tuple(limb.levels for limb in limbs)
    n = states.state_count(levels)
    if n > MAX_STATES:
        raise RobotFileError(
            f"{path}: limb: {n:,} states (the product of the limbs' levels {levels}), expected at most {MAX_STATES:,}"
        )
    table, units = _transitions(path, doc["transitions"], levels)
    n_trials = None
    if isinstance(doc["transitions"], dict) and "n_trials" in doc["transitions"]:
        allowed = np.zeros((table.n_states, table.n_states), dtype=bool)
        allowed[table.src, table.dst] = True
        n_trials = _n_trials(path, doc["transitions"], table.n_states, allowed)

    safety = _safety(path, doc.get("safety", {}))
    control = _control(path, doc.get("control", {}), safety)
    act_index = {a.name: j for j, a in enumerate(actuators)}
    plant = plant_section(path, doc.get("plant", {}), [a.name for a in actuators], len(limbs), table.n_states,
                          [act_index[limb.actuator] for limb in limbs], units)
    for line in unreachable_levels(path, list(limbs), [a.name for a in actuators], plant):
        log.warning("warning: %s", line)
    for line in coupling_warnings(path, list(limbs), [a.name for a in actuators], plant, table, control.hold_margin_deg):
        log.warning("warning: %s", line)
    library = None
    if "gaits" in doc:
        from .gait.library import library_from_robot_file

        library = library_from_robot_file(path, doc["gaits"])
    return Robot(name, path, description, limbs, actuators, table, units, safety, control, plant, n_trials, library)


def _array_of_tables(path: Path, value: Any, key: str) -> list[dict]:
    if not isinstance(value, list) or not value or not all(isinstance(t, dict) for t in value):
        raise RobotFileError(f"{path}: {key}: expected one or more [[{key}]] tables")
    return value


def _entry(kind: str, i: int, table: Any) -> str:
    """How an error names the ``i``-th (0-based) ``[[kind]]`` table: by its name when it has
    one, e.g. ``limb 'left'``, else by its place counted from 1, ``limb #2``."""
    name = table.get("name") if isinstance(table, dict) else None
    return f"{kind} {name!r}" if isinstance(name, str) and name else f"{kind} #{i + 1}"


def _actuators(path: Path, value: Any) -> tuple[Actuator, ...]:
    tables = _array_of_tables(path, value, "actuator")
    if len(tables) > MAX_ACTUATORS:
        raise RobotFileError(f"{path}: actuator: at most {MAX_ACTUATORS} actuators, got {len(tables)}")
    out: list[Actuator] = []
    for i, t in enumerate(tables):
        f = _Fields(path, _entry("actuator", i, t), t, {"name", "channel"}, sep=": ")
        name = f.string("name")
        if not NAME_RE.match(name):
            f.fail("name", "lowercase letters, digits and '-', 1 to 15 characters", name)
        if any(a.name == name for a in out):
            f.fail("name", "a name no other actuator has", name)
        channel = f.integer("channel", i, 0, MAX_ACTUATORS - 1)
        if any(a.channel == channel for a in out):
            f.fail("channel", "a channel no other actuator uses", channel)
        out.append(Actuator(name, channel))
    return tuple(out)


def _limbs(path: Path, value: Any, actuator_names: set[str]) -> tuple[Limb, ...]:
    tables = _array_of_tables(path, value, "limb")
    if len(tables) > MAX_LIMBS:
        raise RobotFileError(f"{path}: limb: at most {MAX_LIMBS} limbs, got {len(tables)}")
    out: list[Limb] = []
    for i, t in enumerate(tables):
        f = _Fields(path, _entry("limb", i, t), t, {"name", "levels", "psi_star_deg", "hysteresis_deg", "actuator", "imu", "friction"},
                    sep=": ")
        name = f.string("name")
        if any(limb.name == name for limb in out):
            f.fail("name", "a name no other limb has (duplicate limb)", name)
        levels = f.integer("levels", 2, 2, 10)
        psi = t.get("psi_star_deg")
        if isinstance(psi, (int, float)) and not isinstance(psi, bool):
            psi = [psi]
        if (
            not isinstance(psi, list)
            or len(psi) != levels - 1
            or not all(isinstance(p, (int, float)) and not isinstance(p, bool) for p in psi)
        ):
            f.fail("psi_star_deg", f"a list of {levels - 1} critical angle(s) in degrees (levels - 1)", psi)
        psi_t = tuple(float(p) for p in psi)
        if not all(-90.0 < p < 90.0 for p in psi_t):
            f.fail("psi_star_deg", "angles strictly between -90 and 90 degrees", psi)
        if any(b <= a for a, b in zip(psi_t, psi_t[1:])):
            f.fail("psi_star_deg", "strictly increasing angles", psi)
        hyst = f.number("hysteresis_deg", 2.0, 0.0, 20.0)
        gaps = [b - a for a, b in zip(psi_t, psi_t[1:])]
        if gaps and hyst >= min(gaps):
            f.fail("hysteresis_deg", f"less than the smallest gap between critical angles ({min(gaps)})", hyst)
        actuator = f.string("actuator")
        if actuator not in actuator_names:
            f.fail("actuator", f"the name of an [[actuator]] ({', '.join(sorted(actuator_names))})", actuator)
        imu = _imu_spec(path, f"{f.where}: imu", t["imu"]) if "imu" in t else None
        friction = limb_friction(path, f.where, t["friction"], levels) if "friction" in t else None
        out.append(Limb(name, levels, psi_t, hyst, actuator, imu, friction))
    declared = [limb.friction is not None for limb in out]
    if any(declared) and not all(declared):
        missing = next(limb.name for limb in out if limb.friction is None)
        raise RobotFileError(f"{path}: limb {missing!r}: friction: expected on every limb or on none "
                             f"(the others give it; without it the simulator infers every limb's mechanism)")
    return tuple(out)


def _imu_spec(path: Path, where: str, value: Any) -> ImuSpec:
    """``imu = { bus = "I2C1", mux = 0x70, channel = 3, address = 0x68 }``, every part optional."""
    f = _Fields(path, where, value, {"bus", "mux", "channel", "address"}, sep=".")
    bus = f.string("bus") if f.has("bus") else None
    mux = f.integer("mux", 0, MUX_ADDRESSES.start, MUX_ADDRESSES.stop - 1) if f.has("mux") else None
    channel = f.integer("channel", 0, 0, MUX_CHANNELS - 1) if f.has("channel") else None
    address = f.integer("address", 0, 0x08, 0x77) if f.has("address") else None
    if address is not None and address in MUX_ADDRESSES:
        f.fail("address", "an IMU address outside the multiplexer range 0x70..0x77", address)
    return ImuSpec(bus, mux, channel, address)


def _safety(path: Path, value: Any) -> Safety:
    f = _Fields(path, "safety", value, set(Safety.__dataclass_fields__))
    d = Safety()
    return Safety(
        max_on_ms=f.integer("max_on_ms", d.max_on_ms, 10, 60_000),
        min_cooldown_ms=f.integer("min_cooldown_ms", d.min_cooldown_ms, 0, 600_000),
        max_duty=f.number("max_duty", d.max_duty, 0.0, 1.0, open_lo=True),
        state_timeout_ms=f.integer("state_timeout_ms", d.state_timeout_ms, 10, 600_000),
        link_watchdog_ms=f.integer("link_watchdog_ms", d.link_watchdog_ms, 0, 600_000),
    )


def _control(path: Path, value: Any, safety: Safety) -> Control:
    f = _Fields(path, "control", value, set(Control.__dataclass_fields__))
    d = Control()
    c = Control(
        tick_hz=f.integer("tick_hz", d.tick_hz, 200, 10_000),
        drive_duty=f.number("drive_duty", d.drive_duty, 0.0, 1.0, open_lo=True),
        hold_duty=f.number("hold_duty", d.hold_duty, 0.0, 1.0),
        debounce_ticks=f.integer("debounce_ticks", d.debounce_ticks, 1, 1000),
        hold_ms=f.integer("hold_ms", d.hold_ms, 0, 60_000),
        hold_margin_deg=f.number("hold_margin_deg", d.hold_margin_deg, 0.0, 30.0),
        telemetry_hz=f.integer("telemetry_hz", d.telemetry_hz, 1, 1000),
        overrun_fault=f.integer("overrun_fault", d.overrun_fault, 1, 1000),
        fallback=f.table.get("fallback", d.fallback),
    )
    if not isinstance(c.fallback, bool):
        f.fail("fallback", "true or false", c.fallback)
    if c.drive_duty > safety.max_duty:
        f.fail("drive_duty", f"at most safety.max_duty ({safety.max_duty})", c.drive_duty)
    if c.hold_duty > c.drive_duty:
        f.fail("hold_duty", f"at most control.drive_duty ({c.drive_duty})", c.hold_duty)
    if c.telemetry_hz > c.tick_hz:
        f.fail("telemetry_hz", f"at most control.tick_hz ({c.tick_hz})", c.telemetry_hz)
    return c


# ---------------------------------------------------------------------------------------
# Transition tables: inline matrix or external CSV.


def _transitions(path: Path, value: Any, levels: tuple[int, ...]) -> tuple[TransitionTable, str]:
    f = _Fields(
        path, "transitions", value,
        {"matrix", "file", "forbidden", "durations_s", "default_duration_s", "units", "states", "n_trials",
         *PLANAR_FIELDS},
    )
    units = f.string("units", "steps")
    n = states.state_count(levels)
    if f.has("matrix") == f.has("file"):
        raise RobotFileError(f"{path}: transitions: expected exactly one of 'matrix' or 'file'")
    if f.has("states"):
        expected = [states.label(i, levels) for i in range(n)]
        if value["states"] != expected:
            f.fail("states", f"the state order {expected}", value["states"])

    if f.has("matrix"):
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
        src, dst, rew, dur = _csv(path, f.string("file"), levels)

    if f.has("forbidden"):
        _check_forbidden(path, value["forbidden"], levels, src, dst)

    if f.has("default_duration_s"):
        default = f.number("default_duration_s", None, 0.0, 3600.0, open_lo=True)
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
            m = _same_shape_matrix(path, f"transitions.{key}", value[key], n, allowed,
                                   variance=key.startswith("var_"), allow_nan=True)
            v = m[src, dst]
            known = v[~np.isnan(v)]
            fill = float(known.max()) if key.startswith("var_") and len(known) else 0.0
            given[key] = np.where(np.isnan(v), fill, v)
    return PlanarRewards(**given) if given else None


def _n_trials(path: Path, value: dict, n: int, allowed: np.ndarray) -> np.ndarray | None:
    """``n_trials`` (a learned file): whole numbers >= 0 like the matrix, 'x' where forbidden."""
    if "n_trials" not in value:
        return None
    m = _same_shape_matrix(path, "transitions.n_trials", value["n_trials"], n, allowed, variance=True)
    src, dst = np.nonzero(allowed)
    v = m[src, dst]
    bad = [(int(a), int(b)) for a, b, x in zip(src, dst, v) if x != int(x)]
    if bad:
        a, b = bad[0]
        raise RobotFileError(f"{path}: transitions.n_trials[{a + 1}][{b + 1}]: expected a whole number of trials, "
                             f"got {m[a, b]!r}")
    return v.astype(np.int64)


def _same_shape_matrix(path: Path, name: str, rows: Any, n: int, allowed: np.ndarray, *, variance: bool,
                       allow_nan: bool = False) -> np.ndarray:
    where = f"{path}: {name}"
    expected = "a variance >= 0" if variance else "a number"  # (nan, when allowed: not measured)
    if not isinstance(rows, list) or len(rows) != n:
        got = len(rows) if isinstance(rows, list) else type(rows).__name__
        raise RobotFileError(f"{where}: expected {n} rows like the matrix, got {got}")
    out = np.full((n, n), np.nan)
    for a, row in enumerate(rows):
        if not isinstance(row, list) or len(row) != n:
            got = len(row) if isinstance(row, list) else type(row).__name__
            raise RobotFileError(f"{where}: row {a + 1}: expected {n} entries, got {got}")
        for b, v in enumerate(row):
            if a == b:
                continue  # the diagonal is not a transition
            cell = f"{where}[{a + 1}][{b + 1}]"
            if v == FORBIDDEN:
                if allowed[a, b]:
                    raise RobotFileError(f"{cell}: transition is allowed in the matrix, expected {expected}, got 'x'")
                continue
            unknown = allow_nan and isinstance(v, float) and math.isnan(v)
            if not unknown and (not _is_number(v) or (variance and v < 0)):
                raise RobotFileError(f"{cell}: expected {expected} or 'x', got {v!r}")
            if not allowed[a, b]:
                raise RobotFileError(f"{cell}: transition is forbidden in the matrix, expected 'x', got {v!r}")
            out[a, b] = float(v)
    return out


def _check_forbidden(path: Path, marks: Any, levels: tuple[int, ...], src, dst) -> None:
    """``forbidden = ["01->11", ...]`` states what the robot cannot do; the table must agree."""
    where = f"{path}: transitions.forbidden"
    if not isinstance(marks, list) or not all(isinstance(m, str) for m in marks):
        raise RobotFileError(f"{where}: expected a list of transitions like \"01->11\"")
    given = set(zip(np.asarray(src).tolist(), np.asarray(dst).tolist()))
    n = states.state_count(levels)
    for k, mark in enumerate(marks):
        parts = [p.strip() for p in mark.split("->")]
        if len(parts) != 2:
            raise RobotFileError(f"{where}[{k}]: expected FROM->TO, got {mark!r}")
        a = _state_ref(parts[0], levels, n, f"{where}[{k}]")
        b = _state_ref(parts[1], levels, n, f"{where}[{k}]")
        if (a, b) in given:
            raise RobotFileError(
                f"{where}[{k}]: {mark} is marked forbidden but the table also gives it a reward (expected 'x' there)"
            )


def _matrix(path: Path, rows: Any, n: int) -> tuple[np.ndarray, np.ndarray]:
    where = f"{path}: transitions.matrix"
    if not isinstance(rows, list) or len(rows) != n:
        got = len(rows) if isinstance(rows, list) else type(rows).__name__
        raise RobotFileError(f"{where}: expected {n} rows (one per state, {n} = product of limb levels), got {got}")
    reward = np.zeros((n, n))
    allowed = np.zeros((n, n), dtype=bool)
    for a, row in enumerate(rows):
        if not isinstance(row, list) or len(row) != n:
            got = len(row) if isinstance(row, list) else type(row).__name__
            raise RobotFileError(f"{where}: row {a + 1}: expected {n} entries, got {got}")
        for b, v in enumerate(row):
            if a == b:
                if not (v == FORBIDDEN or _is_number(v)):
                    raise RobotFileError(f"{where}[{a + 1}][{b + 1}]: expected a number or 'x', got {v!r}")
                continue  # the diagonal is not a transition
            if v == FORBIDDEN:
                continue
            if not _is_number(v):
                raise RobotFileError(
                    f"{where}[{a + 1}][{b + 1}]: expected a number or 'x' (forbidden), got {v!r}"
                )
            reward[a, b] = float(v)
            allowed[a, b] = True
    return reward, allowed


def _durations_matrix(path: Path, rows: Any, n: int, allowed: np.ndarray) -> np.ndarray:
    where = f"{path}: transitions.durations_s"
    if not isinstance(rows, list) or len(rows) != n:
        raise RobotFileError(f"{where}: expected {n} rows like the matrix")
    out = np.full((n, n), np.nan)
    for a, row in enumerate(rows):
        if not isinstance(row, list) or len(row) != n:
            raise RobotFileError(f"{where}: row {a + 1}: expected {n} entries")
        for b, v in enumerate(row):
            if a == b:
                continue
            if v == FORBIDDEN:
                if allowed[a, b]:
                    raise RobotFileError(
                        f"{where}[{a + 1}][{b + 1}]: transition is allowed in the matrix, expected a duration > 0"
                    )
                continue
            if not _is_number(v) or not v > 0:
                raise RobotFileError(f"{where}[{a + 1}][{b + 1}]: expected a duration > 0 seconds or 'x', got {v!r}")
            if not allowed[a, b]:
                raise RobotFileError(
                    f"{where}[{a + 1}][{b + 1}]: transition is forbidden in the matrix, expected 'x', got {v!r}"
                )
            out[a, b] = float(v)
    return out


def _csv(path: Path, name: str, levels: tuple[int, ...]):
    csv_path = (path.parent / name).resolve()
    n = states.state_count(levels)
    src: list[int] = []
    dst: list[int] = []
    rew: list[float] = []
    dur: list[float] = []
    seen: set[tuple[int, int]] = set()
    try:
        size = csv_path.stat().st_size
        fh = csv_path.open(newline="", encoding="utf-8")
    except OSError as e:
        raise RobotFileError(f"{path}: transitions.file: cannot open {csv_path}: {e.strerror}") from None
    if size > MAX_CSV_BYTES:
        fh.close()
        raise RobotFileError(f"{path}: transitions.file: {csv_path} has {size:,} bytes, expected at most {MAX_CSV_BYTES:,}")
    with fh:
        has_duration = None
        for lineno, row in enumerate(_csv_rows(fh, csv_path), start=1):
            if not row or row[0].lstrip().startswith("#"):
                continue
            cells = [c.strip() for c in row]
            if lineno == 1 and cells[:3] == ["from", "to", "reward"]:
                continue  # header
            where = f"{csv_path}:{lineno}"
            if len(cells) not in (3, 4):
                raise RobotFileError(f"{where}: expected from,to,reward[,duration_s], got {len(cells)} fields")
            if has_duration is None:
                has_duration = len(cells) == 4
            elif has_duration != (len(cells) == 4):
                raise RobotFileError(f"{where}: every row must have a duration, or none")
            a = _state_ref(cells[0], levels, n, f"{where}: from")
            b = _state_ref(cells[1], levels, n, f"{where}: to")
            if a == b:
                raise RobotFileError(f"{where}: a transition from a state to itself is not a transition")
            if (a, b) in seen:
                raise RobotFileError(f"{where}: transition {cells[0]} -> {cells[1]} is given twice")
            seen.add((a, b))
            try:
                r = float(cells[2])
            except ValueError:
                raise RobotFileError(f"{where}: reward: expected a number, got {cells[2]!r}") from None
            if not math.isfinite(r):
                raise RobotFileError(f"{where}: reward: expected a finite number, got {cells[2]!r}")
            src.append(a)
            dst.append(b)
            rew.append(r)
            if has_duration:
                try:
                    d = float(cells[3])
                except ValueError:
                    d = -1.0
                if not d > 0 or not math.isfinite(d):
                    raise RobotFileError(f"{where}: duration_s: expected a number > 0, got {cells[3]!r}")
                dur.append(d)
    if not src:
        raise RobotFileError(f"{csv_path}: no transitions (expected rows from,to,reward)")
    return src, dst, rew, (dur if dur else None)


def _csv_rows(fh, csv_path: Path):
    """csv.reader's rows, its errors (NUL bytes, a field over its size limit) as RobotFileError."""
    reader = csv.reader(fh)
    while True:
        try:
            yield next(reader)
        except StopIteration:
            return
        except (csv.Error, UnicodeDecodeError) as e:
            raise RobotFileError(f"{csv_path}:{reader.line_num}: not a readable CSV row: {e}") from None


def _state_ref(text: str, levels: tuple[int, ...], n: int, where: str) -> int:
    """A state in a CSV row or a forbidden mark: a label (one digit per limb), else an index."""
    expected = f"{where}: expected a state label of {len(levels)} digits or an index 0..{n - 1}, got {text!r}"
    if len(text) == len(levels):
        try:
            return states.index(text, levels)
        except ValueError as e:
            raise RobotFileError(f"{expected} ({e})") from None
    if text.isdigit() and int(text) < n:
        return int(text)
    raise RobotFileError(expected)


def _is_number(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
