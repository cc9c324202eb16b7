"""The claim bench's counts (issue 13's targets): from the rows ``claim.run_condition`` gives,
how many conditions the firmware completes, where it keeps 75 % of its nominal speed, how
the impossible ones stop, the learn-then-walk gait's and the idealised drive's counts."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from ..sim.physical.drive import BARELY_MOVES
from .claim import OVERHEAT_C, OVERHEATED, ConditionResult, DriveOutcome


def _clean_stop(fb: DriveOutcome) -> bool:
    """Stopped with a fault (a refused START included), its coils below 50 °C 2 s later, and no
    coil past ``OVERHEAT_C`` on the way: a stop that first ruined a coil is not clean."""
    return not fb.completed and bool(fb.fault) and fb.coil_max_end_c < 50.0 and fb.coil_peak_c <= OVERHEAT_C


#: The idealised drive "walks" a row when it makes at least this share of its nominal speed the
#: right way; below it, comparing the firmware's speed with it says nothing.
IDEALISED_FLOOR = BARELY_MOVES


def _learned_summary(results: Sequence[ConditionResult], nominal: ConditionResult, sign: float) -> dict[str, Any]:
    """The learn-then-walk gait's counts (``run_condition(learned=…)``), in the bench's
    direction (``sign``)."""
    if "learned_gait" not in nominal.extra:
        return {}
    lnom = nominal.extra["learned_gait"]["feedback"]["speed_mm_s"]
    lposs = [r.extra["learned_gait"] for r in results if r.extra["learned_gait"]["physically_possible"]]
    ldone = [g for g in lposs if g["feedback"]["completed"]]
    lkept = [g for g in ldone if sign * lnom > 0 and sign * g["feedback"]["speed_mm_s"] >= 0.75 * sign * lnom]
    limposs = [r.extra["learned_gait"] for r in results if not r.extra["learned_gait"]["physically_possible"]]
    lclean = [g for g in limposs if _clean_stop(DriveOutcome(**g["feedback"]))]
    return {"learned_gait_states": nominal.extra["learned_gait"]["states"],
            "learned_nominal_feedback_mm_s": round(lnom, 4),
            "learned_physically_possible": len(lposs),
            "learned_feedback_completed_where_possible": len(ldone),
            "learned_feedback_kept_75pct_where_possible": len(lkept),
            "learned_impossible": len(limposs),
            "learned_impossible_stopped_with_fault_and_cold_coils": len(lclean)}


def _idealised_summary(possible: Sequence[ConditionResult], nominal: ConditionResult, sign: float) -> dict[str, Any]:
    """How the idealised drive's own speed compares (``idealised_walk``): the rows a condition
    slows by itself, and how often the firmware keeps 75 % of what the idealised drive makes
    in the same row (counted only where that drive walks the row: ``IDEALISED_FLOOR``). Not
    counted when the idealised drive does not walk the bench's direction (``sign``) nominally."""
    ideal_nom = nominal.idealised_mm_s
    if not ideal_nom or sign * ideal_nom <= 0:
        return {}
    measured = [r for r in possible if r.idealised_mm_s is not None]
    walked = [r for r in measured if sign * r.idealised_mm_s >= IDEALISED_FLOOR * abs(ideal_nom)]
    return {
        "idealised_nominal_mm_s": round(ideal_nom, 4),
        "idealised_kept_75pct_where_possible": sum(sign * r.idealised_mm_s >= 0.75 * abs(ideal_nom) for r in measured),
        "idealised_walked_where_possible": len(walked),
        "idealised_barely_moves": [r.point.name for r in measured if r not in walked],
        "feedback_kept_75pct_of_idealised_where_it_walks": sum(
            r.feedback.completed and sign * r.feedback.speed_mm_s >= 0.75 * sign * r.idealised_mm_s for r in walked),
        "slowed_by_the_condition_itself": [
            r.point.name for r in measured if sign * r.idealised_mm_s < 0.75 * abs(ideal_nom)],
    }


def _slope_summary(results: Sequence[ConditionResult]) -> dict[str, Any]:
    sloped = [r for r in results if "levelled_on_ground" in r.extra]
    if not sloped:
        return {}
    return {"slope_conditions": len(sloped),
            "slope_completed_flat_calibration_only": sum(r.feedback.completed for r in sloped),
            "slope_completed_after_ground_levelling": sum(
                r.extra["levelled_on_ground"]["feedback"]["completed"] for r in sloped)}


def summarise(results: Sequence[ConditionResult], nominal: ConditionResult, direction: str = "+x") -> dict[str, Any]:
    """The targets of issue 13, counted honestly, in ``direction`` (the way the bench walks).

    Speeds count in that direction only: a nominal firmware run that walks the other way keeps
    nothing, and the open loop's bar is what its nominal run makes that way (none backwards),
    whether or not the bench calls the run completed, unless it overheated a coil (a drive
    that ruins its coils is no competitor; the tuner already avoids them: ``tune_open_loop_for``)."""
    sign = 1.0 if direction == "+x" else -1.0
    nom = nominal.feedback.speed_mm_s
    ahead = sign * nom  # the nominal firmware's speed in the bench's direction
    ol = nominal.open_loop
    ol_nom = 0.0 if ol.note.startswith(OVERHEATED) else max(0.0, sign * ol.speed_mm_s)
    possible = [r for r in results if r.possible]
    impossible = [r for r in results if not r.possible]
    done = [r for r in possible if r.feedback.completed]
    kept = [r for r in done if ahead > 0 and sign * r.feedback.speed_mm_s >= 0.75 * ahead]
    clean_stops = [r for r in impossible if _clean_stop(r.feedback)]
    return {
        **_learned_summary(results, nominal, sign),
        **_idealised_summary(possible, nominal, sign),
        **_slope_summary(results),
        "conditions": len(results),
        "physically_possible": len(possible),
        "feedback_completed_where_possible": len(done),
        "feedback_kept_75pct_where_possible": len(kept),
        "feedback_kept_75pct_fraction": round(len(kept) / len(possible), 4) if possible else None,
        "impossible": len(impossible),
        "impossible_stopped_with_fault_and_cold_coils": len(clean_stops),
        "open_loop_completed": sum(r.open_loop.completed for r in results),
        "open_loop_kept_75pct": sum(ol_nom > 0 and r.open_loop.completed and sign * r.open_loop.speed_mm_s
                                    >= 0.75 * ol_nom for r in results),
        "open_loop_bar_mm_s": round(ol_nom, 4),
        "nominal_feedback_mm_s": round(nom, 4),
        "nominal_open_loop_mm_s": round(nominal.open_loop.speed_mm_s, 4),
        "nominal_open_loop_completed": nominal.open_loop.completed,
        "targets": {
            "feedback completes every possible condition": len(done) == len(possible),
            "feedback keeps >= 75 % in >= 90 % of possible": bool(possible) and len(kept) >= 0.9 * len(possible),
            "impossible conditions stop with a fault and cold coils": len(clean_stops) == len(impossible),
            "nominal feedback at least as fast as open loop": ahead > 0 and ahead >= ol_nom,
        },
    }
