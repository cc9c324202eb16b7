"""States the simulated body (``proleg.body``) cannot hold, because the coils the raised limbs
need lift a limb that should stay down (a neighbour's bend, or a coil shared with the raised
limb). Part of the robot file's plausibility checks (``robot_body``):

* ``coupled_states``: every such state, the limb and what lifts it (``robot_body.coupling_warnings``
  gives a few lines per kind and a count: an eight-limb robot on four shared coils has hundreds);
* ``shared_coil_lifts``: those where the limb is lifted by its own coil, shared with a raised
  limb: no step can leave a shared coil's limbs so (the gait feasibility check,
  ``proleg.gait.feasibility``, refuses such a step as ``shared-actuator``);
* ``unholdable_states``: the others, a limb resting or lifted by its neighbours past its edge.
"""

from __future__ import annotations

from typing import Any

from .robot_plant import PlantSection
from .robot_pose import held_psi, settles_held_up
from .robot_reach import COUPLING_CHECK_MAX_STATES, entered_states


#: what ``shared_coil_lifts`` gives per state: (actuator name, lifted limb, raised limbs on
#: that actuator), limbs by index
CoilLift = tuple[str, int, tuple[int, ...]]


def coupled_states(limbs: list[Any], actuators: list[str], section: PlantSection, table: Any,
                   hold_margin_deg: float, drive: list[int] | None = None) -> dict[int, list[tuple[int, list[int], float]]]:
    """States the physical plant's body cannot hold because neighbour coupling lifts a limb:
    ``{state: [(limb, raising limbs, ψ°), ...]}`` for every state the matrix lets the robot
    enter (an allowed transition into it from another state).

    Each state is posed as ``robot_pose.held_psi`` says (every other coil cold). A limb below its top
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
    held = held_psi(limbs, actuators, section, entered, hold_margin_deg, drive, pose="peak")
    # two limbs: no rule settles a limb held up inside the band above its level (PSI_HELD_UP)
    low = ({} if settles_held_up(len(limbs)) else
           held_psi(limbs, actuators, section, entered, hold_margin_deg, drive) or {})
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


def unsettled(limb: Any, level: int, psi: float) -> bool:
    """Whether a ``coupled_states`` hit at ψ is a limb inside the band above its level (it
    reads its level but never settles: two limbs, ``settles_held_up``), not past it."""
    return psi < limb.psi_star_deg[level] + limb.hysteresis_deg / 2.0


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
