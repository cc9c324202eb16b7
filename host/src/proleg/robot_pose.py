"""Where the firmware holds a raised limb (its hold edge, the peak of its rise, how low it sinks
held low) and how the simulated body (``proleg.body``) poses every other limb with the raised
ones held there: ``held_psi``, which the coupling and descent checks (``robot_coupling``,
``robot_descents``) read.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .body import coil_reach_deg, curl_problem, own_reach_deg
from .robot_plant import PlantSection
from .robot_reach import body_of


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


def settles_held_up(n_limbs: int) -> bool:
    """Whether the firmware settles a limb its neighbours hold up inside the band above its
    level (``PSI_RELAX_HELD_UP``, core/psi.h ``PSI_HELD_UP``: three or more limbs)."""
    return n_limbs > 2


def held_psi(limbs: list[Any], actuators: list[str], section: PlantSection, states: list[int],
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
