"""Is a robot file plausible on the simulated body (``proleg.body``)? Checked when the file is
loaded, as warnings about the simulator and the file, not refusals (a real body may differ).
The checks live by what they ask, and every name is importable from here:

* ``robot_reach``: can each limb get to its levels and hold tops (``reach_warnings``,
  ``unreachable_states``, ``unreachable_strokes``, ``worn_holds``; ``body_of``, the physical
  plant's body for a robot's limbs, coils and ``[plant]`` table);
* ``robot_pose``: where the firmware holds raised limbs, and how the body poses the others
  (``held_psi``);
* ``robot_coupling``: states the body cannot hold (``coupled_states``, ``shared_coil_lifts``,
  ``unholdable_states``);
* ``robot_descents``: transitions that cannot end because a limb cannot come down
  (``blocked_descents``).

This module words the coupling and descent findings for the robot file's warnings
(``coupling_warnings``) and asks them of a loaded robot (``body_coupling``, ``warned_step``).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from .names import counted
from .robot_coupling import (CoilLift, coupled_states, shared_coil_lifts, unholdable_states,  # noqa: F401
                             unsettled)
from .robot_descents import blocked_descents
from .robot_plant import PlantSection
from .robot_pose import (HELD_UP_WINDOW_DEG, HOLD_OVERSHOOT_DEG, held_low_deg, held_psi,  # noqa: F401
                         hold_edge_deg, hold_peak_deg, settles_held_up)
from .robot_pose import held_psi as _held_psi  # noqa: F401 (tests pose the body through it)
from .robot_reach import (COUPLING_CHECK_MAX_STATES, HOLD_TOP_CLEARANCE_DEG, WORN_STROKE_LOSS,  # noqa: F401
                          Unreached, body_of, body_reach, entered_states, hold_top_deg, reach_warnings,
                          unreachable_holds, unreachable_levels, unreachable_states, unreachable_strokes,
                          worn_holds, worn_holds_of)


#: ``coupling_warnings`` shows this many states of each kind, then how many more there are.
WARNING_EXAMPLES = 3


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


def take_out(what: str, unmeasured: bool) -> str:
    """How a load warning says to take ``what`` (transitions) out of the robot's table: an
    ``"x"`` in a written matrix, a ``forbidden`` mark in an unmeasured one (which has no entries
    to mark)."""
    return f"list {what} in [transitions] forbidden" if unmeasured else f"mark {what} \"x\""


def coupling_warnings(path: Path, limbs: list[Any], section: PlantSection, table: Any,
                      coupled: dict[int, list[tuple[int, list[int], float]]],
                      blocked: dict[tuple[int, int], tuple[int, list[int], float]] | None = None,
                      unmeasured: bool = False) -> tuple[list[str], list[str]]:
    """Lines about ``coupled`` (``coupled_states``), one per lifted limb naming the state, the
    limb and what lifts it, and about ``blocked`` (``blocked_descents``), one per transition:
    ``(shown, rest)``. ``shown`` has, per kind (a limb resting past its edge, lifted by a
    shared coil, lifted by raised neighbours, kept from coming down), the first
    ``WARNING_EXAMPLES`` lines, then one line counting the rest; ``rest`` the others (for -v).
    ``unmeasured``: the table is ``matrix = "unmeasured"`` (``take_out``)."""
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
                    f"where it rests and cannot be held; check its psi_star_deg, or "
                    f"{take_out('the transitions into the state', unmeasured)}"))
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
                    f"STATE_TIMEOUT; narrow its hysteresis_deg, or {take_out('the transitions into it', unmeasured)}"))
                continue
            kinds["shared" if shared else "neighbours"].append((s,
                f"{path}: state {table.label(s)}: limb {lb.name!r} (level {k}) is lifted to {psi:.1f}° {how} on "
                f"the simulated {section.length_mm:g} mm body, past its level-{k + 1} {edge}: the state reads "
                f"as another and cannot be held; {take_out('the transitions into it', unmeasured)} (no gait may rely on it)"))
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
            f"level {k + 1} and the step cannot end; {fix}{take_out('the transition', unmeasured)} (no gait may rely on it)"))
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
