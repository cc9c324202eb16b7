"""What the simulator warns of when it makes a physical plant (``closed_loop.make_plant``):
a robot the plant moves in one axis only (``planar_warnings``), a supply that heats a coil
too little to lift its limb (``underpowered_warnings``), air so warm that coils start part
of the way through their transformation (``ambient_warnings``), and a supply or a duty that
would settle a coil past where NiTi loses its shape (``overheat_warnings``). Each returns the
lines to warn of, none when all is well."""

from __future__ import annotations

import math
from typing import Any

from ..robot import Robot
from ..robot_reach import boost_ms_of


def planar_warnings(robot: Robot) -> list[str]:
    """A line when the robot file carries planar statistics (Δy, Δθ: a body that steers in the
    plane, planar-4): the physical plant lays the limbs out in a row, in file order, and moves
    the body along that row only, so what it simulates is not that robot. planar-4 walked
    +0.2 mm a cycle \"in +x\" on four contacts in a row (front, left, back, right), and nothing
    said it was not its star-shaped body. Variances alone (``var_dx``, a learned file's) are not
    a planar motion: every file ``proleg learn --out`` wrote was warned about as a planar robot."""
    if not robot.transitions.moves_in_plane:
        return []
    names = ", ".join(lb.name for lb in robot.limbs)
    return [f"{robot.path}: [transitions] has planar statistics (dy, dtheta_deg): a robot that moves in the "
            f"plane, which the physical plant does not model. It lays the {len(robot.limbs)} limbs out in a "
            f"row in file order ({names}) and moves the body along that row (x) only, so its speeds, "
            f"faults and measured matrix are of that row, not of this robot; --plant table simulates the "
            f"file's planar statistics"]


def rise_duty(robot: Any) -> tuple[float, str]:
    """The hottest duty the firmware gives a rise for good, and its key: ``control.drive_duty``;
    with the boost (``robot_reach.boost_ms_of``) ``safety.max_duty``; with the coil's heat
    ceiling (``[safety] coil_heat_ceiling``) at most ``safety.max_mean_duty``, the duty whose
    steady heat the ceiling holds a coil to (core/sma.c heat_step; docs/safety.md). R1 with the
    ceiling at power 0.4: its coils stopped at 61 °C, the steady temperature of 0.45, below As
    (64 °C), and nothing said so: the warning looked at the boost's 0.8 (89 °C)."""
    boost = boost_ms_of(robot) > 0  # as the firmware is built (CTL_BOOST_MS)
    duty = robot.safety.max_duty if boost else robot.control.drive_duty
    key = "safety.max_duty (control.boost_ms is on)" if boost else "control.drive_duty"
    top = duty_ceiling(robot)
    return top if top[0] < duty else (duty, key)


def duty_ceiling(robot: Any) -> tuple[float, str]:
    """The most any rise may get, and its key: ``safety.max_duty``; with the coil's heat ceiling
    (``[safety] coil_heat_ceiling``) ``safety.max_mean_duty``, where it holds a coil for good."""
    if getattr(robot.safety, "coil_heat_ceiling", False):
        return robot.safety.mean_ceiling, "safety.max_mean_duty (the coil's heat ceiling)"
    return robot.safety.max_duty, "safety.max_duty"


def underpowered_warnings(robot: Robot, plant: Any) -> list[str]:
    """A line per coil that the duty a rise heats at (``control.drive_duty``; with
    ``control.boost_ms``, ``safety.max_duty``) cannot bring far enough through its
    transformation, with this plant's supply and conditions, to lift a limb it drives past its
    level-1 edge (ψ*₁ + hysteresis/2): that limb can never rise. R1 with drive_duty = 0.15 (its
    coils settle at 55 °C, As 64 °C) stopped with SMA_ON_LIMIT and STATE_TIMEOUT 'suspects
    sma-left', and nothing said that no duty it was allowed could lift a limb; at power 0.35 its
    coils settle at 67 °C, past As but 6 % of the way to Af, which bends each end to 3.6° of the
    21° it must pass, and the same stop came without a word. The duty advised is the one that
    would settle the coil bending its limbs past their edges (``PhysicalPlant.settled_bend``),
    not merely at As, where a coil has not begun to contract."""
    from .sma import heating_branch

    duty, key = rise_duty(robot)
    top, top_key = duty_ceiling(robot)
    amb = plant.conditions.get("ambient_c")
    edges = [lb.psi_star_deg[0] + lb.hysteresis_deg / 2.0 for lb in robot.limbs]
    bends = plant.settled_bend(duty, edges)
    out = []
    for j, (act, settles, (as_c, af_c)) in enumerate(zip(robot.actuators, plant.steady_coil_temperature_c(duty),
                                                         plant.transformation_c())):
        if amb >= as_c:
            continue
        limbs = [i for i, lb in enumerate(robot.limbs) if lb.actuator == act.name]
        short = [i for i in limbs if bends[i][2] is not None and bends[i][0] < edges[i]]
        if settles >= as_c and not short:
            continue
        needs = [bends[i][2] for i in short]
        need = max(needs) if needs else (duty * (as_c - amb) / (settles - amb) if settles > amb else math.inf)
        # a floor: at it the limb settles just past its edge, and a rise that slow may still meet the
        # on-time limit or the state timeout (R1 advised 0.24 still stops at 0.25: docs/plant.md)
        advice = (f"a duty above {math.ceil(100 * need) / 100:.2f} at the least (at most {top_key}; a "
                  "rise that slow may still pass the on-time limit), or a stronger supply ([plant] supply_v)"
                  if need <= top else
                  f"a stronger supply ([plant] supply_v): even {top_key} {top:g} does not get it there")
        if settles < as_c:
            out.append(f"{robot.path}: coil {act.name!r} heated at {key} {duty:g} settles at {settles:.0f} °C with "
                       f"this supply, below the {as_c:.0f} °C where it starts to contract (As on the physical plant): "
                       f"no limb it drives can rise, and a gait stops with SMA_ON_LIMIT or STATE_TIMEOUT; it needs "
                       f"{advice}")
            continue
        bent = ", ".join(f"limb {robot.limbs[i].name!r} to {bends[i][0]:.1f}° (its level-1 edge: {edges[i]:.1f}°)"
                         for i in short)
        part = heating_branch(settles, as_c, af_c)
        out.append(f"{robot.path}: coil {act.name!r} heated at {key} {duty:g} settles at {settles:.0f} °C with this "
                   f"supply, past the {as_c:.0f} °C where it starts to contract but short of the {af_c:.0f} °C where "
                   f"it finishes (As, Af on the physical plant): it contracts {100 * part:.0f} % of the way and bends "
                   f"{bent}, below the edge (ψ* + hysteresis/2), so {'that limb' if len(short) == 1 else 'those limbs'} "
                   f"cannot rise, and a gait stops with SMA_ON_LIMIT or STATE_TIMEOUT; it needs {advice}")
    return out


def ambient_warnings(robot: Robot, plant: Any) -> list[str]:
    """A line per limb that cannot come down to level 0 because the air is too warm for its
    coils to transform back (``PhysicalPlant.warm_rest``): a coil cools no lower than
    ``ambient_c``, and above its Mf it stays partly contracted. R1 at 45 °C (in range) stopped
    with STATE_TIMEOUT on a limb held at 27° by its own coils, and nothing said why."""
    amb = plant.conditions.get("ambient_c")
    contraction, psi = plant.warm_rest()
    if not any(c > 0.0 for c in contraction):
        return []
    temps = plant._coils.reverse_transformation_c()  # each coil's (Ms, Mf): fatigue and drift shift them

    def span(values: list[float]) -> str:
        lo, hi = min(values), max(values)
        return f"{lo:.0f} °C" if round(lo) == round(hi) else f"{lo:.0f}–{hi:.0f} °C"

    ms, mf = span([t[0] for t in temps]), span([t[1] for t in temps])
    recover = f"{min(t[1] for t in temps):.0f} °C"
    out = []
    for i, (lb, p) in enumerate(zip(robot.limbs, psi)):
        edge = lb.psi_star_deg[0] - lb.hysteresis_deg / 2.0
        if p < edge:
            continue
        coils = ", ".join(f"{a.name!r} {100 * c:.0f} %" for a, c in zip(robot.actuators, contraction) if c > 0.0)
        out.append(f"{robot.path}: limb {lb.name!r} cannot come down to level 0 at ambient_c {amb:g} °C: the coils "
                   f"cool no lower than the air, inside their reverse transformation (Ms {ms}, Mf {mf} on the "
                   f"physical plant), so once heated they stay contracted ({coils} of their stroke) and hold it at "
                   f"{p:.1f}°, above its level-0 edge {edge:.1f}° (ψ* − hysteresis/2): a gait that lowers it ends in "
                   f"STATE_TIMEOUT; the coils recover fully below {recover}")
    return out


def overheat_warnings(robot: Robot, plant: Any) -> list[str]:
    """A line per coil and limit that, with this plant's supply and conditions, the safety
    envelope lets heat too far: the envelope bounds duty and on-time, not energy.

    - ``max_duty`` held would heat it to where NiTi loses its trained shape (``NITI_ANNEAL_C``):
      such a supply ruins a coil within the envelope (R1 at 60 V: past NiTi's melting point; at its own
      7.4 V: 185 °C, which the on-time and mean-duty limits keep it from holding); else, each
      on its own line, the two ceilings below past ``NITI_OVERHEAT_C``, the mean-duty one
      first (lowering it lowers a default hold ceiling too);
    - the hold ceiling (``safety.hold_max_duty``: a duty the firmware may hold forever,
      never on-time) held would settle past ``NITI_OVERHEAT_C``: R1's right coil drawing twice
      its power (``coil_mismatch=0.5``) at full strokes reached 209 °C with no fault, heated at
      the hold duty while waiting (R1 nominal: 85 °C at the ceiling 0.3; the mean-duty ceiling
      0.45 past it too, at 169 °C, which the advice for the hold alone left in place);
    - the mean-duty ceiling (``safety.max_mean_duty``, at most ``max_duty``: what the
      envelope lets a coil average for ever, whatever the host commands) held would settle past
      ``NITI_OVERHEAT_C`` (R1 nominal: 115 °C at 0.45; at 1.3× its power, ``power=1.3``, 142 °C)."""
    from ..physics.materials import NITI_ANNEAL_C, NITI_MELT_C, NITI_OVERHEAT_C, shown_c

    duty = robot.safety.max_duty
    ceiling = robot.safety.hold_ceiling(robot.control.hold_duty)
    amb = plant.conditions.get("ambient_c")
    out = []
    mean = robot.safety.mean_ceiling
    held = plant.steady_coil_temperature_c(ceiling)
    averaged = plant.steady_coil_temperature_c(mean)

    def worn(act: Any, what: str, duty_held: float, settles_c: float, meaning: str, keys: str) -> str:
        safe = math.floor(100 * duty_held * (NITI_OVERHEAT_C - amb) / (settles_c - amb)) / 100  # below, not up to it
        return (f"{robot.path}: coil {act.name!r} held at {what} {duty_held:g} ({meaning}: docs/safety.md) would "
                f"settle at {shown_c(settles_c)} °C with this supply, past the {NITI_OVERHEAT_C:.0f} °C that wears NiTi "
                f"out: lower the supply ([plant] supply_v), or {keys} to {safe:.2f} or less")

    for act, hot, warm, avg in zip(robot.actuators, plant.steady_coil_temperature_c(duty), held, averaged):
        if hot > NITI_ANNEAL_C:
            safe = duty * (NITI_ANNEAL_C - amb) / (hot - amb)
            # two significant digits below 0.01: 60 V with power=2 advised "max_duty below 0.00"
            shown = f"{safe:.2f}" if safe >= 0.01 else f"{safe:.2g}"
            # past the melting point a steady state is no temperature the wire would have (R1 at 60 V:
            # "about 10,519 °C"): the wire melts first
            settles = (f"would settle at {hot:.0f} °C" if hot < NITI_MELT_C else
                       f"would heat past the {NITI_MELT_C:.0f} °C where NiTi melts")
            out.append(f"{robot.path}: coil {act.name!r} held at max_duty {duty:g} {settles} with "
                       f"this supply, past the {NITI_ANNEAL_C:.0f} °C where NiTi loses its trained shape: the safety "
                       f"envelope bounds duty, not energy; lower the supply ([plant] supply_v), or [safety] max_duty below {shown}")
            continue
        if avg > NITI_OVERHEAT_C:
            out.append(worn(act, "the mean-duty ceiling", mean, avg, "what the safety envelope lets a coil average "
                            "for ever, whatever the host commands", "safety.max_mean_duty"))
        if warm > NITI_OVERHEAT_C:
            out.append(worn(act, "the hold ceiling", ceiling, warm, "a duty the firmware may hold forever, never "
                            "on-time", "control.hold_duty and safety.hold_max_duty"))
    return out
