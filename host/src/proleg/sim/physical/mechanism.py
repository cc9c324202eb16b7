"""Which friction mechanism each limb carries: from the robot file, or inferred.

The paper's mechanisms: D1 (material M1, touching at ψ < ψ*, is soft/sticky; M2 hard/slippery)
and D2 (the reverse). A robot file may say so per limb (``friction = "D1"`` or a list of
materials per level, lowest level first, e.g. ``["soft", "hard", "soft"]``, a material being a
name or a pad's own ``{ mu_static, mu_kinetic }``; checked by
``proleg.robot``, on every limb or none). A robot file without that key has its mechanisms inferred from the sign pattern of
the robot's transition matrix: every assignment of D1/D2 to the limbs is swept kinematically
through every allowed transition (``measure.kinematic_signs_all``: one sweep, replayed per assignment) and the assignment whose signs
agree with the most non-zero matrix entries wins (ties: D1 first). A robot with a multi-level
limb is not inferred: its multi-level limbs alternate soft/hard from level 0, its two-level
limbs take D1. Robots of more than ``INFER_MAX_LIMBS`` limbs are
not inferred (the work grows as 4^n): they take D1 on every limb, and loading such a file
without ``friction`` warns. Nor is a robot whose matrix is unmeasured (no signs to agree with):
it takes the defaults of a multi-level robot, and its file warns likewise.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ...errors import SimError
from ...physics import materials as mat
from ...robot import stroke_leads
from ...robot_plant import INFER_MAX_LIMBS, too_many_to_infer


@dataclass(frozen=True)
class Mechanisms:
    names: tuple[str, ...]                      # "D1", "D2" or "custom"
    materials: tuple[tuple[str | tuple[float, float], ...], ...]  # per limb, material (or pad's μs, μk) per level
    source: str                                 # "robot file", "given", "inferred from the matrix", "default (…why)"


def _materials(name_or_list: Any, levels: int, where: str) -> tuple[str, tuple[str, ...]]:
    if isinstance(name_or_list, str):
        if name_or_list not in mat.MECHANISMS:
            raise SimError(f"{where}: friction {name_or_list!r}: expected one of {', '.join(mat.MECHANISMS)} or a list of materials")
        mats = mat.MECHANISMS[name_or_list]
        if levels != 2:
            raise SimError(f"{where}: friction {name_or_list!r} describes 2 levels, the limb has {levels}")
        return name_or_list, mats
    mats = tuple(tuple(float(x) for x in m) if isinstance(m, (tuple, list)) else str(m) for m in name_or_list)
    if len(mats) != levels or any(isinstance(m, str) and m not in mat.MATERIALS
                                  or not isinstance(m, str) and len(m) != 2 for m in mats):
        raise SimError(f"{where}: friction: expected {levels} materials, each one of {', '.join(mat.MATERIALS)} "
                       f"or a (mu_static, mu_kinetic) pair, got {list(mats)}")
    named = next((k for k, v in mat.MECHANISMS.items() if v == mats), "custom")
    return named, mats


def limb_mechanisms(robot: Any, override: Sequence[Any] | None = None, body: Any = None) -> Mechanisms:
    """Each limb's friction mechanism: ``override``, the robot file's, a default, or inferred
    from the matrix on the robot file's body (the pads are the file's, whatever a run's
    conditions do to the body), or on ``body`` (the run's, ``measure.body_of_run``) where the
    file's is one the model cannot pose."""
    limbs = list(robot.limbs)
    levels = [len(lb.psi_star_deg) + 1 for lb in limbs]
    if override is not None:
        if len(override) != len(limbs):
            raise SimError(f"mechanisms: expected one per limb ({len(limbs)}), got {len(override)}")
        got = [_materials(m, k, f"mechanisms[{i}]") for i, (m, k) in enumerate(zip(override, levels))]
        return Mechanisms(tuple(g[0] for g in got), tuple(g[1] for g in got), "given")
    declared = [getattr(lb, "friction", None) for lb in limbs]
    if all(d is not None for d in declared):
        got = [_materials(d, k, f"limb {lb.name!r}") for d, k, lb in zip(declared, levels, limbs)]
        return Mechanisms(tuple(g[0] for g in got), tuple(g[1] for g in got), "robot file")
    unmeasured = getattr(robot, "unmeasured", False)
    if any(k != 2 for k in levels) or getattr(robot, "transitions", None) is None or unmeasured:
        mats = tuple(tuple("soft" if lv % 2 == 0 else "hard" for lv in range(k)) for k in levels)
        why = ("a limb has more than two levels" if any(k != 2 for k in levels) else
               "the matrix is unmeasured" if unmeasured else "no transition matrix")
        return Mechanisms(tuple("D1" if k == 2 else "custom" for k in levels), mats, f"default (not inferred: {why})")
    if too_many_to_infer(limbs):  # 2^n assignments × n·2^n transitions (robot_plant)
        return Mechanisms(("D1",) * len(limbs), (mat.MECHANISMS["D1"],) * len(limbs),
                          f"default (not inferred for more than {INFER_MAX_LIMBS} limbs)")
    names = _infer(robot, body)
    return Mechanisms(names, tuple(mat.MECHANISMS[n] for n in names), "inferred from the matrix")


def _infer(robot: Any, body: Any = None) -> tuple[str, ...]:
    reward, allowed = robot.transitions.dense()
    key = (tuple(tuple(float(x) for x in row) for row in np.asarray(reward)),
           tuple(tuple(bool(x) for x in row) for row in np.asarray(allowed)),
           tuple((lb.name, tuple(lb.psi_star_deg), lb.actuator, getattr(lb, "stroke_deg", None))
                 for lb in robot.limbs),
           tuple((a.name, a.channel) for a in robot.actuators),
           stroke_leads(robot.limbs, getattr(robot, "control", None)),  # the drive follows strokes
           _body_key(robot))
    try:
        return _infer_cached(key, robot)
    except SimError:
        # the file's body is one the model cannot pose (it would curl over itself: the load
        # warned) and the run's is another (--condition overlap_mm=0): infer on the run's body
        # rather than refuse a run whose body is fine
        if body is None:
            raise
        return _infer_cached(key + (repr((dict(body.values), {k: dict(v) for k, v in body.named.items()})),),
                             robot, body)


def _body_key(robot: Any) -> tuple:
    """What else the sweep depends on: each limb's band and the hold margin (where the drive
    holds it) and the body (``[plant]``: length, stiffness, the physical keys such as the coils'
    overlaps). Without it a second robot of the same matrix on another body got the first one's
    mechanisms in one process."""
    plant = getattr(robot, "plant", None)
    physical = getattr(plant, "physical", None) or {}
    return (tuple(float(getattr(lb, "hysteresis_deg", 0.0)) for lb in robot.limbs),
            float(getattr(getattr(robot, "control", None), "hold_margin_deg", 0.0) or 0.0),
            repr(getattr(plant, "length_mm", None)), repr(getattr(plant, "working_strain", None)),
            repr(sorted(physical.items())))


# Inference is a pure function of the robot's limbs, actuators and matrix; memoised so that
# building many plants of one robot sweeps it once.
_CACHE: dict[tuple, tuple[str, ...]] = {}


def _infer_cached(key: tuple, robot: Any, body: Any = None) -> tuple[str, ...]:
    hit = _CACHE.get(key)
    if hit is not None:
        return hit
    from .measure import kinematic_signs_all

    reward, allowed = robot.transitions.dense()
    reward = np.asarray(reward, dtype=float)
    best, best_score = None, -1
    combos = list(itertools.product(("D1", "D2"), repeat=len(robot.limbs)))
    for combo, signs in zip(combos, kinematic_signs_all(robot, combos, body=body)):
        score = 0
        for a in range(len(reward)):
            for b in range(len(reward)):
                if a != b and allowed[a][b] and reward[a][b] != 0 and np.sign(signs[a][b]) == np.sign(reward[a][b]):
                    score += 1
        if score > best_score:
            best, best_score = combo, score
    _CACHE[key] = best
    return best


