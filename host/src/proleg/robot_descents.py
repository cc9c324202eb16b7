"""``blocked_descents``: transitions that lower a limb the raised limbs of the state it goes to
hold inside its hysteresis band on the simulated body (``proleg.body``): it keeps reading the
level above and the step cannot end. Part of the robot file's plausibility checks
(``robot_body``; its lines are ``robot_body.coupling_warnings``').
"""

from __future__ import annotations

from typing import Any

from .robot_plant import PlantSection
from .robot_pose import HELD_UP_WINDOW_DEG, held_psi, settles_held_up
from .robot_reach import COUPLING_CHECK_MAX_STATES


def blocked_descents(limbs: list[Any], actuators: list[str], section: PlantSection, table: Any,
                     hold_margin_deg: float, drive: list[int] | None = None
                     ) -> dict[tuple[int, int], tuple[int, list[int], float]]:
    """Allowed transitions the physical plant's body cannot finish because neighbour coupling
    keeps a limb from coming down: ``{(from, to): (limb, raising limbs, ψ°)}``.

    The firmware's level bands are hysteretic: a limb lowered to level k reads level k only
    once ψ falls below ψ*(k) − hysteresis/2. Posed in the state it is lowered into
    (``robot_pose.held_psi``), a limb whose ψ stays at or above that edge keeps reading level k + 1, and
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
    held = held_psi(limbs, actuators, section, into, hold_margin_deg, drive) or {}
    low = (held_psi(limbs, actuators, section, into, hold_margin_deg, drive, pose="low") or {}
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
