"""Robot files: what a lab writes down about its robot.

A robot file (TOML, see docs/ARCHITECTURE.md and robots/*.toml) names the limbs in label
order, their friction levels and critical angles ψ*, the actuators that drive them, the
transition reward matrix (inline, or an external CSV for large robots), optional
per-transition durations, the safety envelope and the control settings. ``load_robot``
checks every field and raises ``RobotFileError`` with the file, the field and what was
expected; it never clamps or guesses.
"""

from __future__ import annotations

import logging
import math
import re
import tomllib
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from . import states
from .errors import RobotFileError
from .names import identifier
from .robot_body import (CoilLift, Unreached, blocked_descents, coupled_states, coupling_warnings, reach_warnings,
                         shared_coil_lifts, unreachable_states)
from .robot_plant import (PlantSection, default_plant_section, inference_warning, limb_friction, plant_section,
                          rest_warnings)
from .robot_climb import ClimbLimit, climb_guard_refusal, climb_limit
from .robot_fields import Fields, read_text
from .robot_transitions import n_trials_section, transitions_section
from .transitions import TransitionTable

log = logging.getLogger(__name__)

NAME_RE = re.compile(r"[a-z0-9][a-z0-9-]{0,14}")  # fullmatch: "$" would let a final "\n" through
#: Robot names may be longer than the 15 characters the firmware reports (GET_INFO's
#: robot_name field, protocol ROBOT_NAME_LEN 16 with its NUL): the firmware keeps the full
#: name in ROM and sends the first 15 characters. Published robots have longer names
#: (issue 17); 63 keeps build directory names reasonable.
ROBOT_NAME_RE = re.compile(r"[a-z0-9][a-z0-9-]{0,62}")
INFO_NAME_LEN = 15


def info_name(name: str) -> str:
    """The robot's name as the firmware's INFO reports it (its first 15 characters): what a
    board's answer is compared with."""
    return name[:INFO_NAME_LEN]

MAX_LIMBS = 8
#: ``[safety] min_cooldown_ms`` is at most this many ``max_on_ms`` (sma.c's pay-back rate,
#: max_on/min_cooldown in steps of 1/256, must not round to 0; SET_PARAM refuses the same).
MAX_COOLDOWN_PER_ON = 255
MAX_ACTUATORS = 8
#: A robot file larger than this is refused before it is parsed (an inline matrix of
#: 1,024 states takes about 5 MB); a transition CSV larger than robot_transitions.MAX_CSV_BYTES likewise.
MAX_FILE_BYTES = 16 * 1024 * 1024
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


#: The highest ``[[limb]] stroke_deg``: the firmware's hold band above it stays below 89° (psi.c).
STROKE_MAX_DEG = 85.0


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
    #: how far the controller raises the limb when its top level is wanted (°): heated until ψ
    #: reaches it and held there, instead of just past the top critical angle (None)
    stroke_deg: float | None = None


@dataclass(frozen=True)
class Actuator:
    name: str
    channel: int
    channel_given: bool = True  # False: no channel key, the default (its position among the [[actuator]]s)


#: The most on-limit hits that may latch: the guard counts them in a byte and, in the tick it
#: reaches the limit, up to 8 coils may hit at once (core/safety.c asserts the same).
MAX_ON_LIMIT_LATCH = 255 - 8
#: The mean-duty window's range (ms; docs/safety.md: kept as 8 slots of a window / 8).
DUTY_WINDOW_MS_RANGE = (8, 600_000)

#: The shortest link watchdog a robot file may set (0 turns it off): the host's heartbeat
#: comes every quarter of it (``proleg.link.client.WATCHDOG_SHARE``).
MIN_LINK_WATCHDOG_MS = 100


@dataclass(frozen=True)
class Safety:
    max_on_ms: int = 3000
    min_cooldown_ms: int = 800
    max_duty: float = 0.8
    state_timeout_ms: int = 8000
    link_watchdog_ms: int = 2000  # on by default: a host that goes away stops the robot (docs/safety.md)
    #: the thermal budget (docs/safety.md): a duty at or below hold_max_duty is holding, never
    #: on-time (None: max(0.3, control.hold_duty)); the mean duty over any duty_window_ms is at
    #: most max_mean_duty; on_limit_latch on-limit hits without progress latch SMA_ON_LIMIT.
    #: 0.45: held for ever the paper robots' coils settle at 115 °C, 5 K under the 120 °C that
    #: wears NiTi out (materials.NITI_OVERHEAT_C); 0.5 settled at 125 °C, and a host flicking a
    #: held limb's threshold kept a coil there without a fault (docs/safety.md, "Keys")
    hold_max_duty: float | None = None
    max_mean_duty: float = 0.45
    duty_window_ms: int = 10_000
    on_limit_latch: int = 3

    @property
    def mean_ceiling(self) -> float:
        """The most a duty held for ever may be: it fits the mean-duty window and max_duty."""
        return min(self.max_mean_duty, self.max_duty)

    def hold_ceiling(self, hold_duty: float) -> float:
        """``hold_max_duty``, or its default: max(0.3, the control's hold duty), at most
        ``mean_ceiling`` (a duty the coil may hold forever fits the window)."""
        if self.hold_max_duty is not None:
            return self.hold_max_duty
        return min(self.mean_ceiling, max(0.3, hold_duty))


#: control.boost_ms: 0 (off) or this range. Below 100 ms a coil still heating back to As (its
#: dead time, 0.15-0.6 s) would count as lagging at every rise; at or above the stall
#: detector's 5 s (CTL_STALL_MS) the limb is cut off as "cannot reach" first.
BOOST_MIN_MS = 100
BOOST_MAX_MS = 4000


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
    #: a rising limb that gets no progress edge closer for this long heats at safety.max_duty
    #: until the next START (core/ctl.h, CTL_BOOST_MS); 0: never (the default)
    boost_ms: int = 0
    fallback: bool = True  # firmware switches to a build-time fallback gait when it loses an actuator
    #: limbs raised to their strokes together: which crosses psi* first (None: the largest stroke);
    #: lowered together: which goes down first while the others are held at their strokes (None:
    #: they fall as they cool). Limb names.
    stroke_rise_lead: str | None = None
    stroke_fall_lead: str | None = None
    #: the steepest ground (degrees, rising in the gait's direction) a gait is started on, per
    #: direction: START steeper uphill is refused (NACK TOO_STEEP). None: no guard
    #: (docs/calibration.md)
    max_climb_deg: ClimbLimit | None = None


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
    #: states the matrix enters that a shared coil cannot hold on the simulated body (it lifts
    #: one of its limbs while holding another up): state -> (actuator, lifted limb, raised limbs)
    #: per lift; ``proleg.robot_body.shared_coil_lifts``, checked by ``proleg.gait.feasibility``
    coil_lifts: dict[int, tuple[CoilLift, ...]] = field(default_factory=dict)
    #: states the matrix enters that a raised limb cannot reach on the simulated body, even with
    #: every raised limb's coil at full stroke: state -> (limb, ψ° at most, ψ° needed) per limb;
    #: ``proleg.robot_body.unreachable_states``, checked by ``proleg.gait.feasibility``
    unreachable: dict[int, tuple[Unreached, ...]] = field(default_factory=dict)

    @property
    def where(self) -> str:
        """How an error about this robot's file names it (as a load error does): its path."""
        return str(self.path)

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


def load_robot(path: str | Path) -> Robot:
    """Read and check a robot file; RobotFileError says what is wrong and where."""
    path = Path(path)
    text = read_text(path, MAX_FILE_BYTES, "robot file")
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
    top = Fields(path, "robot file", doc, {"robot", "limb", "actuator", "transitions", "safety", "control", "plant",
                                            "gaits"})
    for key in ("robot", "limb", "actuator", "transitions"):
        if not top.has(key):
            raise RobotFileError(f"{path}: missing [{key}]{' entries' if key in ('limb', 'actuator') else ''}")

    head = Fields(path, "robot", doc["robot"], {"name", "description"})
    name = head.string("name")
    if not ROBOT_NAME_RE.fullmatch(name):
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
    table, units = transitions_section(path, doc["transitions"], levels, [limb.name for limb in limbs])
    n_trials = None
    if isinstance(doc["transitions"], dict) and "n_trials" in doc["transitions"]:
        allowed = np.zeros((table.n_states, table.n_states), dtype=bool)
        allowed[table.src, table.dst] = True
        n_trials = n_trials_section(path, doc["transitions"], table.n_states, allowed)

    safety = _safety(path, doc.get("safety", {}))
    control = _control(path, doc.get("control", {}), safety)
    _check_strokes(path, control, limbs)
    for line in hold_crossings(path, limbs, control.hold_margin_deg):
        log.warning("warning: %s", line)
    act_index = {a.name: j for j, a in enumerate(actuators)}
    plant = plant_section(path, doc.get("plant", {}), [a.name for a in actuators], len(limbs), table.n_states,
                          [act_index[limb.actuator] for limb in limbs], units)
    for line in rest_warnings(path, list(limbs), plant):
        log.warning("warning: %s", line)
    for line in reach_warnings(path, list(limbs), [a.name for a in actuators], plant, control.hold_margin_deg):
        log.warning("warning: %s", line)
    coupled = coupled_states(list(limbs), [a.name for a in actuators], plant, table, control.hold_margin_deg)
    blocked = blocked_descents(list(limbs), [a.name for a in actuators], plant, table, control.hold_margin_deg)
    shown, rest = coupling_warnings(path, list(limbs), plant, table, coupled, blocked)
    for line in shown:
        log.warning("warning: %s", line)
    for line in rest:
        log.debug("warning: %s", line)
    if (line := inference_warning(path, list(limbs))) is not None:
        log.warning("warning: %s", line)
    library = None
    if "gaits" in doc:
        from .gait.library import library_from_robot_file, missing_statistics

        library = library_from_robot_file(path, doc["gaits"])
        if library is not None and (why := missing_statistics(library, table)):
            raise RobotFileError(f"{path}: gaits.library: {why}")
    _check_climb(path, control, limbs, library)
    return Robot(name, path, description, limbs, actuators, table, units, safety, control, plant, n_trials, library,
                 shared_coil_lifts(list(limbs), coupled),
                 unreachable_states(list(limbs), [a.name for a in actuators], plant, table))


def _check_climb(path: Path, control: Control, limbs: Sequence[Limb], library: Any) -> None:
    if control.max_climb_deg is not None and (why := climb_guard_refusal(len(limbs), library)):
        raise RobotFileError(f"{path}: control.max_climb_deg: {why}")


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
        f = Fields(path, _entry("actuator", i, t), t, {"name", "channel"}, sep=": ")
        name = f.string("name")
        if not NAME_RE.fullmatch(name):
            f.fail("name", "lowercase letters, digits and '-', 1 to 15 characters", name)
        if any(a.name == name for a in out):
            f.fail("name", "a name no other actuator has", name)
        channel = f.integer("channel", i, 0, MAX_ACTUATORS - 1)
        if any(a.channel == channel for a in out):
            f.fail("channel", "a channel no other actuator uses", channel)
        out.append(Actuator(name, channel, "channel" in t))
    return tuple(out)


def _limbs(path: Path, value: Any, actuator_names: set[str]) -> tuple[Limb, ...]:
    tables = _array_of_tables(path, value, "limb")
    if len(tables) > MAX_LIMBS:
        raise RobotFileError(f"{path}: limb: at most {MAX_LIMBS} limbs, got {len(tables)}")
    out: list[Limb] = []
    for i, t in enumerate(tables):
        f = Fields(path, _entry("limb", i, t), t, {"name", "levels", "psi_star_deg", "hysteresis_deg", "actuator", "imu", "friction",
                                                   "stroke_deg"},
                    sep=": ")
        name = f.string("name")
        if not name or not name.isprintable():  # empty: psi_ in the DBC; a newline splits printed lines
            f.fail("name", "a name of printable characters, at least one", name)
        if any(limb.name == name for limb in out):
            f.fail("name", "a name no other limb has (duplicate limb)", name)
        if (twin := next((limb.name for limb in out if identifier(limb.name) == identifier(name)), None)) is not None:
            f.fail("name", f"a name that stays apart from limb {twin!r} as an identifier (both are "
                           f"{identifier(name)!r} in recordings and CAN signals)", name)
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
        if psi_t[0] - hyst / 2 <= -90.0 or psi_t[-1] + hyst / 2 >= 90.0:  # the firmware's band edges
            f.fail("psi_star_deg", f"angles whose bands psi* ± hysteresis_deg/2 ({hyst:g}/2) lie strictly inside "
                   f"(-90, 90) degrees", psi)
        actuator = f.string("actuator")
        if actuator not in actuator_names:
            f.fail("actuator", f"the name of an [[actuator]] ({', '.join(sorted(actuator_names))})", actuator)
        imu = _imu_spec(path, f"{f.where}: imu", t["imu"]) if "imu" in t else None
        friction = limb_friction(path, f.where, t["friction"], levels) if "friction" in t else None
        stroke = f.number("stroke_deg", 0.0, -math.inf, math.inf) if f.has("stroke_deg") else None  # range: _check_strokes
        out.append(Limb(name, levels, psi_t, hyst, actuator, imu, friction, stroke))
    declared = [limb.friction is not None for limb in out]
    if any(declared) and not all(declared):
        missing = next(limb.name for limb in out if limb.friction is None)
        raise RobotFileError(f"{path}: limb {missing!r}: friction: expected on every limb or on none "
                             f"(the others give it; without it the simulator infers every limb's mechanism)")
    return tuple(out)


def _check_strokes(path: Path, control: Control, limbs: Sequence[Limb]) -> None:
    """Each ``stroke_deg`` lies at least 1° above where the limb is held without one (so that
    its hold band starts above that hold's, and rounds to a distinct edge) and at most
    STROKE_MAX_DEG; ``stroke_rise_lead`` / ``stroke_fall_lead`` name a limb that has one."""
    for lb in limbs:
        if lb.stroke_deg is None:
            continue
        lo = lb.psi_star_deg[-1] + lb.hysteresis_deg / 2 + control.hold_margin_deg + 1.0
        if not lo <= lb.stroke_deg <= STROKE_MAX_DEG:
            # the firmware holds it between stroke_deg and 1° above (psi.c: edges within ±89°)
            raise RobotFileError(
                f"{path}: limb {lb.name!r}: stroke_deg: expected an angle from {lo:g} (1° above where it is held "
                f"without one: psi* + hysteresis/2 + control.hold_margin_deg) to {STROKE_MAX_DEG:g} degrees, "
                f"got {lb.stroke_deg:g}")
    with_stroke = [lb.name for lb in limbs if lb.stroke_deg is not None]
    for key in ("stroke_rise_lead", "stroke_fall_lead"):
        name = getattr(control, key)
        if name is not None and not with_stroke:
            raise RobotFileError(f"{path}: control.{key}: {name!r}, but no [[limb]] has a stroke_deg to lead with")
        if name is not None and name not in with_stroke:
            raise RobotFileError(f"{path}: control.{key}: expected the name of a limb with a stroke_deg "
                                 f"({', '.join(with_stroke)}), got {name!r}")


#: How far above its hold edge the firmware lets a held limb's coil heat (core/psi.h
#: PSI_HOLD_BAND_CDEG): the hold band is [hold edge, hold edge + 1°].
HOLD_BAND_DEG = 1.0


def hold_crossings(path: Path, limbs: Sequence[Limb], hold_margin_deg: float) -> list[str]:
    """One warning line per pair of neighbouring thresholds of a limb too close for the
    controller to hold the lower level: it holds level k with ψ between the hold edge
    ψ*_k + h/2 + ``hold_margin_deg`` and 1° above it (docs/control.md), and a hold band that
    reaches the next band's lower edge ψ*_{k+1} − h/2 takes the limb into level k+1. A warning,
    not an error: ``SET_PARAM`` may move the thresholds and the margin on the board."""
    out = []
    for lb in limbs:
        h = lb.hysteresis_deg
        need = h + hold_margin_deg + HOLD_BAND_DEG  # ψ*_{k+1} − ψ*_k must exceed this
        for k, (lo, hi) in enumerate(zip(lb.psi_star_deg, lb.psi_star_deg[1:]), start=1):
            if hi - lo > need:
                continue
            top = lo + h / 2 + hold_margin_deg + HOLD_BAND_DEG
            out.append(f"{path}: limb {lb.name!r}: psi_star_deg {lo:g}° and {hi:g}° are {hi - lo:g}° apart: holding "
                       f"level {k}, the controller heats it up to {top:g}° (psi* + hysteresis/2 + "
                       f"control.hold_margin_deg + {HOLD_BAND_DEG:g}°), which reaches level {k + 1}'s band "
                       f"(from {hi - h / 2:g}°), so level {k} cannot be held; space them more than {need:g}° "
                       f"apart (hysteresis_deg {h:g} + hold_margin_deg {hold_margin_deg:g} + {HOLD_BAND_DEG:g}), "
                       f"or lower hold_margin_deg or hysteresis_deg")
    return out


def stroke_leads(limbs: Sequence[Any], control: Any) -> tuple[int, int | None] | None:
    """(rise lead, fall lead or None) as limb indices, or None when no limb has a stroke: the
    control keys; without ``stroke_rise_lead`` the limb with the largest stroke (the first such
    in the file), without ``stroke_fall_lead`` no fall lead (limbs fall as their coils cool)."""
    strokes = [getattr(lb, "stroke_deg", None) for lb in limbs]
    idx = [i for i, st in enumerate(strokes) if st is not None]
    if not idx:
        return None
    names = [lb.name for lb in limbs]
    rise, fall = getattr(control, "stroke_rise_lead", None), getattr(control, "stroke_fall_lead", None)
    return (names.index(rise) if rise else max(idx, key=lambda i: (strokes[i], -i)),
            names.index(fall) if fall else None)


def _imu_spec(path: Path, where: str, value: Any) -> ImuSpec:
    """``imu = { bus = "I2C1", mux = 0x70, channel = 3, address = 0x68 }``, every part optional."""
    f = Fields(path, where, value, {"bus", "mux", "channel", "address"}, sep=".")
    bus = f.string("bus") if f.has("bus") else None
    mux = f.integer("mux", 0, MUX_ADDRESSES.start, MUX_ADDRESSES.stop - 1) if f.has("mux") else None
    channel = f.integer("channel", 0, 0, MUX_CHANNELS - 1) if f.has("channel") else None
    address = f.integer("address", 0, 0x08, 0x77) if f.has("address") else None
    if address is not None and address in MUX_ADDRESSES:
        f.fail("address", "an IMU address outside the multiplexer range 0x70..0x77", address)
    return ImuSpec(bus, mux, channel, address)


def _safety(path: Path, value: Any) -> Safety:
    f = Fields(path, "safety", value, set(Safety.__dataclass_fields__))
    d = Safety()
    s = Safety(
        max_on_ms=f.integer("max_on_ms", d.max_on_ms, 10, 60_000),
        min_cooldown_ms=f.integer("min_cooldown_ms", d.min_cooldown_ms, 0, 600_000),
        max_duty=f.number("max_duty", d.max_duty, 0.0, 1.0, open_lo=True),
        state_timeout_ms=f.integer("state_timeout_ms", d.state_timeout_ms, 10, 600_000),
        link_watchdog_ms=f.integer("link_watchdog_ms", d.link_watchdog_ms, 0, 600_000),
        hold_max_duty=f.number("hold_max_duty", None, 0.0, 1.0) if f.has("hold_max_duty") else None,
        max_mean_duty=f.number("max_mean_duty", d.max_mean_duty, 0.0, 1.0, open_lo=True),
        duty_window_ms=f.integer("duty_window_ms", d.duty_window_ms, *DUTY_WINDOW_MS_RANGE),
        on_limit_latch=f.integer("on_limit_latch", d.on_limit_latch, 1, MAX_ON_LIMIT_LATCH),
    )
    if s.hold_max_duty is not None and s.hold_max_duty > s.mean_ceiling:
        f.fail("hold_max_duty", f"at most max_mean_duty and max_duty ({s.mean_ceiling:g}): a "
               "duty the coil may hold forever must fit the mean-duty window", s.hold_max_duty)
    # the host feeds the watchdog with a PING every quarter of it (link/client.py): below
    # 100 ms that is a frame every few ms, and a desktop OS's scheduling alone can miss it
    if 0 < s.link_watchdog_ms < MIN_LINK_WATCHDOG_MS:
        f.fail("link_watchdog_ms", f"0 (off) or at least {MIN_LINK_WATCHDOG_MS} ms", s.link_watchdog_ms)
    # sma.c pays on-time back at max_on/min_cooldown in steps of 1/256: a cool-down of 256
    # on-times or more would pay back nothing, and a coil that hit its limit never heat again
    if s.min_cooldown_ms > MAX_COOLDOWN_PER_ON * s.max_on_ms:
        f.fail("min_cooldown_ms", f"at most {MAX_COOLDOWN_PER_ON} × safety.max_on_ms ({MAX_COOLDOWN_PER_ON * s.max_on_ms})",
               s.min_cooldown_ms)
    return s


def _control(path: Path, value: Any, safety: Safety) -> Control:
    f = Fields(path, "control", value, set(Control.__dataclass_fields__))
    d = Control()
    c = Control(
        tick_hz=f.integer("tick_hz", d.tick_hz, 200, 10_000),
        drive_duty=f.number("drive_duty", d.drive_duty, 0.0, 1.0, open_lo=True),
        hold_duty=f.number("hold_duty", d.hold_duty, 0.0, 1.0),
        debounce_ticks=f.integer("debounce_ticks", d.debounce_ticks, 1, 1000),
        hold_ms=f.integer("hold_ms", d.hold_ms, 0, 600_000),  # as SET_PARAM's (core/param.c)
        hold_margin_deg=f.number("hold_margin_deg", d.hold_margin_deg, 0.0, 30.0),
        telemetry_hz=f.integer("telemetry_hz", d.telemetry_hz, 1, 1000),
        overrun_fault=f.integer("overrun_fault", d.overrun_fault, 1, 1000),
        boost_ms=f.integer("boost_ms", d.boost_ms, 0, BOOST_MAX_MS),
        fallback=f.table.get("fallback", d.fallback),
        stroke_rise_lead=f.string("stroke_rise_lead") if f.has("stroke_rise_lead") else None,
        stroke_fall_lead=f.string("stroke_fall_lead") if f.has("stroke_fall_lead") else None,
        max_climb_deg=climb_limit(f),
    )
    if not isinstance(c.fallback, bool):
        f.fail("fallback", "true or false", c.fallback)
    if c.drive_duty > safety.max_duty:
        f.fail("drive_duty", f"at most safety.max_duty ({safety.max_duty})", c.drive_duty)
    if c.hold_duty > c.drive_duty:
        f.fail("hold_duty", f"at most control.drive_duty ({c.drive_duty})", c.hold_duty)
    if safety.hold_max_duty is None and c.hold_duty > safety.mean_ceiling:
        f.fail("hold_duty", f"at most safety.max_mean_duty ({safety.mean_ceiling:g}): "
               "a duty that holds a state must fit the mean-duty window (or set safety.hold_max_duty "
               "below it, and the hold counts as on-time)", c.hold_duty)
    ceiling = safety.hold_ceiling(c.hold_duty)
    if c.drive_duty <= ceiling:
        # at or below the hold ceiling a duty is holding, never on-time (docs/safety.md): a coil
        # driven there would never meet max_on_ms, the cool-down or the on-limit latch
        f.fail("drive_duty", f"above the hold ceiling {ceiling:g} (safety.hold_max_duty, by default "
               "max(0.3, control.hold_duty)): at or below it heating counts as holding, never as on-time, "
               "so max_on_ms, the cool-down and the on-limit latch would never apply", c.drive_duty)
    if c.telemetry_hz > c.tick_hz:
        f.fail("telemetry_hz", f"at most control.tick_hz ({c.tick_hz})", c.telemetry_hz)
    if 0 < c.boost_ms < BOOST_MIN_MS:
        f.fail("boost_ms", f"0 (off) or {BOOST_MIN_MS} .. {BOOST_MAX_MS} ms", c.boost_ms)
    return c
