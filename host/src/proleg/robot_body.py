"""Is a robot file plausible on the simulated body (``proleg.body``)? Checked when the file is
loaded, as warnings about the simulator and the file, not refusals (a real body may differ):

* ``reach_warnings`` (the body built and bent once for both): ``unreachable_levels``, a limb
  whose own coil, at full stroke, cannot bend it to its top level (or a body too long for the
  model: ``body.curl_problem``);
  and ``unreachable_holds``, a limb that reaches its top level but not the hold top the
  controller heats it to (``control.hold_margin_deg``), even with every coil at full stroke;
* ``coupled_states`` / ``coupling_warnings``: states the body cannot hold, because the coils
  the raised limbs need lift a limb that should stay down (a neighbour's bend, or a coil
  shared with the raised limb); ``coupling_warnings`` gives a few lines per kind and a count
  (an eight-limb robot on four shared coils has hundreds of such states);
* ``blocked_descents``: transitions that lower a limb the raised limbs of the state it goes
  to hold inside its hysteresis band: it keeps reading the level above (also in
  ``coupling_warnings``);
* ``shared_coil_lifts``: those of them where the limb is lifted by its own coil, shared with
  a raised limb: no step can leave a shared coil's limbs so (the gait feasibility check,
  ``proleg.gait.feasibility``, refuses such a step as ``shared-actuator``);
* ``unreachable_states``: states the matrix enters in which a raised limb cannot get to its
  level even with the coils of every raised limb at full stroke (a limb on another limb's
  coil, which bends the body at that limb: ``unreachable_levels`` warns about the limb); the
  feasibility check refuses a step into one (``unreachable``), so the build does not choose
  such a gait as gait 0.

``body_of`` is the physical plant's body for a robot's limbs, coils and ``[plant]`` table.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from .body import (DEFAULT_OVERLAP_MM, BodyGeometry, Shape, body_geometry, coil_homes, coil_reach_deg, curl_key,
                   curl_problem, own_reach_deg)
from .names import counted
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
    reach = body_reach(limb_actuators, len(actuators), section)
    if isinstance(reach, str):
        return [f"{path}: plant.{curl_key(section.given)}: {reach} (gait and build go on; the physical plant of "
                "`proleg sim` and `learn --sim` refuses such a body, `--plant table` runs it)"]
    own, full = reach
    return (unreachable_levels(path, limbs, limb_actuators, len(actuators), own, section) +
            unreachable_holds(path, limbs, own, full, section, hold_margin_deg))


def body_reach(limb_actuators: list[int], n_actuators: int,
               section: PlantSection) -> tuple[list[float], list[float]] | str:
    """ψ per limb on the physical plant's body: ``(own, full)``, with only the limb's own coil
    at full stroke and with every coil at full stroke; or, for a body too long for the model,
    why (``body.curl_problem``)."""
    geo = body_of(limb_actuators, n_actuators, section)
    curl = curl_problem(geo)
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
    if len(limbs) < 2:
        return []
    reach = body_reach([actuators.index(lb.actuator) for lb in limbs], len(actuators), section)
    no_stroke = [i for i, lb in enumerate(limbs) if getattr(lb, "stroke_deg", None) is None]
    if isinstance(reach, str):
        return no_stroke
    kept = 1.0 - WORN_STROKE_LOSS
    return [i for i in no_stroke if hold_top_deg(limbs[i], hold_margin_deg) > kept * min(reach[0][i], reach[1][i])]


def worn_holds_of(robot: Any) -> list[int]:
    """``worn_holds`` of a loaded robot, with its own hold margin; none for a robot without
    its [plant] table."""
    if getattr(robot, "plant", None) is None:
        return []
    return worn_holds(list(robot.limbs), [a.name for a in robot.actuators], robot.plant,
                      float(robot.control.hold_margin_deg))


#: Above this many states the coupling check is skipped (one shape per state; the largest
#: example robots have 36).
COUPLING_CHECK_MAX_STATES = 4096


#: How far past its hold top (the hold edge + 1°, where the bang-bang hold switches the coil off)
#: a raised limb's rise carries it: the coil, driven at the drive duty through its
#: transformation, keeps contracting for a while after it is switched off. Measured on the
#: physical plant (nominal, `proleg sim --record`, 20 s of gait 0, the peak of each limb raised
#: alone above its hold top): 0.8–1.2° on caterpillar-4, 0.8–2.1° inchworm-3, 2.0–2.6° R1,
#: 1.9–2.8° R2, 2.5–3.6° R3, 2.0–2.1° nano-3x6 (ψ* 8–40°, 120 mm: l0 rose past its level-2
#: hold top 22° to 24°, lifting l1 from under its 9° edge to 9.7°: 212 read instead of 202,
#: STATE_TIMEOUT), 2.7° R1 with hysteresis 16°. The held limbs then swing between the hold edge
#: and about 1° above the hold top (caterpillar-4's 0101: the rear proleg at 19°, its hold top
#: 18°; docs/control.md). The typical overshoot, not the largest: a pose at the largest warned
#: about states the bundled robots walk through.
HOLD_OVERSHOOT_DEG = 2.0


def hold_edge_deg(limb: Any, level: int, hold_margin_deg: float) -> float:
    """Where the firmware's bang-bang hold heats a limb held on ``level`` ≥ 1 from (core/ctl.c,
    psi.c ``E_HOLD``): its threshold's upper band edge plus ``hold_margin_deg``, ψ*(level) +
    hysteresis/2 + margin; on its top level with a ``stroke_deg``, the stroke. The least ψ
    the hold keeps: below it the coil heats (measured on the physical plant, a held limb stays
    at or above it once it got there)."""
    stroke = getattr(limb, "stroke_deg", None)
    if stroke is not None and level == limb.levels - 1:
        return float(stroke)
    return limb.psi_star_deg[level - 1] + limb.hysteresis_deg / 2.0 + hold_margin_deg


def hold_peak_deg(limb: Any, level: int, hold_margin_deg: float) -> float:
    """The highest a limb held on ``level`` ≥ 1 goes: its hold top (``hold_edge_deg`` +
    ``PSI_HOLD_BAND`` 1°, where the coil is switched off) plus ``HOLD_OVERSHOOT_DEG``."""
    return hold_edge_deg(limb, level, hold_margin_deg) + 1.0 + HOLD_OVERSHOOT_DEG


def held_low_deg(limb: Any, level: int, hold_margin_deg: float) -> float:
    """The least a limb held on ``level`` ≥ 1 sinks to held low (core/ctl.h ``CTL_HELD_UP``,
    three or more limbs): while a falling limb within 2° of its crossing has not come 1° lower
    for 1.5 s, every held limb is heated only below its band's upper edge ψ*(level) +
    hysteresis/2 (a stroke too), not its hold edge ``hold_margin_deg`` above it, and sags under
    that edge before its coil, heated again, catches it: its band's lower edge ψ* −
    hysteresis/2, the least at which it still reads its level. Measured on the physical plant
    (three limbs on 80 mm, ψ* 20°, 8° and 16°/28°, 012 → 002): the held limb sagged from 31° to
    27.6°, 1.4° under its upper edge 29°, the lowered middle one came down from 8.1° to its 7°
    edge in 5 s and the step ended, though posed at the upper edge it stayed at 7.5°."""
    return limb.psi_star_deg[level - 1] - limb.hysteresis_deg / 2.0


#: How close above its crossing (its band's lower edge) a falling limb held up must be for the
#: firmware to hold the others low (core/stall.c: the fall edges, ``PSI_FALL_EDGES`` 1° and 2°).
HELD_UP_WINDOW_DEG = 2.0


def _held_psi(limbs: list[Any], actuators: list[str], section: PlantSection, states: list[int],
              hold_margin_deg: float, drive: list[int] | None = None,
              pose: str = "edge") -> dict[tuple[int, int], float] | None:
    """ψ of each limb below its top level in each of ``states`` on the physical plant's body,
    ``{(state, limb): ψ°}``, with every raised limb's coil at the contraction that holds it
    where the firmware holds it (``pose``): "edge", at its hold edge (``hold_edge_deg``,
    ψ*(its level) + hysteresis/2 + ``hold_margin_deg``, or its ``stroke_deg`` on its top
    level), the least the bang-bang hold keeps; "peak", at the most its rise reaches
    (``hold_peak_deg``, the hold top + ``HOLD_OVERSHOOT_DEG``); "low", the least it sinks to held
    low (``held_low_deg``, its band's lower edge: three or more limbs, while a falling limb is
    held up); each a
    fraction of its own coil's full-stroke reach,
    ``own_reach_deg``. A stroke held that high bends the whole body: R1 at full strokes cannot
    hold 10 or 01, and a matrix allowing them loaded without a word when raised limbs were
    posed just past ψ*. Posed at ψ* + margin, h/2 below the hold edge, R1 with hysteresis 16°
    lifted the lowered end to 10°, under its 12° band; the firmware holds the raised end at
    32–35° and the other end sat at 13–15° and never settled (STATE_TIMEOUT). The limb's own
    coil is at the least it can be (cold, or what the other limbs on a shared coil need: the
    controller may let it cool that far, no further).
    None: a body the model cannot describe (``curl_problem``).

    ``drive``: the actuator index that drives each limb, where it is not the robot file's (a
    fallback's remap, ``proleg.limbloss``): the coils stay where the body has them, and a
    limb driven by another limb's coil is held by that coil's contraction."""
    from .body import Shape
    from .states import limb_levels

    limb_act = [actuators.index(lb.actuator) for lb in limbs]
    geo = body_of(limb_act, len(actuators), section)
    if curl_problem(geo):
        return None  # unreachable_levels says why
    drive = list(limb_act) if drive is None else list(drive)
    if drive == limb_act:
        reach = own_reach_deg(geo, limb_act)
    else:  # how far each limb's driving coil alone lifts it at full stroke
        lifts = {a: coil_reach_deg(geo, a) for a in set(drive)}
        reach = [lifts[a][i] for i, a in enumerate(drive)]
    levels = tuple(lb.levels for lb in limbs)
    rows, cases = [], []
    for s in states:
        want = limb_levels(s, levels)
        held_at = {"edge": hold_edge_deg, "peak": hold_peak_deg, "low": held_low_deg}[pose]
        demand = [min(1.0, held_at(limbs[i], k, hold_margin_deg) / reach[i])
                  if k > 0 and reach[i] > 0 else 0.0 for i, k in enumerate(want)]
        for i, k in enumerate(want):
            if k >= limbs[i].levels - 1:
                continue  # at its top level
            # one coil on two limbs lifts its near limb first, so the far one alone cannot be up
            c = np.zeros(len(actuators))
            for j, d in enumerate(demand):
                if j != i:
                    c[drive[j]] = max(c[drive[j]], d)
            rows.append(c)
            cases.append((s, i))
    if not rows:
        return {}
    psi = Shape(geo, tabulate=False).compute(np.array(rows))[0]
    # in (−180°, 180°] however far the body curls (Shape.compute wraps it)
    return {case: float(p[case[1]]) for case, p in zip(cases, psi)}


def entered_states(table: Any) -> list[int]:
    """The states the matrix lets the robot enter: those with an allowed transition into them
    from another state, in order."""
    return sorted({int(d) for s, d in zip(table.src, table.dst) if s != d})


def coupled_states(limbs: list[Any], actuators: list[str], section: PlantSection, table: Any,
                   hold_margin_deg: float, drive: list[int] | None = None) -> dict[int, list[tuple[int, list[int], float]]]:
    """States the physical plant's body cannot hold because neighbour coupling lifts a limb:
    ``{state: [(limb, raising limbs, ψ°), ...]}`` for every state the matrix lets the robot
    enter (an allowed transition into it from another state).

    Each state is posed as ``_held_psi`` says (every other coil cold). A limb below its top
    level whose ψ, with the raised limbs at their hold peaks (``hold_peak_deg``), reaches the
    next level's entry edge (ψ* + hysteresis/2) reads that level: the state is not reachable
    on this body (e.g. caterpillar-4's 1020: the rear proleg between the raised tail and the
    front proleg at level 2 bends to ≈ 16° > 13°; one coil on both of R1's limbs lifts its
    own end first, so 01 cannot be held). A limb that rests past its level-1 edge comes with
    no raising limbs. On two limbs (``settles_held_up``) a limb the raised limbs hold at or
    above its band's lower edge (ψ* − hysteresis/2) even at their hold edges
    (``hold_edge_deg``) never settles there: it comes with that ψ (``unsettled``)."""
    from .states import limb_levels

    if len(limbs) < 2 or table.n_states > COUPLING_CHECK_MAX_STATES:
        return {}
    entered = entered_states(table)
    held = _held_psi(limbs, actuators, section, entered, hold_margin_deg, drive, pose="peak")
    # two limbs: no rule settles a limb held up inside the band above its level (PSI_HELD_UP)
    low = ({} if settles_held_up(len(limbs)) else
           _held_psi(limbs, actuators, section, entered, hold_margin_deg, drive) or {})
    levels = tuple(lb.levels for lb in limbs)
    out: dict[int, list[tuple[int, list[int], float]]] = {}
    for (s, i), psi_i in (held or {}).items():
        want = limb_levels(s, levels)
        lb = limbs[i]
        star, half = lb.psi_star_deg[want[i]], lb.hysteresis_deg / 2.0
        raising = [j for j, kj in enumerate(want) if kj > 0 and j != i]
        if psi_i >= star + half:
            out.setdefault(s, []).append((i, raising, psi_i))
        elif raising and low.get((s, i), -180.0) >= star - half:
            out.setdefault(s, []).append((i, raising, low[(s, i)]))
    return out


def settles_held_up(n_limbs: int) -> bool:
    """Whether the firmware settles a limb its neighbours hold up inside the band above its
    level (``PSI_RELAX_HELD_UP``, core/psi.h ``PSI_HELD_UP``: three or more limbs)."""
    return n_limbs > 2


def unsettled(limb: Any, level: int, psi: float) -> bool:
    """Whether a ``coupled_states`` hit at ψ is a limb inside the band above its level (it
    reads its level but never settles: two limbs, ``settles_held_up``), not past it."""
    return psi < limb.psi_star_deg[level] + limb.hysteresis_deg / 2.0


def blocked_descents(limbs: list[Any], actuators: list[str], section: PlantSection, table: Any,
                     hold_margin_deg: float, drive: list[int] | None = None
                     ) -> dict[tuple[int, int], tuple[int, list[int], float]]:
    """Allowed transitions the physical plant's body cannot finish because neighbour coupling
    keeps a limb from coming down: ``{(from, to): (limb, raising limbs, ψ°)}``.

    The firmware's level bands are hysteretic: a limb lowered to level k reads level k only
    once ψ falls below ψ*(k) − hysteresis/2. Posed in the state it is lowered into
    (``_held_psi``), a limb whose ψ stays at or above that edge keeps reading level k + 1, and
    the step ends in STATE_TIMEOUT, although the same state is reached from below (raising a
    neighbour lifts the limb short of ψ* + hysteresis/2). Where ψ reaches that upper edge too
    the state itself cannot be held (``coupled_states``), and it is left to that warning.

    The raised limbs are posed at their hold edges (ψ* + hysteresis/2 + margin: the least the
    bang-bang hold keeps them at). With three or more limbs the firmware holds them low (heated
    only below their band's upper edges; they sag to their lower edges, ``held_low_deg``) once
    a falling limb sits within
    ``HELD_UP_WINDOW_DEG`` of its crossing: there the step is blocked only if the limb stays
    up held low too (the ψ given is then that one). caterpillar-4's 1110 → 1010, the rear
    proleg at 11.3° against its 11° edge at the hold edges, comes down so (docs/control.md)."""
    from .states import limb_levels

    if len(limbs) < 2 or table.n_states > COUPLING_CHECK_MAX_STATES:
        return {}
    levels = tuple(lb.levels for lb in limbs)
    lowered: dict[tuple[int, int], list[int]] = {}   # (from, to) -> the limbs it lowers
    for a, b in zip(table.src, table.dst):
        a, b = int(a), int(b)
        if a != b:
            down = [i for i, (x, y) in enumerate(zip(limb_levels(a, levels), limb_levels(b, levels))) if y < x]
            if down:
                lowered[(a, b)] = down
    into = sorted({b for _, b in lowered})
    held = _held_psi(limbs, actuators, section, into, hold_margin_deg, drive) or {}
    low = (_held_psi(limbs, actuators, section, into, hold_margin_deg, drive, pose="low") or {}
           if settles_held_up(len(limbs)) else {})
    out: dict[tuple[int, int], tuple[int, list[int], float]] = {}
    for (a, b), down in lowered.items():
        want = limb_levels(b, levels)
        for i in down:
            lb, k = limbs[i], want[i]
            psi_i = held.get((b, i))
            lo = lb.psi_star_deg[k] - lb.hysteresis_deg / 2.0
            if psi_i is None or not lo <= psi_i < lb.psi_star_deg[k] + lb.hysteresis_deg / 2.0:
                continue
            if low and psi_i < lo + HELD_UP_WINDOW_DEG:  # the others are held low: down if that frees it
                psi_i = low.get((b, i), psi_i)
                if psi_i < lo:
                    continue
            out[(a, b)] = (i, [j for j, kj in enumerate(want) if kj > 0 and j != i], psi_i)
            break
    return out


#: ``coupling_warnings`` shows this many states of each kind, then how many more there are.
WARNING_EXAMPLES = 3

#: what ``shared_coil_lifts`` gives per state: (actuator name, lifted limb, raised limbs on
#: that actuator), limbs by index
CoilLift = tuple[str, int, tuple[int, ...]]


def body_coupling(robot: Any, table: Any = None, drive: list[int] | None = None) -> tuple[dict, dict]:
    """``coupled_states`` and ``blocked_descents`` of a loaded robot: on ``table`` (default its
    own), with ``drive`` (a fallback's remap; default the robot file's map)."""
    limbs, names = list(robot.limbs), [a.name for a in robot.actuators]
    table = robot.transitions if table is None else table
    margin = robot.control.hold_margin_deg
    return (coupled_states(limbs, names, robot.plant, table, margin, drive),
            blocked_descents(limbs, names, robot.plant, table, margin, drive))


def warned_step(robot: Any, a: int, b: int) -> bool:
    """Whether the checks when the robot file was loaded warned about the step ``a`` -> ``b``
    (state indices): ``b`` a state that cannot be held, the step one that cannot end on the
    simulated body, or a limb that cannot reach one of its levels."""
    coupled, blocked = body_coupling(robot)
    if b in coupled or (a, b) in blocked:
        return True
    return bool(reach_warnings(robot.path, list(robot.limbs), [x.name for x in robot.actuators], robot.plant,
                               robot.control.hold_margin_deg))


#: what ``unreachable_states`` gives per state: (limb, ψ° at most, ψ° its level needs)
Unreached = tuple[int, float, float]


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
    psi = Shape(geo, tabulate=False).compute(np.array(rows))[0]
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


def unholdable_states(limbs: list[Any], coupled: dict[int, list[tuple[int, list[int], float]]]
                      ) -> dict[int, tuple[tuple[int, float], ...]]:
    """The states of ``coupled`` (``coupled_states``) the body cannot hold for a limb that rests
    or is lifted by its neighbours past its level's upper edge: ``{state: ((limb, ψ°), ...)}``.
    A limb lifted by a coil it shares with a raised limb is ``shared_coil_lifts``' (a
    ``shared-actuator`` error of the gait check where a step moves only some of that coil's
    limbs) and left out here."""
    out: dict[int, tuple[tuple[int, float], ...]] = {}
    for s, hits in coupled.items():
        held = tuple((i, psi) for i, raising, psi in hits
                     if not any(limbs[j].actuator == limbs[i].actuator for j in raising))
        if held:
            out[s] = held
    return out


def shared_coil_lifts(limbs: list[Any], coupled: dict[int, list[tuple[int, list[int], float]]]
                      ) -> dict[int, tuple[CoilLift, ...]]:
    """The states of ``coupled`` (``coupled_states``) a shared coil cannot hold: a limb is
    lifted by its own coil, which also holds one of the raised limbs up (one coil on two
    limbs lifts its near limb first: paper-r1-one-actuator's 01). Other states the body
    cannot hold (a neighbour's bend) are left to ``coupling_warnings``."""
    out: dict[int, tuple[CoilLift, ...]] = {}
    for s, hits in coupled.items():
        lifts = tuple((limbs[i].actuator, i, tuple(j for j in raising if limbs[j].actuator == limbs[i].actuator))
                      for i, raising, _ in hits
                      if any(limbs[j].actuator == limbs[i].actuator for j in raising))
        if lifts:
            out[s] = lifts
    return out


def coupling_warnings(path: Path, limbs: list[Any], section: PlantSection, table: Any,
                      coupled: dict[int, list[tuple[int, list[int], float]]],
                      blocked: dict[tuple[int, int], tuple[int, list[int], float]] | None = None
                      ) -> tuple[list[str], list[str]]:
    """Lines about ``coupled`` (``coupled_states``), one per lifted limb naming the state, the
    limb and what lifts it, and about ``blocked`` (``blocked_descents``), one per transition:
    ``(shown, rest)``. ``shown`` has, per kind (a limb resting past its edge, lifted by a
    shared coil, lifted by raised neighbours, kept from coming down), the first
    ``WARNING_EXAMPLES`` lines, then one line counting the rest; ``rest`` the others (for -v)."""
    kinds: dict[str, list[tuple[Any, str]]] = {"rests": [], "shared": [], "neighbours": [], "unsettled": [],
                                               "descents": []}
    for s, hits in coupled.items():
        for i, raising, psi in hits:
            lb = limbs[i]
            k = limb_levels_of(s, limbs)[i]
            edge = f"edge {lb.psi_star_deg[k] + lb.hysteresis_deg / 2.0:.1f}° (ψ* + hysteresis/2)"
            if not raising:  # nothing lifts it: it rests there
                kinds["rests"].append((s, 
                    f"{path}: state {table.label(s)}: limb {lb.name!r} rests at {psi:.1f}° on the simulated "
                    f"{section.length_mm:g} mm body, past its level-{k + 1} {edge}: its level {k} lies below "
                    f"where it rests and cannot be held; check its psi_star_deg, or mark the transitions into "
                    f"the state \"x\""))
                continue
            names = ", ".join(repr(limbs[j].name) for j in raising)
            shared = [j for j in raising if limbs[j].actuator == lb.actuator]
            how = (f"by its own coil {lb.actuator!r}, which also holds {', '.join(repr(limbs[j].name) for j in shared)} "
                   f"up" if shared else f"by the raised limbs {names}")
            if unsettled(lb, k, psi):
                lo = lb.psi_star_deg[k] - lb.hysteresis_deg / 2.0
                kinds["unsettled"].append((s,
                    f"{path}: state {table.label(s)}: limb {lb.name!r} (level {k}) is held up to {psi:.1f}° {how} on "
                    f"the simulated {section.length_mm:g} mm body (each at its hold edge, ψ* + hysteresis/2 + "
                    f"control.hold_margin_deg, the least the firmware holds it at), inside the hysteresis band above "
                    f"its level ({lo:.1f}..{lo + lb.hysteresis_deg:.1f}°): it reads level {k} but never settles (a two-limb "
                    f"firmware has no rule that settles a limb held up), so every step into the state ends in "
                    f"STATE_TIMEOUT; narrow its hysteresis_deg, or mark the transitions into it \"x\""))
                continue
            kinds["shared" if shared else "neighbours"].append((s,
                f"{path}: state {table.label(s)}: limb {lb.name!r} (level {k}) is lifted to {psi:.1f}° {how} on "
                f"the simulated {section.length_mm:g} mm body, past its level-{k + 1} {edge}: the state reads "
                f"as another and cannot be held; mark the transitions into it \"x\" (no gait may rely on it)"))
    for (a, s), (i, raising, psi) in (blocked or {}).items():
        if any(h[0] == i for h in coupled.get(s, ())):
            continue  # the state's own line says it: the limb never settles there however it comes
        lb = limbs[i]
        k = limb_levels_of(s, limbs)[i]
        shared = [j for j in raising if limbs[j].actuator == lb.actuator]
        how = (f"its own coil {lb.actuator!r}, which also holds {', '.join(repr(limbs[j].name) for j in shared)} up, "
               f"holds it at" if shared else
               f"the raised limbs {', '.join(repr(limbs[j].name) for j in raising)} hold it at" if raising else
               "it rests at")  # no limb raised: its level-k band holds the body's rest angle
        fix = "" if raising else "check its psi_star_deg, or "
        lo = lb.psi_star_deg[k] - lb.hysteresis_deg / 2.0
        pose = ""
        if raising and not shared:
            pose = (" (each held low, sunk to its band's lower edge ψ* − hysteresis/2, the firmware's rule for a "
                    "limb held up on its way down)" if settles_held_up(len(limbs)) and psi < lo + HELD_UP_WINDOW_DEG else
                    " (each at its hold edge, ψ* + hysteresis/2 + control.hold_margin_deg, the least the firmware "
                    "holds it at)")
        kinds["descents"].append(((a, s),
            f"{path}: transition {table.label(a)}→{table.label(s)}: limb {lb.name!r} cannot come down to level "
            f"{k}: {how} {psi:.1f}°{pose} on the simulated {section.length_mm:g} mm body, above its level-{k} "
            f"edge {lo:.1f}° (ψ* − hysteresis/2), so it keeps reading "
            f"level {k + 1} and the step cannot end; {fix}mark the transition \"x\" (no gait may rely on it)"))
    what = {"rests": "a limb resting past its next level's edge",
            "shared": "a limb lifted by its own coil, shared with a raised limb",
            "neighbours": "a limb lifted by raised neighbours",
            "unsettled": "a limb held up inside the band above its level, where it never settles"}
    entered = len({int(d) for d in table.dst})
    shown: list[str] = []
    rest: list[str] = []
    for kind, lines in kinds.items():
        shown += [line for _, line in lines[:WARNING_EXAMPLES]]
        if len(lines) > WARNING_EXAMPLES:
            rest += [line for _, line in lines[WARNING_EXAMPLES:]]
            if kind == "descents":
                shown.append(f"{path}: {_more(len(lines) - WARNING_EXAMPLES)}: in all, {len(lines)} "
                             f"of the {len(table.src)} transitions the matrix allows cannot end on the simulated "
                             f"body because raised limbs keep a limb from coming down (-v lists every line)")
                continue
            n = len({s for s, _ in lines})
            shown.append(f"{path}: {_more(len(lines) - WARNING_EXAMPLES)}: in all, {n} of the "
                         f"{entered} states the matrix enters cannot be held on the simulated body because of "
                         f"{what[kind]} (-v lists every line)")
    return shown, rest


def limb_levels_of(state: int, limbs: list[Any]) -> tuple[int, ...]:
    from .states import limb_levels

    return tuple(limb_levels(state, tuple(lb.levels for lb in limbs)))


def _more(n: int) -> str:
    return f"{counted(n, 'more line')} like these"
