"""The simulated robot: the host-sim firmware in closed loop with the plant.

Every ``plant_dt_s`` of virtual time: the plant's true ψ and dψ/dt go into the IMU
models, the firmware runs its control ticks (reading those IMUs over the simulated I2C
bus and setting PWM), and the plant integrates over the duties the firmware set. The
firmware ticks in C; Python touches the loop once per plant step, which is what lets
the simulation run far faster than real time.

The board is any object with the simulated-board interface (``proleg.sim.board.
SimulatedBoardLike``): by default the host-sim build (``SimBoard``) of the robot's firmware;
an emulated MCU can be passed as ``board=``. The plant is the physical one by default
(``proleg.sim.physical``: displacement from friction mechanics, with the robot file's
``[plant]`` conditions and any given on top); ``plant="table"`` picks the lookup plant
(``proleg.sim.plant``: the robot's matrix, e.g. to test learning against a known matrix), and
a plant object is used as it is. ``make_plant`` is the factory. ``SimulatedRobot`` offers ``write``/``read``/
``advance``, the board interface ``proleg.link.sim_link.SimLink`` (and so the client, the
console, the recorder and hil_tests) talk to.
"""

from __future__ import annotations

import hashlib
import logging
import math
import random
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from types import SimpleNamespace
from typing import Any

from .. import paths
from ..errors import SimError
from ..firmware.boards import Board, load_board
from ..firmware.placement import place_imus, sim_imu_keys
from ..robot import Robot
from .board import SimBoard, SimulatedBoardLike
from .plant import Plant, plant_params_from_robot, planar_motion_from_robot, true_rewards_from_robot
from .plant_warnings import ambient_warnings, overheat_warnings, planar_warnings, underpowered_warnings

log = logging.getLogger(__name__)

DEFAULT_PLANT_DT_S = 0.002
PLANTS = ("physical", "table")
DEFAULT_PLANT = "physical"


def make_plant(robot: Robot, kind: str = DEFAULT_PLANT, conditions: Any = None, *, seed: int = 1) -> Any:
    """The plant ``kind`` ("physical" or "table") of ``robot``. ``conditions``: ``key=value``
    strings, a mapping or a ``Conditions``, applied on top of the robot file's ``[plant]``
    (physical plant only; the table plant takes none: SimError)."""
    if kind == "table":
        if conditions:
            raise SimError("--condition: conditions apply to the physical plant (--plant physical), "
                           "the table plant reads only the robot file's [plant] table")
        return Plant(plant_params_from_robot(robot), true_rewards_from_robot(robot), robot.levels, seed,
                     planar_motion_from_robot(robot))
    if kind != "physical":
        raise SimError(f"plant {kind!r}: expected one of: {', '.join(PLANTS)}")
    from .physical import PhysicalPlant

    from .physical.climb import slope_warnings

    plant = PhysicalPlant(robot, plant_conditions(robot, conditions), seed=seed)
    for line in (planar_warnings(robot) + overheat_warnings(robot, plant) + underpowered_warnings(robot, plant)
                 + ambient_warnings(robot, plant) + slope_warnings(robot, plant)):
        log.warning("warning: %s", line)
    return plant


def plant_conditions(robot: Robot, conditions: Any = None) -> Any:
    """The physical plant's ``Conditions`` for ``robot``: its robot file's ``[plant]`` values,
    with ``conditions`` (strings, a mapping or a ``Conditions``) on top."""
    from .physical import Conditions, parse_conditions
    from .physical.conditions import by_item_name, check_given_once, coil_of_limb, conditions_from_section

    limbs, acts = [lb.name for lb in robot.limbs], [a.name for a in robot.actuators]
    base = conditions_from_section(robot.plant, acts, limbs)
    if isinstance(conditions, Conditions):
        return by_item_name(_merge(base, conditions), limbs, acts, coil_of_limb(robot))
    parsed = parse_conditions(conditions or [], base)  # a name given twice: its own error
    if conditions and not isinstance(conditions, Mapping):
        check_given_once(conditions, limbs, acts, coil_of_limb(robot))
    return by_item_name(parsed, limbs, acts, coil_of_limb(robot))  # each limb and coil once


def condition_strings(conditions: Any) -> list[str]:
    """``Conditions`` as the ``key=value`` strings ``--condition`` takes (``key=NAME:value`` for
    a per-limb or per-actuator value, ``key=value`` for all of them), in the schema's key order:
    what a run's ``--json`` reports as its ``effective_conditions`` and a script can give back.
    Keys left at their defaults are not listed."""
    from .physical.conditions import KEYS

    out = []
    for key in KEYS:
        if key in conditions.values:
            out.append(f"{key}={float(conditions.values[key])!r}")
        for name, v in conditions.named.get(key, {}).items():
            out.append(f"{key}={name + ':' if name else ''}{float(v)!r}")
    return out


def _merge(base: Any, top: Any) -> Any:
    from dataclasses import replace as _replace

    named = {k: dict(v) for k, v in base.named.items()}
    for k, v in top.named.items():
        named.setdefault(k, {}).update(v)
    return _replace(base, values={**base.values, **top.values}, named=named)


def cache_dir() -> Path:
    return paths.cache_dir("sim")


def sim_library(robot: Robot, *, objective: str = "total", max_transitions: int | None = None,
                board: str = "host-sim") -> Path:
    """The robot's host-sim firmware (or that of a host-sim variant such as host-sim-can),
    built once per distinct rendered project and cached."""
    from ..firmware.build import build, firmware_gaits, render_project

    board = load_board(board)
    files = render_project(robot, board, firmware_gaits(robot, objective, max_transitions))
    digest = hashlib.sha256()
    for rel in sorted(files):
        digest.update(rel.encode() + b"\0" + files[rel].encode() + b"\0")
    out = cache_dir() / f"{robot.name}-{digest.hexdigest()[:16]}"
    lib = out / board.artifact
    if not lib.exists():
        build(robot, board, out, objective=objective, max_transitions=max_transitions)
    return lib


@dataclass
class LinkFaults:
    """Bytes dropped or corrupted on the simulated serial link, both directions."""

    drop: float = 0.0  # probability per byte
    corrupt: float = 0.0  # probability per byte (one random bit flipped)
    rng: random.Random = field(default_factory=lambda: random.Random(7))

    def apply(self, data: bytes) -> bytes:
        if not data or (self.drop == 0.0 and self.corrupt == 0.0):
            return data
        out = bytearray()
        for b in data:
            r = self.rng.random()
            if r < self.drop:
                continue
            if r < self.drop + self.corrupt:
                b ^= 1 << self.rng.randrange(8)
            out.append(b)
        return bytes(out)


class SimulatedRobot:
    """A simulated board running ``robot``'s firmware, wired to a plant of ``robot``.

    ``board``: a simulated board already loaded with the robot's firmware (any
    ``SimulatedBoardLike``, e.g. an emulated MCU); by default the host-sim build from
    ``library`` (or built and cached by ``sim_library``), reset with ``seed``. ``board_info``:
    the board description whose I2C buses carry the IMUs (default host-sim).
    ``plant``: "physical" (default), "table" or a plant object; ``conditions``: the physical
    plant's conditions on top of the robot file's (``make_plant``).
    """

    def __init__(
        self,
        robot: Robot,
        library: Path | None = None,
        *,
        seed: int = 1,
        plant: Any = None,
        conditions: Any = None,
        plant_dt_s: float = DEFAULT_PLANT_DT_S,
        board: SimulatedBoardLike | None = None,
        board_info: Board | None = None,
    ):
        self.robot = robot
        self.board_info = board_info or load_board("host-sim")
        self.board: SimulatedBoardLike = board if board is not None else SimBoard(library or sim_library(robot), seed)
        if plant is None or isinstance(plant, str):
            plant = make_plant(robot, plant or DEFAULT_PLANT, conditions, seed=seed)
        elif conditions:
            raise SimError("SimulatedRobot: conditions go with a plant kind, not with a plant object")
        self.plant = plant
        self.plant_kind = "table" if isinstance(plant, Plant) else "physical"
        # The key of each limb's IMU on the board's buses (proleg.firmware.placement).
        self.imu_addresses = sim_imu_keys(place_imus(robot, self.board_info))
        self.channels = tuple(range(max(a.channel for a in robot.actuators) + 1))
        self.ticks_per_step = max(1, round(plant_dt_s * 1e6 / self.board.tick_us))
        self.plant_dt_s = self.ticks_per_step * self.board.tick_us / 1e6
        self.link_faults = LinkFaults()
        self._pending_s = 0.0  # virtual time asked of advance() not yet run (under one plant step)
        self._push_truth()

    # -- the board interface SimLink drives (write/read/advance) -------------------------
    def write(self, data: bytes) -> None:
        self.board.write(self.link_faults.apply(data))

    def read(self) -> bytes:
        return self.link_faults.apply(self.board.read())

    def advance(self, seconds: float) -> None:
        """Run firmware and plant together for ``seconds`` of virtual time: the whole plant
        steps that fit, a remainder shorter than a step carried over to the next call (as
        ``SimBoard.advance`` carries ticks). Rounding each call instead let the board's clock
        drift from its caller's: a link stepping 2 ms ran an 800 Hz robot's 2.5 ms plant step
        on every call, 1.25 s of firmware and plant per second of link clock."""
        self._pending_s += seconds
        n = int(self._pending_s / self.plant_dt_s + 1e-9)
        self._pending_s -= n * self.plant_dt_s
        for _ in range(n):
            self.step()

    @property
    def time_s(self) -> float:
        return self.board.time_s

    # -- the loop -----------------------------------------------------------------------
    def step(self) -> None:
        """One plant step: firmware ticks on the current truth, then the plant moves."""
        board = self.board
        board.run_ticks(self.ticks_per_step)
        duties = [board.pwm(ch) for ch in self.channels]
        self.plant.step(self.plant_dt_s, duties)
        self._push_truth()

    def run_ticks(self, n: int) -> None:
        """Exactly ``n`` control ticks (the plant advances by whole steps as they complete)."""
        for _ in range(n // self.ticks_per_step):
            self.step()
        self.board.run_ticks(n % self.ticks_per_step)

    def _push_truth(self) -> None:
        truth = self.plant.limb_truth
        for i, addr in enumerate(self.imu_addresses):
            self.board.imu_truth(addr, *truth(i))

    # -- fault injection ----------------------------------------------------------------
    def inject(self, fault: str) -> None:
        """Apply a fault by name; see ``FAULTS``."""
        _apply_fault(self, fault)

    def check_fault(self, fault: str, option: str = "--inject") -> None:
        """SimError (naming ``option`` and the fault) when ``inject(fault)`` would fail (an
        unknown fault, limb or coil), without injecting anything: a fault due later in a run
        is checked before the run starts."""
        try:
            _apply_fault(_dry_run(self), fault)
        except SimError as e:
            raise SimError(f"{option} {fault}: {e}") from None


def _dry_run(sim: SimulatedRobot) -> SimpleNamespace:
    """``sim``'s names, with every fault's effect a no-op (``check_fault``)."""
    def nothing(*_args: Any) -> None:
        return None

    return SimpleNamespace(robot=sim.robot, imu_addresses=sim.imu_addresses, link_faults=SimpleNamespace(),
                           board=SimpleNamespace(imu_fault=nothing),
                           plant=SimpleNamespace(kill_actuator=nothing, inject_drift=nothing))


def split_fault(fault: str) -> tuple[str, str]:
    """``FAULT[:ARG]`` → (the fault's name, ARG): the name with the spaces at its ends stripped
    (as ``--condition`` reads `` power = 0.8``), ``drift@RATE`` as ``drift`` with ``@RATE``."""
    name, _, arg = fault.partition(":")
    name = name.strip()
    if name.startswith("drift@"):  # drift@RATE: every actuator (drift[:ACTUATOR][@RATE])
        name, arg = "drift", name[len("drift"):] + (":" + arg if arg else "")
    return name, arg


def _apply_fault(sim: Any, fault: str) -> None:
    name, arg = split_fault(fault)
    if name not in FAULTS:
        raise SimError(f"unknown fault {fault!r} (expected one of: {', '.join(sorted(FAULTS))})")
    # a ':' with nothing after it is a name or number left out, not the fault's default: drift:
    # drifted every coil and link-drop: dropped 1 % of the bytes, as if the ':' were not there
    _, colon, rest = fault.partition(":")
    if colon and not rest.strip():
        raise SimError(f"nothing after ':' (expected {name}:{FAULT_ARGS[name]}, or {name} alone "
                       f"for {FAULT_DEFAULTS[name]})" if name in FAULT_DEFAULTS else
                       f"nothing after ':' (expected {name}:{FAULT_ARGS[name]})")
    if name == "drift" and colon and rest.strip().startswith("@") and not _names_coil(sim, rest):
        raise SimError("no actuator between ':' and '@' (expected drift:ACTUATOR@RATE, or drift@RATE for every coil)")
    FAULTS[name](sim, arg)


def _limb_addr(sim: SimulatedRobot, arg: str) -> int:
    """The IMU address of the limb ``arg`` names, read as ``--condition`` reads a limb
    (``resolve_name``): its name (spaces at its ends not counting), rear/front (the first and
    last limb) where no limb has that name, or its index."""
    from .physical.conditions import ALIASES, NoSuchName, resolve_name

    names = [limb.name for limb in sim.robot.limbs]
    try:
        return sim.imu_addresses[resolve_name(arg, names)]
    except NoSuchName:
        also = [a for a in ALIASES if a not in names]
        raise SimError(f"fault needs a limb ({', '.join([*names, *also])} or 0..{len(names) - 1}), "
                       f"got {arg.strip()!r}") from None


def _channel(sim: SimulatedRobot, arg: str) -> int:
    """The channel of the actuator ``arg`` names, as ``--condition`` reads a coil
    (``resolve_name``): its name or channel, a limb's name (that limb's coil), or rear/front
    (the first and last limb's coil) where no actuator or limb has that name (caterpillar-4's
    ``rear`` is its rear proleg's)."""
    from .physical.conditions import NoSuchName, coil_of_limb, resolve_name

    actuators = sim.robot.actuators
    name = arg.strip()
    for a in actuators:
        if name == a.name or (name.isdigit() and name == str(a.channel)):
            return a.channel
    try:
        return actuators[resolve_name(name, [a.name for a in actuators], coil_of_limb(sim.robot),
                                      [lb.name for lb in sim.robot.limbs], index=False)].channel
    except NoSuchName:
        raise SimError(
            f"fault needs an actuator ({', '.join(a.name for a in actuators)}, a limb's name, rear, front "
            f"or its channel), got {name!r}"
        ) from None


def _rate(arg: str, default: float, what: str, hi: float = math.inf) -> float:
    """``arg`` as a finite number in 0..``hi`` (``default`` when empty); ``what`` names it."""
    try:
        v = float(arg) if arg else default
    except ValueError:
        raise SimError(f"{what}: expected a number, got {arg!r}") from None
    if not (math.isfinite(v) and 0.0 <= v <= hi):
        raise SimError(f"{what}: expected a number {'≥ 0' if hi == math.inf else f'in 0..{hi:g}'}, got {arg!r}")
    return v


def _drift(sim: SimulatedRobot, arg: str) -> None:
    # drift:ACTUATOR@RATE: the rate after the last '@', unless the whole names an actuator or a
    # limb (a limb called front@pad, or leg@2): an '@' may be part of a name, as in --condition
    target, rate = arg, ""
    if "@" in arg and not _names_coil(sim, arg):
        target, _, rate = arg.rpartition("@")
        if not rate.strip():  # drift@ drifted at the default rate
            raise SimError("drift@RATE (per second of on-time): no rate after '@' (expected e.g. drift@0.05, or "
                           "drift alone for 0.05)")
    target, rate = target.strip(), rate.strip()
    channels = [a.channel for a in sim.robot.actuators] if target in ("", "all") else [_channel(sim, target)]
    r = _rate(rate, 0.05, "drift@RATE (per second of on-time)")
    for ch in channels:
        sim.plant.inject_drift(ch, r)


def _names_coil(sim: SimulatedRobot, arg: str) -> bool:
    try:
        _channel(sim, arg)
    except SimError:
        return False
    return True


#: What follows a fault's ':', for the messages that name it.
FAULT_ARGS = {"imu-silent": "LIMB", "imu-stuck": "LIMB", "imu-garbage": "LIMB", "dead-actuator": "ACTUATOR",
              "drift": "ACTUATOR[@RATE]", "link-drop": "P", "link-corrupt": "P"}
#: What a fault without its ':' part does, where it may go without.
FAULT_DEFAULTS = {"drift": "every coil", "link-drop": "P = 0.01", "link-corrupt": "P = 0.01"}

FAULTS = {
    # imu-silent:LIMB — the IMU stops acknowledging on I2C
    "imu-silent": lambda sim, arg: sim.board.imu_fault(_limb_addr(sim, arg), "no-ack"),
    # imu-stuck:LIMB — the IMU returns the same bytes forever
    "imu-stuck": lambda sim, arg: sim.board.imu_fault(_limb_addr(sim, arg), "stuck"),
    # imu-garbage:LIMB — the IMU returns random bytes
    "imu-garbage": lambda sim, arg: sim.board.imu_fault(_limb_addr(sim, arg), "garbage"),
    # dead-actuator:ACTUATOR — the SMA coil no longer heats
    "dead-actuator": lambda sim, arg: sim.plant.kill_actuator(_channel(sim, arg)),
    # drift[:ACTUATOR|all][@RATE] — the SMA's heating response weakens with use
    "drift": _drift,
    # link-drop[:P] / link-corrupt[:P] — bytes dropped / bit-flipped on the serial link
    "link-drop": lambda sim, arg: setattr(sim.link_faults, "drop", _rate(arg, 0.01, "link-drop:P (a probability)", 1.0)),
    "link-corrupt": lambda sim, arg: setattr(sim.link_faults, "corrupt",
                                             _rate(arg, 0.01, "link-corrupt:P (a probability)", 1.0)),
}
