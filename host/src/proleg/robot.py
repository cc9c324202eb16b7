"""Robot files: what a lab writes down about its robot.

A robot file (TOML, see docs/ARCHITECTURE.md and robots/*.toml) names the limbs in label
order, their friction levels and critical angles ψ*, the actuators that drive them, the
transition reward matrix (inline, or an external CSV for large robots), optional
per-transition durations, the safety envelope and the control settings. ``load_robot``
checks every field and raises ``RobotFileError`` with the file, the field and what was
expected; it never clamps or guesses.

The ``[[limb]]`` and ``[[actuator]]`` tables are read in ``proleg.robot_limbs``, ``[safety]``
and ``[control]`` in ``proleg.robot_settings``; their names are re-exported here, so
``proleg.robot`` stays the one place to import them from.
"""

from __future__ import annotations

import logging
import re
import tomllib
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from . import states
from .errors import RobotFileError
from .robot_body import (CoilLift, Unreached, blocked_descents, coupled_states, coupling_warnings, reach_warnings,
                         shared_coil_lifts, unholdable_states, unreachable_states, unreachable_strokes)
from .robot_reach import boost_warning
from .robot_plant import PlantSection, default_plant_section, inference_warning, plant_section, rest_warnings
from .robot_climb import climb_guard_refusal
from .robot_fields import Fields, read_text
from .robot_limbs import (  # noqa: F401 (re-exported: the robot file's names are imported from proleg.robot)
    HOLD_BAND_DEG,
    MAX_ACTUATORS,
    MAX_LIMBS,
    MUX_ADDRESSES,
    MUX_CHANNELS,
    NAME_ALPHABET,
    NAME_RE,
    STROKE_MAX_DEG,
    Actuator,
    ImuSpec,
    Limb,
    _actuators,
    _check_strokes,
    _limbs,
    hold_crossings,
    name_re,
    stroke_leads,
    too_long,
)
from .robot_settings import (  # noqa: F401 (re-exported: the robot file's names are imported from proleg.robot)
    BOOST_MAX_MS,
    BOOST_MIN_MS,
    DUTY_WINDOW_MS_RANGE,
    MAX_COOLDOWN_PER_ON,
    MAX_ON_LIMIT_LATCH,
    MIN_LINK_WATCHDOG_MS,
    Control,
    Safety,
    _control,
    _safety,
    window_warning,
)
from .robot_transitions import is_unmeasured, n_trials_section, transitions_section
from .transitions import TransitionTable

log = logging.getLogger(__name__)

#: Robot names may be longer than the 15 characters the firmware reports (GET_INFO's
#: robot_name field, protocol ROBOT_NAME_LEN 16 with its NUL): the firmware keeps the full
#: name in ROM and sends the first 15 characters. Published robots have longer names
#: (issue 17); 63 keeps build directory names reasonable.
ROBOT_NAME_RE = name_re(63)
INFO_NAME_LEN = 15


def info_name(name: str) -> str:
    """The robot's name as the firmware's INFO reports it (its first 15 characters): what a
    board's answer is compared with."""
    return name[:INFO_NAME_LEN]

#: A robot file larger than this is refused before it is parsed (an inline matrix of
#: 1,024 states takes about 5 MB); a transition CSV larger than robot_transitions_csv.MAX_CSV_BYTES likewise.
MAX_FILE_BYTES = 16 * 1024 * 1024
#: Brackets and braces nested deeper than this are refused before parsing (a robot file
#: needs 3: a matrix row inside the matrix inside a table); tomllib recurses per level.
MAX_NESTING = 32
#: At most this many states (product of limb levels): 2^20, 16 binary limbs and more.
MAX_STATES = 1 << 20


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
    #: states the matrix enters that the simulated body cannot hold because a limb rests or is
    #: lifted (by its neighbours, not by a coil it shares) past its level's upper edge: state ->
    #: (limb, ψ°) per such limb; ``proleg.robot_body.coupled_states``' (the load check's "cannot be
    #: held" lines), checked by ``proleg.gait.feasibility``
    unholdable: dict[int, tuple[tuple[int, float], ...]] = field(default_factory=dict)
    #: allowed steps the simulated body cannot end because raised limbs keep a limb from coming
    #: down: (from, to) -> (limb, raising limbs, ψ°); ``proleg.robot_body.blocked_descents``' (the
    #: load check's "cannot come down" lines), checked by ``proleg.gait.feasibility``
    blocked: dict[tuple[int, int], tuple[int, list[int], float]] = field(default_factory=dict)
    #: ``[transitions] matrix = "unmeasured"``: every allowed transition's reward is 0 until
    #: measured (``proleg learn``, ``proleg sim --measure-matrix``), so no gait moves it
    unmeasured: bool = False

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
        hint = ""
        for table in ("limb", "actuator"):  # [limb] twice: the parser's words name no fix
            if f"Cannot declare ('{table}',) twice" in str(e) or (
                    "Cannot overwrite a value" in str(e) and re.search(rf"^\s*\[{table}\]", text, re.M)):
                hint = f": a robot has one or more {table}s, write each one as [[{table}]] (two brackets)"
                break
        raise RobotFileError(f"{path}: not valid TOML: {e}{hint}") from None
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
        head.fail("name", f"{NAME_ALPHABET}, 1 to 63 characters", name, too_long(name))
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
    unmeasured = is_unmeasured(doc["transitions"])
    n_trials = None
    if isinstance(doc["transitions"], dict) and "n_trials" in doc["transitions"]:
        allowed = np.zeros((table.n_states, table.n_states), dtype=bool)
        allowed[table.src, table.dst] = True
        n_trials = n_trials_section(path, doc["transitions"], table.n_states, allowed)

    safety = _safety(path, doc.get("safety", {}))
    control = _control(path, doc.get("control", {}), safety)
    _check_strokes(path, control, limbs)
    if (line := window_warning(path, safety, control)) is not None:
        log.warning("warning: %s", line)
    for line in hold_crossings(path, limbs, control.hold_margin_deg):
        log.warning("warning: %s", line)
    act_index = {a.name: j for j, a in enumerate(actuators)}
    plant_doc = doc.get("plant", {})
    if unmeasured and "units" not in doc["transitions"] and isinstance(plant_doc, dict) and "step_mm" in plant_doc:
        # an unmeasured matrix counts in mm (what a hand, a tracker or the simulator measures), and
        # step_mm is the table plant's, which an unmeasured matrix cannot drive: a file that was a
        # written one in steps keeps loading, told so (learn --out leaves it out)
        log.warning('warning: %s: plant.step_mm is not used: an unmeasured matrix is learned in mm (say '
                    'transitions.units = "steps" to count in step_mm instead)', path)
        plant_doc = {k: v for k, v in plant_doc.items() if k != "step_mm"}
    plant = plant_section(path, plant_doc, [a.name for a in actuators], len(limbs), table.n_states,
                          [act_index[limb.actuator] for limb in limbs], units)
    for line in rest_warnings(path, list(limbs), plant):
        log.warning("warning: %s", line)
    for line in reach_warnings(path, list(limbs), [a.name for a in actuators], plant, control.hold_margin_deg):
        log.warning("warning: %s", line)
    if (line := boost_warning(path, list(limbs), [a.name for a in actuators], plant, control, safety)) is not None:
        log.warning("warning: %s", line)
    for line in unreachable_strokes(path, list(limbs), [a.name for a in actuators], plant, table,
                                    control.hold_margin_deg):
        log.warning("warning: %s", line)
    coupled = coupled_states(list(limbs), [a.name for a in actuators], plant, table, control.hold_margin_deg)
    blocked = blocked_descents(list(limbs), [a.name for a in actuators], plant, table, control.hold_margin_deg)
    shown, rest = coupling_warnings(path, list(limbs), plant, table, coupled, blocked, unmeasured)
    for line in shown:
        log.warning("warning: %s", line)
    for line in rest:
        log.debug("warning: %s", line)
    if (line := inference_warning(path, list(limbs), unmeasured)) is not None:
        log.warning("warning: %s", line)
    library = None
    if "gaits" in doc:
        from .gait.library import library_from_robot_file, missing_statistics

        library = library_from_robot_file(path, doc["gaits"], table)
        if library is not None and (why := missing_statistics(library, table)):
            raise RobotFileError(f"{path}: gaits.library: {why}")
    _check_climb(path, control, limbs, library)
    return Robot(name, path, description, limbs, actuators, table, units, safety, control, plant, n_trials, library,
                 shared_coil_lifts(list(limbs), coupled),
                 unreachable_states(list(limbs), [a.name for a in actuators], plant, table),
                 unholdable_states(list(limbs), coupled), blocked, unmeasured)


def _check_climb(path: Path, control: Control, limbs: Sequence[Limb], library: Any) -> None:
    if control.max_climb_deg is not None and (why := climb_guard_refusal(len(limbs), library)):
        raise RobotFileError(f"{path}: control.max_climb_deg: {why}")

