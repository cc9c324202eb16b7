"""``proleg learn``'s report and its learned robot file: from the trials in ``--log`` to what
is printed and written (docs/learning.md).

``with_track`` gives the trials recorded without their motion (``--source tracker``) theirs
from ``--track``; ``report_and_write`` prints the per-transition estimates on stdout, writes
``--out`` (before the table) and returns the exit code. Both read only the options, the robot
and the trials, never a link; a mistake in those is a ``LearnError`` (exit 2). Exploring,
and the options, are ``cli/learn.py``'s.
"""

from __future__ import annotations

import argparse
import logging
import math
import sys

import numpy as np

from ..errors import LearnError, ProlegError
from ..names import counted

log = logging.getLogger("proleg")


def with_track(args: argparse.Namespace, trials: list) -> list:
    if args.track is None:
        return trials
    from ..learn.tracker import GAP_FRAMES, TrackerError, attach_track, read_track

    try:
        track = read_track(args.track)
        bare = [t for t in trials if t.dx is None]
        if not bare:
            return trials
        attached, offset, outside = attach_track(bare, track, args.tracker_offset)
    except TrackerError as e:
        raise LearnError(f"learn: {e}") from None
    how = "given" if args.tracker_offset is not None else "estimated"
    span = (f"its times {track.t[0]:g}..{track.t[-1]:g} s, the trials' {min(t.t_start for t in bare) + offset:g}.."
            f"{max(t.t_end for t in bare) + offset:g} s on its clock (offset {offset:+.3f} s, {how})")
    if not attached:
        raise LearnError(f"learn: --track {args.track}: covers none of the {counted(len(bare), 'trial')} without motion: {span}; "
                         "give the track of this run, or --tracker-offset")
    settle = 0.05  # attach_track's settle_s: the poses are read that long after each event
    gaps = [g for g in ((track.gap_around(t.t_start + settle + offset) or track.gap_around(t.t_end + settle + offset))
                        for t in outside) if g is not None]
    if len(gaps) < len(outside):
        log.warning("learn: --track %s: %d of %s begin or end outside it and are left without motion "
                    "(%s)", args.track, len(outside) - len(gaps), counted(len(bare), "trial"), span)
    if gaps:
        log.warning("learn: --track %s: %d of %s fall in a gap of it and are left without motion (no frame from "
                    "%g to %g s%s, on its clock: more than %d of its frame intervals; the camera lost the robot, "
                    "or dropped frames)", args.track, len(gaps), counted(len(bare), "trial"), gaps[0][0], gaps[0][1],
                    "" if len(set(gaps)) == 1 else f", and {counted(len(set(gaps)) - 1, 'other gap')}", GAP_FRAMES)
    log.info("%s: %s given their motion (clock offset %+.3f s, %s)", args.track, counted(len(attached), "trial"), offset,
             how)
    return [t for t in trials if t.dx is not None] + attached + outside


def _strayed(trials) -> str:
    """``a->b k/n (via s, …)`` for every transition some of whose trials passed through a state
    outside it (``Trial.passed``), in first-seen order; "" when none did."""
    seen: dict[tuple[str, str], list[int]] = {}
    via: dict[tuple[str, str], dict[str, None]] = {}
    for tr in trials:
        k = (tr.src, tr.dst)
        seen.setdefault(k, [0, 0])[1] += 1
        if tr.passed:
            seen[k][0] += 1
            via.setdefault(k, {}).update(dict.fromkeys(tr.passed))
    return ", ".join(f"{a}->{b} {seen[a, b][0]}/{seen[a, b][1]} (via {', '.join(v)})" for (a, b), v in via.items())


def _fmt(v: float, nd: int = 2) -> str:
    if v is None or (isinstance(v, float) and math.isnan(v)):
        return "-"
    text = f"{v:.{nd}f}"
    return text[1:] if text.startswith("-") and not text.strip("-0.") else text  # -0.00 is 0.00


def _trial_units(args: argparse.Namespace, robot, trials: list) -> str:
    """The unit the trials' Δx are in: mm for the simulator's, the robot file's for a tracker's
    or a hand's. A log that mixes the two (resumed with another source) cannot be averaged."""
    sources = {tr.source for tr in trials}
    if "sim" not in sources:
        return robot.units
    others = sorted(s or "unsaid" for s in sources - {"sim"})
    if others and robot.units != "mm":
        raise LearnError(f"learn: {args.log} mixes simulated trials (Δx in mm) with {', '.join(others)} ones (in "
                         f"{robot.units}, the robot file's unit); learn them from separate logs")
    return "mm"  # the plant moves in mm


#: how many transitions the report's "too few trials" line names before it counts the rest
FLAGGED_SHOWN = 10


def report_and_write(args: argparse.Namespace, robot, trials: list, failures: list = ()) -> int:
    """Print the report of ``trials`` (and ``failures``, the transitions the robot faulted on:
    ``measure.Failure``), write ``--out``; the exit code."""
    from ..learn.estimate import estimate, penalised_table
    from ..learn.makeable import KINDS, not_asked, report_lines
    from ..learn.robotfile import write_learned_robot

    t = robot.transitions
    bare = sum(1 for tr in trials if tr.dx is None)
    if bare and bare == len(trials):  # a tracker's trials, no track attached: nothing to estimate
        what = (f"learn: {args.log}: {counted(bare, 'transition')} recorded without their motion (Δx; --source tracker): "
                f"attach the tracker's track with --track FILE.csv (proleg learn {args.robot} --log {args.log} "
                "--track FILE.csv --report)")
        if args.report or args.out or args.half_width:
            raise LearnError(what + "; nothing to report")
        print(what, file=sys.stdout)
        return 0
    units = _trial_units(args, robot, trials)
    est = estimate(t, trials)
    out = sys.stdout
    dx = est.dx
    # transitions exploring leaves out (learn/makeable.py: the hardware cannot make them, the body
    # cannot hold their state, the robot faulted making them): not measured, said so, and "x" in
    # the learned file (one measured after all keeps its trials)
    left = not_asked(robot, try_unholdable=getattr(args, "try_unholdable", False), failures=failures)
    left_out = {e: why for e, why in left.items() if dx.n[e] == 0}
    path = None
    if args.out:  # written before the table is printed: a reader that goes away (| head) loses no file
        if not int(dx.n.sum()):
            raise LearnError(f"learn: {args.log} holds no trial with a measured motion; nothing to write")
        path = write_learned_robot(robot, est, args.out, units=units, stats_as_keys=True, left_out=left_out)
    print(f"{robot.name}: {counted(int(dx.n.sum()), 'trial')}, {counted(t.n_transitions, 'allowed transition')} "
          f"(Δx in {units}, {int(est.confidence * 100)} % intervals)", file=out)
    extra = est.extra_trials(args.half_width) if args.half_width else None
    if extra is not None and left_out:
        extra[list(left_out)] = 0
    head = f"{'transition':>12} {'n':>3} {'mean Δx':>9} {'var':>8} {'interval':>19}"
    planar = "dy" in est.components and bool(np.any(est.components["dy"].n > 0))
    if planar:
        head += f" {'mean Δy':>8} {'mean Δθ':>8}"
    if extra is not None:
        head += f" {'more':>5}"
    print(head, file=out)
    for e, (a, b) in enumerate(zip(t.src.tolist(), t.dst.tolist())):
        lab = f"{t.label(a)}->{t.label(b)}"
        if e in left_out:
            print(f"{lab:>12} {0:>3} {'-':>9} {'-':>8} {KINDS[left_out[e].kind].tag:>19}", file=out)
            continue
        ci = "-" if math.isnan(dx.half_width[e]) else f"[{dx.low[e]:.2f}, {dx.high[e]:.2f}]"
        row = f"{lab:>12} {int(dx.n[e]):>3} {_fmt(dx.mean[e]):>9} {_fmt(dx.var[e]):>8} {ci:>19}"
        if planar:
            row += f" {_fmt(est.components['dy'].mean[e]):>8} {_fmt(est.components['dtheta_deg'].mean[e], 1):>8}"
        if extra is not None:
            row += f" {int(extra[e]):>5}"
        print(row, file=out)
    if bare:
        print(f"{bare} more transitions recorded without their motion (Δx) are not counted: attach the "
              "tracker's track with --track FILE.csv", file=out)
    for line in report_lines(t, left_out, FLAGGED_SHOWN):
        print(line, file=out)
    skip = {f"{t.label(int(t.src[e]))}->{t.label(int(t.dst[e]))}" for e in left_out}
    flagged = [f for f in est.flagged() if f not in skip]
    if flagged:  # the table above has each one's n: a few names and the count, not hundreds of them
        shown = ", ".join(flagged[:FLAGGED_SHOWN]) + (
            f", … ({len(flagged) - FLAGGED_SHOWN} more; column n)" if len(flagged) > FLAGGED_SHOWN else "")
        print(f"too few trials (< {est.min_samples}): {len(flagged)} of {t.n_transitions}: {shown}", file=out)
    if strayed := _strayed(trials):
        print("passed through other states on the way (a limb crossed a level it should have kept; "
              f"their Δx includes those crossings): {strayed}", file=out)
    if extra is not None:
        why = ("every interval is that narrow" if not extra.sum() else
               "still, after --more: the new trials changed the intervals' variances; run the same command "
               "again for more" if getattr(args, "more", False) else "run them with --more and a robot link")
        print(f"extra trials for ± {args.half_width:g}: {int(extra.sum())} ({why})", file=out)
    if int(dx.n.sum()) and (args.variance_weight or args.report):
        from ..gait import optimal_gaits

        try:
            table = penalised_table(est, args.variance_weight, fallback=t)
            if left_out:  # a gait the hardware cannot make is no best gait
                from ..learn.makeable import without_edges

                table = without_edges(table, left_out)
            res = optimal_gaits(table, "total", "+x")
            best = res.gaits[0] if res.gaits and res.value is not None else None
        except ProlegError:
            best = None
        if best is not None:
            what = "mean" if not args.variance_weight else f"mean − {args.variance_weight:g}·σ"
            print(f"best +x gait for {what}: {','.join(t.label(s) for s in best.states)}", file=out)
    if path is not None:
        print(f"wrote {path}", file=out)
        log.info("learn: next: proleg gait %s shows the best gaits of the learned matrix; proleg build/flash %s "
                 "puts them on the robot", path, path)
    elif int(dx.n.sum()):
        log.info("learn: next: add --out LEARNED.toml to write the robot file with the learned matrix (the "
                 "trials are in %s; nothing is explored again)", args.log)
    return 0
