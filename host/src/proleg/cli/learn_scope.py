"""What ``proleg learn`` says of what it explores and of why it stopped: a robot file that
leaves nothing to explore (``check_explorable``: a ``LearnError`` naming the file), what an
exploration covers and leaves out (``explored``), and what to do after a fault ends one
(``stopped_hint``) or after the simulated robot faulted on transitions the load checks did
not foresee (``faulted_hint``, ``predicted``)."""

from __future__ import annotations

import argparse

from ..errors import LearnError


def check_explorable(robot, try_unholdable: bool = False) -> None:
    """``LearnError`` for a robot whose file leaves nothing to explore: no allowed transition,
    or none on a closed tour from rest (each unreachable from rest or without a way back). It
    created the log, explored nothing and ended in an empty report (exit 0), or, with --out,
    "t.jsonl holds no trial with a measured motion", naming the log, not the robot file."""
    from ..learn.makeable import makeable_robot, not_asked, skipped_lines
    from ..learn.tours import exploration, unexplorable

    t = robot.transitions
    where = getattr(robot, "where", robot.name)
    if t.n_transitions == 0:
        raise LearnError(f"learn: {where}: the robot file allows no transition (its table forbids every one): "
                         "nothing to explore")
    drop = not_asked(robot, try_unholdable=try_unholdable)
    made = makeable_robot(robot, drop).transitions
    if made.n_transitions == 0:
        raise LearnError(f"learn: {where}: none of its {t.n_transitions} allowed transitions is one learning asks "
                         f"for ({'; '.join(skipped_lines(robot, drop))}): nothing to explore; fix what the warnings "
                         "when the robot file is loaded name")
    unreachable, one_way = unexplorable(made, exploration(made, 1).uncoverable)
    if len(unreachable) + len(one_way) >= made.n_transitions:
        parts = [f"{len(x)} {why} ({', '.join(x[:5])}{', …' if len(x) > 5 else ''})"
                 for x, why in ((unreachable, "unreachable from rest"), (one_way, "one-way, no allowed way back")) if x]
        parts[:0] = skipped_lines(robot, drop)
        raise LearnError(f"learn: {where}: none of its {t.n_transitions} allowed transitions is on a closed tour "
                         f"from rest ({'; '.join(parts)}): nothing to explore; allow the transitions that lead "
                         "there from rest and back (in the matrix; with matrix = \"unmeasured\": its allow and "
                         "forbidden)")


def explored(robot, drop: dict, repeats: int) -> str:
    """``N allowed transitions[, K of them … (a->b, …)]: M × R``: what the exploration covers,
    naming the transitions learning leaves out (``drop``: ``makeable.not_asked``) and those no
    closed tour from rest can make (they get no trials)."""
    from ..learn.makeable import makeable_robot, skipped_lines
    from ..learn.tours import exploration, unexplorable

    t = robot.transitions
    made = makeable_robot(robot, drop).transitions
    unreachable, one_way = unexplorable(made, exploration(made, 1).uncoverable)
    left = skipped_lines(robot, drop)
    for labels, why in ((unreachable, "unreachable from rest"), (one_way, "one-way, no allowed way back")):
        if labels:
            shown = ", ".join(labels[:5]) + (f", … ({len(labels) - 5} more)" if len(labels) > 5 else "")
            left.append(f"{len(labels)} of them {why} ({shown})")
    skipped = len(drop) + len(unreachable) + len(one_way)
    head = f"{t.n_transitions} allowed transitions" + "".join(f", {x}" for x in left)
    return f"{head}: {t.n_transitions - skipped} × {repeats}" if skipped else f"{head} × {repeats}"


def stopped_hint(args: argparse.Namespace, e: Exception) -> str:
    """What to do about an exploration that stopped on a fault it does not go on from (an
    E-stop, a fault while no transition was being made, several transitions in a row faulted):
    on a real robot, look at it and clear the fault; the simulated one does not outlive the
    command, and running it again meets the same fault. (A fault while making a transition no
    longer stops learning: ``Explorer`` records it and goes on; ``faulted_hint``.)"""
    if not getattr(e, "fault", False):
        return ""
    if not args.sim:
        return "; look at the robot (proleg console), then clear the fault (key c there)"
    return "; the simulated robot meets it again if run the same way: check the warnings printed when the robot file was loaded"


def faulted_hint(args: argparse.Namespace, robot, failed: list[tuple[str, str]]) -> str:
    """For the end of an exploration on the simulated robot that faulted making ``failed``
    (labels): when the load checks predicted none of some of them, say so and how to find out
    (the physical plant can stop a step its body model's checks pass: a step slower than the
    state timeout, a weak coil)."""
    surprise = [f"{a}->{b}" for a, b in failed if not predicted(robot, a, b)]
    if not args.sim or not surprise:
        return ""
    return (f"; no warning at load predicts {', '.join(surprise)} (the body model's checks pass "
            f"{'it' if len(surprise) == 1 else 'them'}): proleg sim {args.robot} --measure-matrix says whether the "
            "body can make them at all (its not_made list); if it can, the firmware's control failed them on this "
            "body (or a [plant] condition did)")


def predicted(robot, a: str, b: str) -> bool:
    """Whether the load checks warned about the step ``a`` -> ``b`` (labels): a state that
    cannot be held or a step that cannot end on the simulated body, or a limb that cannot
    reach one of its levels."""
    from ..robot_body import warned_step

    t = robot.transitions
    try:
        ia, ib = t.index(a), t.index(b)
    except ValueError:  # a label the table does not know: nothing to look up
        return True
    return warned_step(robot, ia, ib)
