"""Can each limb get where the controller asks, on the simulated body (``proleg.body``)? Part of
the robot file's plausibility checks (``robot_body``), warnings, not refusals:

* ``reach_warnings`` (the body built and bent once for both): ``unreachable_levels``, a limb
  whose own coil, at full stroke, cannot bend it to its top level (or a body too long for the
  model: ``body.curl_problem``);
  and ``unreachable_holds``, a limb that reaches its top level but not the hold top the
  controller heats it to (``control.hold_margin_deg``), even with every coil at full stroke;
* ``worn_holds``: limbs whose hold top a worn coil may fall short of (the firmware's hold watch);
* ``unreachable_states``: states the matrix enters in which a raised limb cannot get to its
  level even with the coils of every raised limb at full stroke (a limb on another limb's
  coil, which bends the body at that limb: ``unreachable_levels`` warns about the limb); the
  feasibility check refuses a step into one (``unreachable``), so the build does not choose
  such a gait as gait 0; ``unreachable_strokes``, a ``stroke_deg`` out of reach in such a state.

``body_of`` is the physical plant's body for a robot's limbs, coils and ``[plant]`` table.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from .body import (DEFAULT_OVERLAP_MM, BodyGeometry, Shape, body_geometry, coil_homes, curl_key, curl_problem,
                   own_reach_deg)
from .robot_plant import PlantSection


def body_of(limb_actuators: list[int], n_actuators: int, section: PlantSection) -> BodyGeometry:
    """The physical plant's body for these limbs and coils (``[plant]`` length_mm, overlap_mm,
    working_strain)."""
    overlap = section.physical.get("overlap_mm", DEFAULT_OVERLAP_MM)
    overlaps = list(overlap) if isinstance(overlap, tuple) else [float(overlap)] * n_actuators
    return body_geometry(limb_actuators, n_actuators, section.length_mm, overlaps,
                         working_strain=section.working_strain)


def reach_warnings(path: Path, limbs: list[Any], actuators: list[str], section: PlantSection,
                   hold_margin_deg: float) -> list[str]:
    """The physical plant's body (``proleg.body``) against what the controller asks of each
    limb, computed once: ``unreachable_levels``' lines, then ``unreachable_holds``' for the
    limbs whose top level is in reach. Warnings about the simulator and the plausibility of the
    file, not refusals: a real body may bend further. A body too long for the model (it would
    curl over itself, so every reach is a wrapped angle) is one line saying so instead."""
    limb_actuators = [actuators.index(lb.actuator) for lb in limbs]
    if len(limbs) < 2:
        return []
    reach = body_reach(limb_actuators, len(actuators), section, actuators)
    if isinstance(reach, str):
        return [f"{path}: plant.{curl_key(section.given)}: {reach} (gait and build go on; the physical plant of "
                "`proleg sim` and `learn --sim` refuses such a body, `--plant table` runs it)"]
    own, full = reach
    return (unreachable_levels(path, limbs, limb_actuators, len(actuators), own, section) +
            unreachable_holds(path, limbs, own, full, section, hold_margin_deg))


def body_reach(limb_actuators: list[int], n_actuators: int, section: PlantSection,
               names: Sequence[str] = ()) -> tuple[list[float], list[float]] | str:
    """ψ per limb on the physical plant's body: ``(own, full)``, with only the limb's own coil
    at full stroke and with every coil at full stroke; or, for a body too long for the model,
    why (``body.curl_problem``, naming the coil by ``names``: the actuators' names)."""
    geo = body_of(limb_actuators, n_actuators, section)
    curl = curl_problem(geo, names)
    if curl:
        return curl
    own = own_reach_deg(geo, limb_actuators)
    shape = Shape(geo, tabulate=False)
    return own, [float(p) for p in shape.compute(np.ones((1, shape.n_coils)))[0][0]]


def hold_top_deg(limb: Any, hold_margin_deg: float) -> float:
    """Where the controller heats a held limb's top level to (docs/control.md): its top
    threshold's upper band edge, ψ*_top + hysteresis/2, plus ``hold_margin_deg`` + 1°."""
    return limb.psi_star_deg[-1] + limb.hysteresis_deg / 2.0 + hold_margin_deg + 1.0


def unreachable_levels(path: Path, limbs: list[Any], limb_actuators: list[int], n_actuators: int,
                       own: list[float], section: PlantSection) -> list[str]:
    """One line per limb whose top level its own coil cannot reach: the top level is entered at
    ψ*_top + hysteresis/2, and ``own`` is ψ with the limb's coil at full stroke and every other
    coil cold (a state with only this limb raised must be reachable)."""
    homes = coil_homes(limb_actuators, n_actuators)
    out = []
    for i, (lb, r) in enumerate(zip(limbs, own)):
        need = lb.psi_star_deg[-1] + lb.hysteresis_deg / 2.0
        if need <= r:
            continue
        head = (f"{path}: limb {lb.name!r}: its top level needs ψ ≥ {need:.1f}° "
                f"(ψ* {lb.psi_star_deg[-1]:g}° + hysteresis/2), its own coil "
                f"{lb.actuator!r} bends it to {r:.1f}° on the simulated {section.length_mm:g} mm body: ")
        home = homes[limb_actuators[i]]
        if home != i:  # a shared coil: one [[actuator]] is one coil, at the first limb naming it
            out.append(head + f"in the model that coil sits at limb {limbs[home].name!r} (one [[actuator]] is one "
                              f"coil, at the first limb that names it); give {lb.name!r} a coil of its own")
        else:
            out.append(head + "lower psi_star_deg, or describe the body in [plant] (length_mm, working_strain)")
    return out


#: How far below its reach a hold top must lie for the hold to end by reaching it: the end's
#: ψ creeps to its last tenths of a degree only as the coil's temperature settles, and
#: a sample of IMU noise above the top is no plan.
HOLD_TOP_CLEARANCE_DEG = 0.5


def _at_most(x: float) -> str:
    """``x`` to the tenth of a degree below it, as advice to write into the robot file: rounded
    to the nearest, 30.06° printed 30.1, and that stroke (or margin) was warned of again."""
    return f"{math.floor(x * 10.0 + 1e-9) / 10.0:.1f}"


def unreachable_holds(path: Path, limbs: list[Any], own: list[float], full: list[float], section: PlantSection,
                      hold_margin_deg: float) -> list[str]:
    """One line per limb whose top level it can reach but whose hold top it cannot with every
    coil at full stroke (``full``): the controller holds a raised limb by heating its coil until
    ψ ≥ ψ*_top + hysteresis/2 + ``hold_margin_deg`` + 1° (the hold top, docs/control.md), or its
    ``stroke_deg``. Short of it the coil heats at every step until the step's hover clock
    lets the gait go on (300 ms), past its transformation: the one-actuator R1's far end bends
    to 23.5° with the default 4° margin's hold top at 26°, and its coil reached 107 °C at every
    step (claim bench, nominal). The hold watch (``worn_holds``, built in wherever this warns)
    then stops heating it where it stopped, short of the hold top. A limb with a stroke is held at its stroke and not
    checked here; a level out of its own coil's reach (``own``) is ``unreachable_levels``'."""
    out = []
    for lb, r, o in zip(limbs, full, own):
        entry = lb.psi_star_deg[-1] + lb.hysteresis_deg / 2.0
        top = hold_top_deg(lb, hold_margin_deg)
        if getattr(lb, "stroke_deg", None) is not None or min(o, r) < entry or top + HOLD_TOP_CLEARANCE_DEG <= r:
            continue  # a stroke, a level out of reach (unreachable_levels' or the body's), or a hold top in reach
        fit = r - HOLD_TOP_CLEARANCE_DEG - 1.0 - entry
        advice = (f"set control.hold_margin_deg to at most {_at_most(max(fit, 0.0))}" if fit >= 0.0 else
                  f"its top level is entered within {r - entry:.1f}° of its reach: lower psi_star_deg")
        out.append(f"{path}: limb {lb.name!r}: held raised, its coil heats until ψ ≥ {top:.1f}° (ψ* "
                   f"{lb.psi_star_deg[-1]:g}° + hysteresis/2 + control.hold_margin_deg {hold_margin_deg:g}° + 1°), "
                   f"but every coil at full stroke bends it to {r:.1f}° on the simulated {section.length_mm:g} mm "
                   f"body: at every step its coil heats past its transformation until the step's hover clock "
                   f"lets the gait go on, and the firmware's hold watch then holds the limb short of its hold "
                   f"top with the coil off; {advice}")
    return out


#: The recoverable stroke a worn coil has lost: the physical plant's fatigue law after many cycles
#: (``proleg.physics.params.FatigueLaw.stroke_loss``, which a test keeps equal to this:
#: Lagoudas (ed.), "Shape Memory Alloys", Springer 2008, ch. 7; Mammano & Dragoni, Int. J.
#: Fatigue 2014). Here, not imported: the robot file's checks sit below the simulator.
WORN_STROKE_LOSS = 0.25


def worn_holds(limbs: list[Any], actuators: list[str], section: PlantSection, hold_margin_deg: float) -> list[int]:
    """The limbs (indices) whose hold top a worn coil may fall short of on the simulated body:
    without a ``stroke_deg``, their hold top (ψ*_top + hysteresis/2 + ``hold_margin_deg`` + 1°)
    lies above what their reach (their own coil's and every coil's, the lesser) keeps after a
    worn coil's stroke loss (``WORN_STROKE_LOSS``, 25 %; ψ taken as proportional to the
    coil's contraction). The firmware is built with its hold watch where any such limb exists
    (``CFG_HOLD_WATCH``, core/ctl.h): a held limb that stopped short of its hold edge is held where
    it stopped instead of heated on. A body the model cannot describe counts every limb."""
    return [i for i in _worn_short(limbs, actuators, section, hold_margin_deg)
            if getattr(limbs[i], "stroke_deg", None) is None]


def _worn_short(limbs: list[Any], actuators: list[str], section: PlantSection, hold_margin_deg: float) -> list[int]:
    """The limbs (indices) whose top a worn coil may fall short of: a limb is held at its
    ``stroke_deg`` where it has one, else at its hold top (``worn_holds``), and either lies
    above what its reach keeps after ``WORN_STROKE_LOSS``; every limb on a body the model cannot
    describe. Where the boost is off by default (``boost_ms_of``) or warned of: such a coil lags
    at the end of its travel short of its top. inchworm-3 with ``stroke_deg = 29`` on every limb
    (own reach 31.1°, 23.3° worn), the boost on, worn by 7,220 cycles at 6 °C ambient: its tail
    coil reached 126 °C (106 °C without the boost); at 100,000 cycles and 0 °C 133 °C (98 °C).
    With ``stroke_deg = 27`` on a 100 mm body (38.1°, 28.6° worn) the boost keeps both rows at
    82-87 °C."""
    if len(limbs) < 2:
        return []
    reach = body_reach([actuators.index(lb.actuator) for lb in limbs], len(actuators), section)
    if isinstance(reach, str):
        return list(range(len(limbs)))
    kept = 1.0 - WORN_STROKE_LOSS

    def top(lb: Any) -> float:
        stroke = getattr(lb, "stroke_deg", None)
        return hold_top_deg(lb, hold_margin_deg) if stroke is None else stroke

    return [i for i, lb in enumerate(limbs) if top(lb) > kept * min(reach[0][i], reach[1][i])]


def worn_holds_of(robot: Any) -> list[int]:
    """``worn_holds`` of a loaded robot, with its own hold margin; none for a robot without
    its [plant] table."""
    if getattr(robot, "plant", None) is None:
        return []
    return worn_holds(list(robot.limbs), [a.name for a in robot.actuators], robot.plant,
                      float(robot.control.hold_margin_deg))


def boost_ms_of(robot: Any) -> int:
    """How long a rise may lag before the firmware heats it at safety.max_duty (CTL_BOOST_MS; 0:
    no boost, none of its code). The robot file's control.boost_ms where it gives one. By default
    ``BOOST_DEFAULT_MS`` where every limb's hold top stays within a worn coil's reach: a rise
    that lags there is a coil short of heat (a weak supply, a draught), and the duty ceiling's
    headroom lifts it. Where a worn coil's stroke may end short of a hold (``worn_holds_of``),
    or of a ``stroke_deg`` (``_worn_short``), a lag may be a coil at the end of its travel,
    and heating it harder only heats it:
    caterpillar-4 with the boost, worn by 7,220 cycles at 6 °C ambient, reached 114 °C where it
    walked at 96 °C without (bench/bench_sweep.py --seed 7; 131 and 110 °C before the hold watch
    watched a limb that settles short of its hold edge); off there by default, unless the
    firmware carries the coil's heat ceiling (safety.coil_heat_ceiling), which bounds it (the
    same row: 88 °C, and it walks). None either way where the drive duty is already the
    ceiling: there is nothing to boost into."""
    from .robot_settings import BOOST_DEFAULT_MS

    if not _boost_headroom(robot.control, robot.safety):
        return 0
    if robot.control.boost_ms is not None:
        return int(robot.control.boost_ms)
    if getattr(robot.safety, "coil_heat_ceiling", False) or getattr(robot, "plant", None) is None:
        return BOOST_DEFAULT_MS
    worn = _worn_short(list(robot.limbs), [a.name for a in robot.actuators], robot.plant,
                       float(robot.control.hold_margin_deg))
    return 0 if worn else BOOST_DEFAULT_MS


def _boost_headroom(control: Any, safety: Any) -> bool:
    """The drive duty is below the duty ceiling in the firmware's per-myriad units (CFG_DRIVE_DUTY_PM
    against CFG_MAX_DUTY_PM): there is something to boost into. One test for the build and the
    load warning, so that the warning never speaks of a boost the build leaves out."""
    return round(control.drive_duty * 10000) < round(safety.max_duty * 10000)


def boost_warning(path: Path, limbs: list[Any], actuators: list[str], section: PlantSection, control: Any,
                  safety: Any) -> str | None:
    """A line when the file turns the boost on for a body where a worn coil may end short of a
    hold (``worn_holds``) without the coil's heat ceiling: the default leaves it off there."""
    if not control.boost_ms or safety.coil_heat_ceiling or not _boost_headroom(control, safety):
        return None
    worn = _worn_short(limbs, actuators, section, float(control.hold_margin_deg))
    if not worn:
        return None
    names = ", ".join(repr(limbs[i].name) for i in worn)
    return (f"{path}: control.boost_ms = {control.boost_ms} on a body where a worn coil may end short of its "
            f"hold or stroke (limbs {names}): a worn coil that lags at the end of its travel is heated at safety.max_duty "
            f"{safety.max_duty:g}, through its transformation, with nothing to gain (caterpillar-4 worn by 7,220 "
            "cycles: 114 °C, 96 °C without); set [safety] coil_heat_ceiling = true, which bounds it (88 °C there), or leave "
            "boost_ms out (off on such a body; docs/control.md, \"The boost\")")


#: Above this many states the coupling check is skipped (one shape per state; the largest
#: example robots have 36).
COUPLING_CHECK_MAX_STATES = 4096


def entered_states(table: Any) -> list[int]:
    """The states the matrix lets the robot enter: those with an allowed transition into them
    from another state, in order."""
    return sorted({int(d) for s, d in zip(table.src, table.dst) if s != d})


#: what ``unreachable_states`` gives per state: (limb, ψ° at most, ψ° its level needs)
Unreached = tuple[int, float, float]


#: Where along the way to full stroke ``_raised_at_full_stroke`` looks at a state's shape.
REACH_PATH_FRACTIONS = tuple(k / 8 for k in range(1, 9))


def _raised_at_full_stroke(limbs: list[Any], actuators: list[str], section: PlantSection, table: Any,
                           keep: Callable[[tuple[int, ...]], bool]) -> list[tuple[int, tuple[int, ...], np.ndarray]]:
    """``(state, levels, ψ° per limb)`` for each state the matrix enters whose levels ``keep``
    keeps, with the coil of every raised limb at full stroke and the others cold: the most any
    drive of that state bends each limb to on the physical plant's body. Empty for one limb,
    for a body the model cannot describe (``curl_problem``) and past ``COUPLING_CHECK_MAX_STATES``."""
    from .states import limb_levels

    if len(limbs) < 2 or table.n_states > COUPLING_CHECK_MAX_STATES:
        return []  # one limb: unreachable_levels is the whole story
    limb_act = [actuators.index(lb.actuator) for lb in limbs]
    geo = body_of(limb_act, len(actuators), section)
    if curl_problem(geo):
        return []
    levels = tuple(lb.levels for lb in limbs)
    rows, wanted = [], []
    for s in entered_states(table):
        want = tuple(limb_levels(s, levels))
        if not keep(want):
            continue
        c = np.zeros(len(actuators))
        for i, k in enumerate(want):
            if k > 0:
                c[limb_act[i]] = 1.0
        rows.append(c)
        wanted.append((s, want))
    if not rows:
        return []
    # the most along the way there (all raised coils contracting together), not only at the
    # end: a soft body whose raised coils turn it past a half turn in all reads its ends'
    # angles past 180° as negative there (R1 with working_strain 0.12, both coils at full
    # stroke: 197° read as −16.7°, "gets at most −16.7°" for a ψ* of 86° it passes on the way)
    rows = np.array(rows)
    shape = Shape(geo, tabulate=False)
    psi = np.max([shape.compute(rows * f)[0] for f in REACH_PATH_FRACTIONS], axis=0)
    return [(s, want, p) for (s, want), p in zip(wanted, psi)]


def unreachable_states(limbs: list[Any], actuators: list[str], section: PlantSection,
                       table: Any) -> dict[int, tuple[Unreached, ...]]:
    """States the matrix enters (an allowed transition into it from another state) in which
    some raised limb cannot reach its level's entry edge (ψ* + hysteresis/2) on the physical
    plant's body, even with the coil of every raised limb at full stroke and the others cold:
    ``{state: ((limb, ψ° reached, ψ° needed), ...)}``. The most any drive of that state gives,
    so no state is listed that some controller could reach. Empty for a body the model cannot
    describe (``unreachable_levels`` says why) and past ``COUPLING_CHECK_MAX_STATES``."""
    out: dict[int, tuple[Unreached, ...]] = {}
    for s, want, p in _raised_at_full_stroke(limbs, actuators, section, table, any):
        short = []
        for i, k in enumerate(want):
            need = limbs[i].psi_star_deg[k - 1] + limbs[i].hysteresis_deg / 2.0 if k > 0 else None
            if need is not None and float(p[i]) < need:
                short.append((i, float(p[i]), need))
        if short:
            out[s] = tuple(short)
    return out


def unreachable_strokes(path: Path, limbs: list[Any], actuators: list[str], section: PlantSection,
                        table: Any, hold_margin_deg: float) -> list[str]:
    """One line per limb with a ``stroke_deg`` that some state the matrix enters, with the limb
    on its top level, cannot bend it to on the physical plant's body, even with the coil of
    every raised limb at full stroke (as ``unreachable_states``): the controller heats it
    toward its stroke at every such raise, past its transformation, until the limb stops
    climbing short of it (docs/robot-file.md, "full strokes"). ``unreachable_holds`` leaves
    strokes out: the middle limb of a three-limb 80 mm body with ``stroke_deg = 40`` bends to
    31° raised alone, its coil at 106 °C at every raise, and loaded without a word (30°: 78 °C).
    A limb whose top level is out of reach there is ``unreachable_states``' (an error of the
    gait check), not repeated here."""
    strokes = [i for i, lb in enumerate(limbs) if getattr(lb, "stroke_deg", None) is not None]
    if not strokes:
        return []
    levels = tuple(lb.levels for lb in limbs)
    raised = _raised_at_full_stroke(limbs, actuators, section, table,
                                    lambda want: any(want[i] == levels[i] - 1 for i in strokes))
    out = []
    for i in strokes:
        lb = limbs[i]
        entry = lb.psi_star_deg[-1] + lb.hysteresis_deg / 2.0
        reached = [(float(p[i]), s) for s, want, p in raised if want[i] == levels[i] - 1 and float(p[i]) >= entry]
        if not reached:
            continue
        r, s = min(reached)
        if lb.stroke_deg + HOLD_TOP_CLEARANCE_DEG <= r:
            continue
        fit = r - HOLD_TOP_CLEARANCE_DEG
        lowest = hold_top_deg(lb, hold_margin_deg)  # a stroke lies at least here (robot_limbs._check_strokes)
        advice = (f"set stroke_deg to at most {_at_most(fit)}" if float(_at_most(fit)) >= lowest else
                  f"no stroke from {lowest:.1f}° (1° above where it is held without one) is in reach there: "
                  f"leave stroke_deg out")
        out.append(f"{path}: limb {lb.name!r}: stroke_deg {lb.stroke_deg:g}° is out of reach in state "
                   f"{table.label(s)}: every raised limb's coil at full stroke bends it to {r:.1f}° on the "
                   f"simulated {section.length_mm:g} mm body, so at every raise there its coil heats past its "
                   f"transformation until the limb stops climbing short of its stroke; {advice}, mark the "
                   f"transitions into {table.label(s)} \"x\", or describe the body in [plant] (length_mm, "
                   f"working_strain)")
    return out
