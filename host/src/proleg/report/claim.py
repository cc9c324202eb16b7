"""The paper's central claim, measured: ψ-feedback firmware vs the best timed open-loop drive
on the physical plant, over a grid of drift modes and sensor/world errors.

``GRID`` lists the conditions (every mode singly at two strengths, and pairs); ``run_condition``
runs both drives under one of them from a cold robot and reports each as completed or stopped
(with the firmware's fault, or why the open loop stopped walking) and its speed in mm/s;
``physically_possible`` says whether the coils can complete the gait's transformations at all
under the condition, within the firmware's safety envelope (an idealised drive with perfect
sensing held to the envelope's rules, ``drive.run_sequence(envelope=True)``) and, if not,
why; a condition the firmware itself completes is possible whatever the idealised drive says. The open-loop drive is tuned once on the fresh robot by ``openloop.
tune_open_loop_robust`` (all 4N − 1 timing parameters free, scored on its worst speed over
±10 % power so that no knife-edge timing wins). ``bench/bench_claim.py`` runs the whole grid;
``hil_tests/test_drift_and_safety.py`` a handful of points.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field
from typing import Any

from ..errors import SimError
from ..names import counted
from ..sim.openloop import OpenLoopDrive, tune_open_loop_robust
from ..physics.materials import NITI_OVERHEAT_C, shown_c

RUN_S = 40.0        # each run, from a cold robot (at least; run_length: a long gait's runs are longer)
#: A run holds at least this many of the nominal gait's cycles (a run completes with two).
CYCLES_PER_RUN = 4
#: How an open-loop run that overheated a coil is noted (``DriveOutcome.note`` starts so).
OVERHEATED = "coil overheated"
OVERHEAT_C = NITI_OVERHEAT_C  # an open-loop coil above this is ruined (physics/materials.py)


@dataclass(frozen=True)
class GridPoint:
    """One condition: ``conditions`` (``key=value`` strings, docs/plant.md) and ``faults``
    (``SimulatedRobot.inject`` names, applied at the start, e.g. ``drift:all@0.02``)."""

    name: str
    modes: tuple[str, ...]
    strength: str                  # "mild" or "strong"
    conditions: tuple[str, ...] = ()
    faults: tuple[str, ...] = ()


# mode -> (mild, strong): each a tuple of conditions or of "!fault" entries
MODES: dict[str, tuple[tuple[str, ...], tuple[str, ...]]] = {
    "supply sag": (("power=0.85",), ("power=0.7",)),
    "supply boost": (("power=1.15",), ("power=1.3",)),
    "source resistance": (("supply_ohm=3",), ("supply_ohm=8",)),
    "draught": (("convection=1.25",), ("convection=1.6",)),
    "enclosure": (("convection=0.8",), ("convection=0.6",)),
    "hot ambient": (("ambient_c=30",), ("ambient_c=38",)),
    "cold ambient": (("ambient_c=15",), ("ambient_c=5",)),
    "fatigue": (("fatigue_cycles=5000",), ("fatigue_cycles=30000",)),
    "coil mismatch": (("coil_mismatch=0.1",), ("coil_mismatch=0.25",)),
    "weak coil": (("power_scale=rear:0.85",), ("power_scale=rear:0.7",)),
    "asymmetric coupling": (("overlap_mm=rear:14",), ("overlap_mm=rear:22",)),
    "imu mounting offset": (("imu_offset_deg=front:3",), ("imu_offset_deg=front:6",)),
    "imu bias": (("imu_bias_deg=rear:-3",), ("imu_bias_deg=rear:-6",)),
    "imu noise": (("imu_noise_deg=0.5",), ("imu_noise_deg=1.5",)),
    "incline": (("incline_deg=5",), ("incline_deg=10",)),
    "decline": (("incline_deg=-5",), ("incline_deg=-10",)),
    "psi* shift": (("psi_star_shift_deg=front:3",), ("psi_star_shift_deg=front:6",)),
    "slippery ground": (("friction=0.6",), ("friction=0.35",)),
    "heavier body": (("mass_g=5",), ("mass_g=8",)),
    "sma drift with use": (("!drift:all@0.01",), ("!drift:all@0.03",)),
    # beyond what the coils can do: the firmware must stop with a fault and cold coils
    "supply collapse": (("power=0.35",), ("power=0.2",)),
    "dead coil": (("!dead-actuator:front",), ("!dead-actuator:rear",)),  # R1: sma-right, sma-left
}

PAIRS: tuple[tuple[str, str], ...] = (
    ("supply sag", "hot ambient"),
    ("supply sag", "draught"),
    ("supply boost", "enclosure"),
    ("hot ambient", "enclosure"),
    ("fatigue", "supply sag"),
    ("imu bias", "incline"),
    ("imu mounting offset", "imu noise"),
    ("weak coil", "asymmetric coupling"),
    ("psi* shift", "cold ambient"),
    ("coil mismatch", "source resistance"),
    ("sma drift with use", "hot ambient"),
    ("slippery ground", "incline"),
)


def _point(modes: Sequence[str], strength: str) -> GridPoint:
    k = 0 if strength == "mild" else 1
    conds: list[str] = []
    faults: list[str] = []
    for m in modes:
        for item in MODES[m][k]:
            (faults.append(item[1:]) if item.startswith("!") else conds.append(item))
    return GridPoint(" + ".join(modes) + f" ({strength})", tuple(modes), strength, tuple(conds), tuple(faults))


#: Modes run only in their pairs: alone they are the nominal robot on this plant (a uniform
#: friction scale on level ground scales every contact's capacity alike, and the quasi-static
#: anchor/slip solve does not change), so a row of their own would count a pass it cannot fail.
PAIRED_ONLY = frozenset({"slippery ground"})


def grid() -> list[GridPoint]:
    """Every mode singly at two strengths (but ``PAIRED_ONLY``), then the pairs at two strengths."""
    out = [_point((m,), s) for m in MODES if m not in PAIRED_ONLY for s in ("mild", "strong")]
    out += [_point(p, s) for p in PAIRS for s in ("mild", "strong")]
    return out


NOMINAL = GridPoint("nominal", (), "none")

#: The best open-loop drive for R1 +x that ``tune_open_loop_for(R1, "+x", budget=150)`` finds
#: (bench/bench_claim.py re-tunes it on every run and prints it; bench/results/claim.json): both
#: coils together, left at 0.8 and right at 0.6, 1.0 s on in a 4 s cycle: a full-stroke inchworm
#: through 00 → 10 → 11 → 10 → 00, ≈ 4.2 mm/s at its worst over ±10 % power. The hil test of the
#: central claim replays it rather than re-tuning (≈ 1–3 min).
TUNED_R1_PLUS_X = OpenLoopDrive((0.8, 0.6), (1.0, 1.0), (4.0, 4.0), (0.0, 0.0), (0, 1))


def point(name: str) -> GridPoint:
    """The grid point called ``name`` (e.g. "supply sag (strong)")."""
    for p in grid():
        if p.name == name:
            return p
    raise SimError(f"claim grid: no point {name!r}")


# ---------------------------------------------------------------------------------------------
@dataclass
class DriveOutcome:
    completed: bool
    speed_mm_s: float
    displacement_mm: float
    fault: str = ""          # the fault codes of a run a fault stopped (ψ-feedback only; "" = none)
    note: str = ""           # why a run without a fault did not complete (wrong way, stalled, overheated)
    coil_max_end_c: float = 0.0   # hottest coil 2 s after the run (cold coils after a fault)
    coil_peak_c: float = 0.0
    reported: str = ""       # fault events of a run no fault stopped (a single on-limit hit): codes ×count


@dataclass
class ConditionResult:
    point: GridPoint
    possible: bool
    why_not: str
    feedback: DriveOutcome
    open_loop: DriveOutcome
    extra: dict[str, Any] = field(default_factory=dict)
    idealised_mm_s: float | None = None   # the idealised drive's speed (``idealised_walk``)

    def to_json(self) -> dict:
        return {"name": self.point.name, "modes": list(self.point.modes), "strength": self.point.strength,
                "conditions": list(self.point.conditions), "faults": list(self.point.faults),
                "physically_possible": self.possible, "why_not": self.why_not,
                "idealised_drive_mm_s": _speed(self.idealised_mm_s),
                "feedback": _round(asdict(self.feedback)), "open_loop": _round(asdict(self.open_loop)),
                **self.extra}


def _speed(v: float | None) -> float | None:
    return None if v is None else round(v, 4)


def _round(d: dict) -> dict:
    return {k: round(v, 4) if isinstance(v, float) else v for k, v in d.items()}


def gait_states(robot: Any, direction: str = "+x", gait: int | Sequence[int] = 0) -> tuple[int, ...]:
    """The states of firmware gait ``gait``, or ``gait`` itself when it is a state sequence."""
    if not isinstance(gait, int):
        return tuple(gait)
    from ..firmware.build import firmware_gaits

    return tuple(firmware_gaits(robot)[direction][gait].states)


def learned_gait(robot: Any, direction: str = "+x") -> tuple[tuple[int, ...], Any]:
    """The gait a user gets from learn-then-walk on the fresh robot: the reward matrix the
    simulator measures (``proleg sim ROBOT --measure-matrix``: every allowed transition driven
    to its state, mm and seconds), then the optimal gait of that matrix (objective "total",
    the firmware's default, with its bound on the cycle's length). Returns (closed state
    sequence, MeasuredMatrix)."""
    from ..sim.physical.measure import measure_matrix

    m = measure_matrix(robot)
    return optimal_gait_of(robot, m, direction), m


def optimal_gait_of(robot: Any, measured: Any, direction: str = "+x") -> tuple[int, ...]:
    """The optimal gait (objective "total", bounded as the firmware bounds it on a larger
    robot) of a matrix the simulator measured: its allowed entries that have a value."""
    import numpy as np

    from ..firmware.gaits import default_max_transitions
    from ..gait.optimal import optimal_gaits
    from ..transitions import TransitionTable

    _, allowed = robot.transitions.dense()
    ok = np.isfinite(measured.matrix_mm)
    table = TransitionTable.from_dense(robot.levels, np.where(ok, measured.matrix_mm, 0.0),
                                       np.asarray(allowed) & ok,
                                       np.where(np.isfinite(measured.duration_s), measured.duration_s, 1.0))
    gaits = list(optimal_gaits(table, "total", direction, default_max_transitions(robot, "total")).gaits)
    if not gaits:
        raise SimError(f"claim: the measured matrix of {robot.name} has no gait in {direction}")
    return tuple(gaits[0].states)


def _plant(robot: Any, point: GridPoint, extra: Sequence[str] = ()) -> Any:
    from ..sim.closed_loop import make_plant

    plant = make_plant(robot, "physical", [*point.conditions, *extra])
    for f in point.faults:
        _plant_fault(robot, plant, f)
    return plant


def _plant_fault(robot: Any, plant: Any, fault: str) -> None:
    name, _, arg = fault.partition(":")
    if name == "drift":
        target, _, rate = arg.partition("@")
        chans = [a.channel for a in robot.actuators if target in ("", "all", a.name)]
        for ch in chans:
            plant.inject_drift(ch, float(rate or 0.05))
    elif name == "dead-actuator":  # rear/front: the first/last limb's coil, as the conditions name them
        from ..sim.physical.conditions import actuator_index

        plant.kill_actuator(robot.actuators[actuator_index(robot, arg)].channel)
    else:
        raise SimError(f"claim grid: fault {fault!r} is not a plant fault")


@dataclass(frozen=True)
class IdealisedWalk:
    """What the idealised drive did under a condition (``idealised_walk``)."""

    possible: bool
    why_not: str
    speed_mm_s: float | None   # its steady speed, None where it could not reach a state
    s_per_cycle: float | None = None   # its steady cycle's length, where it walked one


def run_length(nominal: IdealisedWalk) -> float:
    """How long each run of the bench lasts (s), from the idealised drive's walk on the nominal
    robot (``idealised_walk(robot, NOMINAL)``): ``RUN_S``, or ``CYCLES_PER_RUN`` of its cycles
    where those are longer (caterpillar-4's twelve steps take ≈ 15 s: in 40 s a slowed row
    finished one cycle and counted as not completed)."""
    cycle = nominal.s_per_cycle
    return RUN_S if cycle is None else max(RUN_S, math.ceil(CYCLES_PER_RUN * cycle / 5.0) * 5.0)


def physically_possible(robot: Any, point: GridPoint, direction: str = "+x",
                        gait: int | Sequence[int] = 0) -> tuple[bool, str]:
    """Can the coils complete the gait's transformations under ``point`` at all, within the
    firmware's safety envelope? (``idealised_walk``'s verdict and reason.)"""
    walk = idealised_walk(robot, point, direction, gait)
    return walk.possible, walk.why_not


def idealised_walk(robot: Any, point: GridPoint, direction: str = "+x",
                   gait: int | Sequence[int] = 0) -> IdealisedWalk:
    """An idealised drive (true ψ, true ψ*, the firmware's drive duty, the envelope's on-time
    debt, mean-duty window and state timeout: ``sim.physical.envelope``) walks the gait under
    ``point``: its speed, and whether the coils can complete the gait's transformations at all.
    If it cannot reach a state, or the gait then moves the wrong way, the reason: a dead coil,
    the hottest steady temperature the supply gives the coil against its transformation
    temperatures, the envelope's rule that stops it, or else the end's angle the stroke reaches.

    The speed is not a ceiling (the drive settles 0.3 s in every state and holds 4° past ψ*,
    or at the strokes), but it has no sensing errors and no stall rules: how much a condition
    slows the gait itself, whatever drives it."""
    from ..sim.physical.drive import walk_within_envelope

    plant = _plant(robot, point)
    walk = walk_within_envelope(robot, gait_states(robot, direction, gait), plant)
    mm, s = walk.mm_per_cycle, walk.s_per_cycle
    if mm is not None:
        speed = mm / s if s else 0.0
        if (1 if direction == "+x" else -1) * mm > 0:
            return IdealisedWalk(True, "", speed, s)
        return IdealisedWalk(False, f"the coils complete the gait, but even an ideal drive (true ψ) moves {mm:+.2f} "
                                    f"mm per cycle: under this condition the gait does not go {direction}", speed)
    return IdealisedWalk(False, _why_not_walked(robot, plant, walk.latched), None)


def _why_not_walked(robot: Any, plant: Any, latched: str) -> str:
    from ..sim.plant_warnings import rise_duty

    # the hottest duty the firmware gives a rise for good: the duty ceiling where it boosts a
    # lagging one, the mean-duty ceiling where the coil's heat ceiling holds it there
    duty, _ = rise_duty(robot)
    hot = plant.steady_coil_temperature_c(duty)
    tr = plant.transformation_c()
    for j, a in enumerate(robot.actuators):
        as_c, af_c = tr[j]
        if not plant.alive[j]:
            return f"coil {a.name} does not heat (dead coil): its limb cannot leave level 0"
        if hot[j] < as_c + 0.5 * (af_c - as_c):
            return (f"the supply heats coil {a.name} to at most {hot[j]:.0f} °C at duty {duty:g} "
                    f"(As {as_c:.0f} °C, Af {af_c:.0f} °C): it cannot transform far enough")
    if latched:
        return f"the coils could transform, but not within {latched}"
    return "the coils transform, but the ends do not reach ψ* (stroke lost or ψ* out of reach)"


#: Seconds the robot rests on the condition's ground before START (as a user puts it down and
#: starts it): longer than the 2 s the firmware needs to level itself there.
REST_ON_GROUND_S = 2.5


def feedback_run(robot: Any, point: GridPoint, *, direction: str = "+x", gait: int | Sequence[int] = 0,
                 duration_s: float = RUN_S, seed: int = 1, calibrate: bool = True,
                 level_on_ground: bool = False, board: str = "host-sim") -> DriveOutcome:
    """The ψ-feedback firmware on the simulated ``board`` (host-sim, or the exact MCU image on
    avr-emu / arm-emu), physical plant under ``point``.

    ``gait``: a firmware gait index, or a state sequence loaded with LOAD_GAIT (learn-then-walk).
    ``calibrate``: first what a user does (docs/calibration.md): the robot on FLAT ground, at
    rest, ``proleg calibrate`` (the firmware records each IMU's rest tilt: mounting offset and
    bias); then it is put on the condition's ground (incline), rests there REST_ON_GROUND_S,
    and walks. ``level_on_ground``:
    on that ground, at rest, ``proleg calibrate --ground`` too (the slope, in RAM)."""
    from ..link.level import calibrate_level
    from ..protocol.definition import GAIT_USER
    from ..sim.closed_loop import SimulatedRobot
    from .gait_run import SimSession

    flat = GridPoint(point.name, point.modes, point.strength,
                     tuple(c for c in point.conditions if not c.startswith("incline_deg=")), point.faults)
    first = _plant(robot, flat if calibrate else point)
    if board == "host-sim":
        sim = SimulatedRobot(robot, seed=seed, plant=first)
    else:
        from ..sim.simulated_boards import simulated_robot

        sim = simulated_robot(board, robot, seed=seed, plant=first)
    session = SimSession(sim)
    cal_note = ""
    if calibrate:
        session.advance(0.2)
        try:
            outcome = calibrate_level(session.client)
            if not outcome.ok:
                cal_note = f"flat calibration refused: {outcome}"
        except Exception as e:  # noqa: BLE001 - a refused calibration is a result, reported
            cal_note = f"flat calibration failed: {e}"
        if flat != point:
            sim.plant = _plant(robot, point)  # onto the slope, cold and at rest
            # put down, a moment's rest before START: the firmware levels itself on a ground
            # it has rested on for 2 s (docs/calibration.md, "On a slope")
            session.advance(REST_ON_GROUND_S)
            if level_on_ground:
                session.advance(0.3)
                try:
                    outcome = calibrate_level(session.client, ground=True)
                    if not outcome.ok:
                        cal_note = f"ground levelling refused: {outcome}"
                except Exception as e:  # noqa: BLE001 - reported, like the flat calibration
                    cal_note = f"ground levelling failed: {e}"
    if not isinstance(gait, int):
        states = list(gait)
        session.client.load_gait(states[:-1] if len(states) > 1 and states[0] == states[-1] else states)
        gait = GAIT_USER
    session.advance(0.2)
    run = session.run_gait(direction, gait, duration_s)
    session.advance(2.0)
    # Stopped: a fault latched and stopped the gait (GAIT_STOPPED FAULT), or a command was
    # refused. A FAULT event with no stop is a report (a single on-limit hit: docs/safety.md):
    # the gait went on, and the row says so (``reported``).
    codes = ", ".join(sorted({f.code for f in run.faults}))
    stopped = run.fault_stops > 0 or bool(run.errors)
    faults = codes if stopped else ""
    if run.errors:
        faults = (faults + "; " if faults else "") + "; ".join(run.errors)
    speed = run.displacement_mm / duration_s
    sign = 1 if direction == "+x" else -1
    completed = not faults and run.cycles >= 2 and sign * speed > 0
    note = ""
    if not faults and not completed:
        note = "walks the wrong way (no fault)" if sign * speed <= 0 else f"only {counted(run.cycles, 'cycle')} (no fault)"
    reported = f"{codes} ×{len(run.faults)}" if codes and not stopped else ""
    peak = max(sim.plant.peak_temperature_c)  # since the plant was made: the coils were cold before START
    if peak > OVERHEAT_C:  # the open loop's line (open_loop_run): a run that ruins a coil did not complete
        completed = False
        note = (note + "; " if note else "") + f"{OVERHEATED} ({shown_c(peak)} °C)"
    if cal_note:
        note = (note + "; " if note else "") + cal_note
    return DriveOutcome(completed, speed, run.displacement_mm, faults, note,
                        float(max(sim.plant.temperature_c)), peak, reported)


def open_loop_run(robot: Any, drive: OpenLoopDrive, point: GridPoint, *, direction: str = "+x",
                  gait: int = 0, duration_s: float = RUN_S, dt_s: float = 0.01) -> DriveOutcome:
    """The timed drive replayed on the physical plant under ``point``: completed if the robot
    still changes state in the last third of the run, moves in ``direction`` over the run and
    no coil overheats (> ``OVERHEAT_C``). (The open loop need not walk the firmware's gait:
    any sequence that moves the robot counts.)"""
    plant = _plant(robot, point)
    nch = max(a.channel for a in robot.actuators) + 1
    n = int(round(duration_s / dt_s))
    for i in range(n):
        plant.step(dt_s, drive.duties(i * dt_s, nch))
    peak = max(plant.peak_temperature_c)  # every step, as feedback_run reads the firmware's
    x = plant.displacement_mm
    late = [tr for tr in plant.transitions if tr.t_s > duration_s * 2 / 3]
    sign = 1 if direction == "+x" else -1
    why = ""
    if peak > OVERHEAT_C:
        why = f"{OVERHEATED} ({shown_c(peak)} °C)"
    elif not late:
        why = f"stalled: no state change in the last third (stuck in {robot.transitions.label(plant.true_state)})"
    elif sign * x <= 0:
        why = "walks the wrong way"
    for _ in range(int(2.0 / dt_s)):
        plant.step(dt_s, [0.0] * nch)
    return DriveOutcome(not why, x / duration_s, x, "", why, float(max(plant.temperature_c)), peak)


def tune_open_loop_for(robot: Any, direction: str = "+x", *, budget: int = 150, dt_s: float = 0.01,
                       run_s: float = RUN_S):
    """The best timed drive on the fresh robot (``openloop.tune_open_loop_robust``) among
    those that keep every coil at or below ``OVERHEAT_C``, as ``open_loop_run`` judges them."""
    from ..sim.closed_loop import make_plant

    def factory(power: float) -> Any:
        return make_plant(robot, "physical", [f"power={power:g}"])

    channels = tuple(a.channel for a in robot.actuators)
    return tune_open_loop_robust(factory, channels, +1 if direction == "+x" else -1,
                                 max_duty=robot.safety.max_duty, budget=budget, dt_s=dt_s, run_s=run_s,
                                 max_coil_c=OVERHEAT_C)


def _proved_by_the_firmware(possible: bool, why: str, fb: DriveOutcome) -> tuple[bool, str, dict[str, Any]]:
    """The firmware keeps to the envelope too: its own completed run proves a condition
    possible whatever the idealised drive said (the row says so, with the drive's reason)."""
    if possible or not fb.completed:
        return possible, why, {}
    return True, "", {"possible_by": "the firmware's own run", "idealised_drive_why_not": why}


def run_condition(robot: Any, drive: OpenLoopDrive, point: GridPoint, *, direction: str = "+x",
                  gait: int = 0, duration_s: float = RUN_S,
                  learned: Sequence[int] | None = None) -> ConditionResult:
    """Both drives under ``point``; ``learned``: also the ψ-feedback firmware walking that
    state sequence (the learn-then-walk gait, ``learned_gait``), reported in ``extra``."""
    ideal = idealised_walk(robot, point, direction, gait)
    possible, why = ideal.possible, ideal.why_not
    fb = feedback_run(robot, point, direction=direction, gait=gait, duration_s=duration_s)
    ol = open_loop_run(robot, drive, point, direction=direction, gait=gait, duration_s=duration_s)
    possible, why, extra = _proved_by_the_firmware(possible, why, fb)
    if any(c.startswith("incline_deg=") for c in point.conditions):
        gfb = feedback_run(robot, point, direction=direction, gait=gait, duration_s=duration_s, level_on_ground=True)
        extra["levelled_on_ground"] = {"feedback": _round(asdict(gfb))}
    if learned is not None:
        lideal = idealised_walk(robot, point, direction, learned)
        lfb = feedback_run(robot, point, direction=direction, gait=learned, duration_s=duration_s)
        lp, lwhy, lextra = _proved_by_the_firmware(lideal.possible, lideal.why_not, lfb)
        extra["learned_gait"] = {"states": list(learned), "physically_possible": lp, "why_not": lwhy,
                                 "idealised_drive_mm_s": _speed(lideal.speed_mm_s),
                                 "feedback": _round(asdict(lfb)), **lextra}
    return ConditionResult(point, possible, why, fb, ol, extra, ideal.speed_mm_s)


def summarise(results: Sequence[ConditionResult], nominal: ConditionResult) -> dict[str, Any]:
    """The targets of issue 13, counted (``claim_summary.summarise``)."""
    from .claim_summary import summarise as counts

    return counts(results, nominal)
