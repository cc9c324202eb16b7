"""``proleg gait``: optimal gaits of a robot (along ±x, along a heading in the plane, turning
on the spot, or a library of them), or the score of a typed sequence.

Without a planar option the answer is today's: ``--direction`` +x / −x / both on the
``matrix`` rewards. With ``--heading``, ``--variance-weight``, ``--transition-cost``,
``--rotation-cap-deg``, ``--simple-cycles``, ``--rotate`` or ``--library`` the question is
planar (``proleg.gait.planar``; docs/planar.md) and every gait also shows its SE(2)-composed
net motion per pass and the path of ``--cycles`` passes (``--plot FILE.png`` draws them; with
``--evaluate`` it draws the typed sequence). ``--cycles`` where no path is composed is refused.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

from ..errors import GaitError
from ..names import counted
from ..robot_transitions import HOW_TO_MEASURE
from .number_args import (
    cycles,
    heading_deg,
    max_transitions,
    non_negative_float,
    positive_int,
)

DIRECTIONS = ("+x", "-x")
#: Ties the text lists per answer unless --ties N / --all-ties says otherwise (a 256-state
#: robot ties 10,000 gaits a direction: 20,000 lines); --json lists every one unless --ties N.
TEXT_TIES = 10
PLANAR_FLAGS = ("heading", "variance_weight", "transition_cost", "rotation_cap_deg", "simple_cycles", "rotate", "library")


def add_gait_parser(sub) -> None:
    """Register ``proleg gait`` on the one parser's subcommands."""
    from .main import robot_arg  # a robot file or a bundled example's name

    g = sub.add_parser("gait", help="optimal gaits of a robot, or the score of a sequence")
    g.add_argument("robot", metavar="ROBOT", type=robot_arg)
    g.add_argument("--objective", choices=("total", "rate", "speed"),
                   help="total (the default), rate or speed (docs/gait-selection.md)")
    g.add_argument("--direction", choices=("+x", "-x", "both"), default=None,
                   help="which way to optimise (default both; a planar option gives its own heading)")
    g.add_argument("--max-transitions", type=max_transitions, metavar="N", help="longest gait, 2..256")
    g.add_argument("--evaluate", metavar="SEQ", help="score a closed walk of state labels, the start repeated at the end or not: "
                                                  "00,10,11,01,00 or 00,10,11,01")
    g.add_argument("--json", action="store_true", help="print one JSON object")
    ties = g.add_mutually_exclusive_group()
    ties.add_argument("--ties", type=positive_int, metavar="N",
                      help=f"list the first N optimal gaits of each answer (text: {TEXT_TIES} by default; "
                           "--json: every one by default, and 'ties' says how many there are)")
    ties.add_argument("--all-ties", action="store_true", help="list every optimal gait in the text too")
    p = g.add_argument_group("planar gaits (robot files with dy / dtheta_deg / var_*; docs/planar.md)")
    p.add_argument("--heading", type=heading_deg, metavar="DEG",
                   help="score motion along this heading (0 = +x, 90 = +y; within ±3600)")
    p.add_argument("--variance-weight", type=_weights, metavar="λ|λx,λy,λθ",
                   help="subtract λ·(var_dx + var_dy + var_dtheta_deg), those the robot file gives, or each "
                        "with its own weight")
    p.add_argument("--transition-cost", type=_penalty, metavar="κ",
                   help="subtract κ ≥ 0 per transition (a cost: prefers short gaits)")
    p.add_argument("--rotation-cap-deg", type=non_negative_float, metavar="DEG", help="only gaits turning at most this much per pass")
    p.add_argument("--simple-cycles", action="store_true", help="only simple cycles (each state once per pass)")
    p.add_argument("--rotate", choices=("cw", "ccw"), help="the gait that turns the most this way")
    p.add_argument("--translation-cap", type=non_negative_float, metavar="D",
                   help="with --rotate: at most this translation per pass (default: one mean step)")
    p.add_argument("--library", metavar="HEADINGS", help="best gait per heading, e.g. 0,90,180,270,rot-cw,rot-ccw")
    p.add_argument("--cycles", type=cycles, metavar="N",
                   help="passes in the composed path of a planar answer or of --plot (default 10, at most 10,000); "
                        "refused where nothing composes a path")
    p.add_argument("--plot", metavar="FILE.png",
                   help="draw each answer's gait 0 (with --evaluate: that sequence) composed over --cycles passes")
    g.set_defaults(run=cmd_gait)


def _weights(text: str) -> float | tuple[float, float, float]:
    """One λ (a float: every variance the robot file gives) or λx,λy,λθ (a tuple: each its own)."""
    parts = [p.strip() for p in text.split(",")]
    if len(parts) not in (1, 3):
        raise argparse.ArgumentTypeError(f"expected λ or λx,λy,λθ, got {text!r}")
    values = [_penalty(p) for p in parts]
    return values[0] if len(values) == 1 else (values[0], values[1], values[2])


def _penalty(text: str) -> float:
    """A transition cost or variance weight: a number in [0, MAX_PENALTY]."""
    from ..gait.planar import MAX_PENALTY

    v = non_negative_float(text)
    if v > MAX_PENALTY:
        raise argparse.ArgumentTypeError(f"expected a number in [0, {MAX_PENALTY:g}], got {text!r}")
    return v


def _variance_weights(robot, given: float | tuple[float, float, float] | None) -> tuple[float, float, float]:
    """``--variance-weight`` as (λx, λy, λθ): a list as given, one λ by ``library.one_weight``."""
    from ..gait.library import one_weight

    if given is None:
        return (0.0, 0.0, 0.0)
    if isinstance(given, tuple):
        return given
    return one_weight(robot.transitions, given)


def check_speed_objective(robot, objective: str) -> None:
    """``--objective speed`` divides by the transitions' durations: a robot file without them is
    a GaitError naming the file and the key to give."""
    if objective == "speed" and robot.transitions.duration is None:
        raise GaitError(f"--objective speed: {robot.path} gives no transition durations (expected "
                        "transitions.durations_s or transitions.default_duration_s, or a duration_s column in its CSV)")


def cmd_gait(args: argparse.Namespace) -> int:
    from ..robot import load_robot

    robot = load_robot(args.robot)
    planar = any(getattr(args, k) is not None and getattr(args, k) is not False for k in PLANAR_FLAGS)
    _check_cycles(args, planar)
    # what the command line gave, before a [gaits] table fills in the rest of --library's options
    given = {k for k in (*PLANAR_FLAGS, "translation_cap", "max_transitions", "direction")
             if getattr(args, k) is not None and getattr(args, k) is not False}
    if args.evaluate is not None:
        args.objective = args.objective or "total"
        check_speed_objective(robot, args.objective)
        if args.ties is not None or args.all_ties:
            raise GaitError(f"{'--ties' if args.ties is not None else '--all-ties'}: not with --evaluate "
                            "(it scores one sequence; the ties are those of an optimisation)")
        ignored = [k for k in (*PLANAR_FLAGS, "max_transitions", "direction") if k in given]
        if ignored:  # they were taken and ignored: the score printed was not the one asked for
            raise GaitError(f"--{ignored[0].replace('_', '-')}: not with --evaluate (it scores the sequence given by "
                            "its reward J; options of an optimisation do not apply)")
        return _print_evaluation(robot, args)
    if args.library is not None and robot.library is not None:
        _library_options(robot, args)
    args.objective = args.objective or "total"
    check_speed_objective(robot, args.objective)
    if args.direction is not None and any(getattr(args, k) is not None for k in ("heading", "rotate", "library")):
        raise GaitError(f"--direction {args.direction}: not with a planar option (--heading, --rotate or --library "
                        "gives the way: heading 0 is +x, 180 is -x)")
    args.direction = args.direction or "both"
    if not planar:
        if args.translation_cap is not None:
            raise GaitError("--translation-cap only applies with --rotate or rot-cw/rot-ccw in --library")
        from ..firmware.gaits import default_max_transitions
        from ..gait import optimal_gaits

        directions = DIRECTIONS if args.direction == "both" else (args.direction,)
        # without --max-transitions, the bound the firmware build uses (caterpillar-4: 36 states)
        bound = args.max_transitions if args.max_transitions is not None else default_max_transitions(
            robot, args.objective)
        answers = [(d, optimal_gaits(robot.transitions, args.objective, d, bound)) for d in directions]
    else:
        try:
            answers = _planar_answers(robot, args, given)
        except GaitError as e:
            raise GaitError(f"{robot.path}: {e}") from None
    if args.plot:
        _plot(robot, answers, args.cycles, args.plot, args.json)
    if args.json:
        doc = {
            "robot": robot.name,
            "states": robot.transitions.labels(),
            "results": [_result_json(robot, name, r, planar, args.cycles, args.ties) for name, r in answers],
        }
        print(json.dumps(doc))
        return 0
    shown = None if args.all_ties else args.ties or TEXT_TIES
    print(_header(robot))
    for name, r in answers:
        print(_result_text(robot, name, r, planar, args.cycles, shown))
    return 0


def _check_cycles(args: argparse.Namespace, planar: bool) -> None:
    """``--cycles`` only where a path is composed: --plot, or a planar answer's text."""
    if args.cycles is not None and not args.plot and (args.evaluate is not None or not planar):
        raise GaitError(f"--cycles {args.cycles}: only with --plot{'' if args.evaluate else ' or a planar option'} "
                        "(nothing else composes a path)")
    args.cycles = args.cycles or 10


def _library_options(robot, args) -> None:
    """``--library`` on a robot file with ``[gaits]``: the options it leaves out are the file's,
    so that the answer is the library the firmware carries (``proleg build`` takes them)."""
    for key, value in robot.library.as_kwargs().items():
        if getattr(args, key, None) in (None, False):
            setattr(args, key, tuple(value) if isinstance(value, list) else value)


def _planar_answers(robot, args, given: set[str]) -> list:
    """The planar question's answers; ``given``: the options the command line gave (a cap that
    applies to none of the headings asked for is refused: it was taken and ignored)."""
    from ..gait.library import Heading, gait_library, parse_headings

    ways = [k for k in ("heading", "rotate", "library") if getattr(args, k) is not None]
    if len(ways) > 1:
        raise GaitError(f"give one of --heading, --rotate and --library, not --{ways[0]} and --{ways[1].replace('_', '-')}")
    if args.library is not None:
        headings = parse_headings(args.library)
    elif args.rotate is not None:
        headings = [Heading(f"rot-{args.rotate}", rotate=args.rotate)]
    elif args.heading is not None:
        headings = [Heading(f"{args.heading:g}", heading_deg=args.heading)]
    else:
        headings = [Heading(d, heading_deg=0.0 if d == "+x" else 180.0)
                    for d in (DIRECTIONS if args.direction == "both" else (args.direction,))]
    turns = [h for h in headings if h.rotate is not None]
    if "rotation_cap_deg" in given and len(turns) == len(headings):
        raise GaitError("--rotation-cap-deg caps how far a heading's gait turns; it does not apply to "
                        f"{', '.join(h.name for h in turns)} (a turn in place: --translation-cap bounds its drift)")
    if "translation_cap" in given and not turns:
        raise GaitError("--translation-cap bounds a turn's drift; it applies with --rotate or rot-cw/rot-ccw in "
                        "--library, not to headings")
    entries = gait_library(
        robot.transitions, headings, args.objective, args.max_transitions,
        variance_weight=_variance_weights(robot, args.variance_weight),
        transition_cost=args.transition_cost or 0.0,
        rotation_cap_deg=args.rotation_cap_deg,
        simple_cycles=args.simple_cycles,
        translation_cap=args.translation_cap,
    )
    return [(e.heading.name, e.result) for e in entries]


def _header(robot) -> str:
    t = robot.transitions
    shown = " ".join(t.labels()) if t.n_states <= 16 else f"{t.label(0)} … {t.label(t.n_states - 1)}"
    return (
        f"{robot.name}: {counted(len(robot.limbs), 'limb')}, {t.n_states} states ({shown}), "
        f"{t.n_transitions} allowed transitions, rewards in {robot.units}"
    )


def _fmt(x: float) -> str:
    return f"{x:+.6g}"


def _title(name: str, planar: bool) -> str:
    if not planar or name in DIRECTIONS:
        return name
    return name if name.startswith("rot-") else f"heading {name}°"


def _result_text(robot, name: str, r, planar: bool, cycles: int, shown: int | None = None) -> str:
    """One answer as text: its value and its first ``shown`` gaits (all when None), each with
    the notes, problems and way in from rest; a line saying how many more there are."""
    t = robot.transitions
    what = {"total": "total", "rate": "per transition", "speed": "per second"}[r.objective]
    what = f"score {what}" if planar else {"total": "total reward J", "rate": "reward per transition",
                                           "speed": f"{robot.units} per second"}[r.objective]
    bound = f", at most {counted(r.max_transitions, 'transition')}" if r.max_transitions is not None else ""
    head = f"\n{_title(name, planar)}  {r.objective} ({what}{bound}): "
    if r.value is None:
        why = f" (its matrix is unmeasured: learn it {HOW_TO_MEASURE})" if getattr(robot, "unmeasured", False) else ""
        return head + (f"no gait moves the robot in {name}" if name in DIRECTIONS else "no gait") + why
    n = len(r.gaits)
    head += f"best {_fmt(r.value)}, {counted(n, 'optimal gait')}"
    if r.below_zero:
        head += " (no gait scores above zero: the best one is shown)"
    if r.truncated:
        head += f" (listing stopped after {n}: more ties exist)"
    lines = [head]
    listed = r.gaits if shown is None else r.gaits[:shown]
    walks = [" → ".join(t.label(s) for s in gait.states) for gait in listed]
    width = max(len(w) for w in walks)
    for walk, gait in zip(walks, listed):
        extra = f"  ×{gait.repeats}" if gait.repeats > 1 else ""
        extra += f"  T={gait.duration:.3g}s" if gait.duration is not None else ""
        lines.append(f"    {walk:<{width}}    J={_fmt(gait.reward)}{extra}  N={gait.transitions}  rate={_fmt(gait.rate)}")
        if planar:
            from ..gait.compose import gait_path

            path = gait_path(t, gait.states, cycles)
            one = path[gait.transitions]
            lines.append(f"      per pass Δx={_fmt(one.x)} Δy={_fmt(one.y)} {robot.units}  Δθ={_fmt(one.theta_deg)}°;"
                         f" after {counted(cycles, 'pass')} ({path[-1].x:+.4g}, {path[-1].y:+.4g}) {robot.units},"
                         f" {path[-1].theta_deg:+.4g}°")
    for walk, gait in zip(walks, listed):
        steps = _opposing_text(t, gait)
        if steps:
            lines.append(f"    note: {walk} raises one limb while lowering another in {steps}; an SMA robot")
            lines.append("          may make such a step as two transitions (heating and cooling differ in speed)")
    for walk, gait in zip(walks, listed):
        guessed = _unmeasured_steps(robot, gait)
        if guessed:
            steps = ", ".join(f"{t.label(a)} → {t.label(b)}" for a, b in guessed)
            lines.append(f"    note: {walk} takes {steps} at the value the file had before learning (n_trials 0:")
            lines.append("          never measured), so its reward is partly a guess; learn those steps before trusting it")
    for walk, gait in zip(walks, listed):
        problems, entry = _feasibility(robot, gait)
        for p in problems:
            lines.append(f"    {p.severity}: {p.message}")
        if entry is not None and entry.transitions:
            names = " → ".join(t.label(s) for s in entry.states)
            lines.append(f"    entry: {walk} is entered from rest by {names} (joining at the gait's state {entry.gait_step + 1})")
    if len(listed) < n:
        more = n - len(listed)
        lines.append(f"    … and {counted(more, 'more tie', spec=',')}: --ties N or --all-ties lists them, "
                     "--json lists every one")
    return "\n".join(lines)


def _feasibility(robot, gait):
    """(problems other than the opposing steps noted above, entry path or None)."""
    from ..gait.feasibility import entry_path, gait_problems

    problems = [p for p in gait_problems(robot, gait.states) if p.kind != "opposing"]
    try:
        entry = entry_path(robot, gait.states)
    except GaitError:
        entry = None
    return problems, entry


def _opposing_text(table, gait) -> str:
    from ..states import opposing_steps

    steps = opposing_steps(gait.states, table.levels)
    return ", ".join(f"{table.label(gait.states[t])} → {table.label(gait.states[t + 1])}" for t in steps)


def _unmeasured_steps(robot, gait) -> list[tuple[int, int]]:
    """The steps of ``gait`` that a learned file (it carries ``n_trials``) never measured: their
    reward is the file's own value from before learning (docs/learning.md), a guess."""
    n_trials = getattr(robot, "n_trials", None)
    if n_trials is None:
        return []
    t = robot.transitions
    trials = {(int(a), int(b)): int(k) for a, b, k in zip(t.src, t.dst, n_trials)}
    steps = list(zip(gait.states, gait.states[1:]))
    return [(int(a), int(b)) for a, b in steps if trials.get((int(a), int(b)), 1) == 0]


def _gait_json(robot, gait, planar: bool = False, cycles: int = 10) -> dict:
    from ..states import opposing_steps

    table = robot.transitions
    d = {
        "states": [table.label(s) for s in gait.states],
        "reward": gait.reward,
        "transitions": gait.transitions,
        "rate": gait.rate,
        "opposing_steps": [
            [table.label(gait.states[t]), table.label(gait.states[t + 1])]
            for t in opposing_steps(gait.states, table.levels)
        ],
    }
    if getattr(robot, "n_trials", None) is not None:
        d["unmeasured_steps"] = [[table.label(a), table.label(b)] for a, b in _unmeasured_steps(robot, gait)]
    if gait.duration is not None:
        d["duration_s"] = gait.duration
    # what the text shows of every gait: how often it repeats within the bound (value =
    # reward × repeats), what the hardware cannot do, and the way in from rest
    problems, entry = _feasibility(robot, gait)
    d.update({
        "repeats": gait.repeats,
        "problems": [{"kind": p.kind, "severity": p.severity, "message": p.message} for p in problems],
        "entry_path": None if entry is None else {"states": [table.label(s) for s in entry.states],
                                                  "gait_step": entry.gait_step},
    })
    if planar:
        from ..gait.compose import gait_path

        path = gait_path(table, gait.states, cycles)
        one = path[gait.transitions]
        d.update({
            "net_motion": {"dx": one.x, "dy": one.y, "dtheta_deg": one.theta_deg},
            "path": [[p.x, p.y, p.theta_deg] for p in path],
        })
    return d


def _result_json(robot, name: str, r, planar: bool, cycles: int, shown: int | None = None) -> dict:
    """One answer: ``gaits`` holds every tie in rank order, or the first ``shown`` (--ties N);
    ``ties`` is how many there are (more than ``len(gaits)`` when capped; with ``truncated``
    the listing itself stopped at ``MAX_TIES``)."""
    d = {
        "direction": name,
        "objective": r.objective,
        "max_transitions": r.max_transitions,
        "value": r.value,
        "ties": len(r.gaits),
        "gaits": [_gait_json(robot, g, planar, cycles) for g in (r.gaits if shown is None else r.gaits[:shown])],
    }
    if planar:
        d["below_zero"] = r.below_zero
        d["path_cycles"] = cycles
    if r.truncated:
        d["truncated"] = True
    return d


def _plot(robot, answers, cycles: int, out: str, json_out: bool = False) -> None:
    """Each answer's gait 0 composed over ``cycles`` passes, in one plane, PNG/SVG/PDF; says
    "wrote PATH" as plot and dbc do (on stderr when stdout carries JSON)."""
    from ..gait.compose import gait_path
    from ..outputs import note_stream
    from ..plot import figure_problem, new_figure, write_figure

    path = Path(out)
    problem = figure_problem(path, "gait --plot")
    if problem:
        raise GaitError(f"--plot {out}: {problem}")
    t = robot.transitions
    fig = new_figure(7, 7)
    ax = fig.subplots()
    missing = [name for name, r in answers if not r.gaits]
    for i, (name, r) in enumerate(answers):
        if not r.gaits:
            continue
        g = r.gaits[0]
        poses = gait_path(t, g.states, cycles)
        xs, ys = [p.x for p in poses], [p.y for p in poses]
        walk = "→".join(t.label(s) for s in g.states)
        ax.plot(xs, ys, color=f"C{i}", lw=1.2, label=f"{name}: {walk}")
        ax.plot(xs[:: g.transitions], ys[:: g.transitions], "o", color=f"C{i}", ms=3)
        end = poses[-1]
        L = 0.05 * max(1e-9, max(abs(v) for v in xs + ys))
        ax.annotate("", xy=(end.x + L * math.cos(math.radians(end.theta_deg)), end.y + L * math.sin(math.radians(end.theta_deg))),
                    xytext=(end.x, end.y), arrowprops={"arrowstyle": "->", "color": f"C{i}"})
    ax.plot([0], [0], "k+", ms=10)
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel(f"x ({robot.units}, start frame)")
    ax.set_ylabel(f"y ({robot.units})")
    ax.set_title(f"{robot.name}: {counted(cycles, 'pass')} of each gait (dots: one pass)")
    ax.grid(True, lw=0.3)
    if len(missing) < len(answers):  # (a legend of nothing was matplotlib's UserWarning on stderr)
        ax.legend(loc="best", fontsize="small")
    if missing:  # an answer without a gait is said, not left out of the figure without a word
        ax.text(0.02, 0.02, "no gait moves the robot: " + ", ".join(missing), transform=ax.transAxes,
                fontsize="small", va="bottom")
    write_figure(fig, path)
    print(f"wrote {path}", file=sys.stderr if json_out else note_stream(path))


def _print_evaluation(robot, args) -> int:
    from ..gait import evaluate_sequence

    table = robot.transitions
    try:
        cycle = table.cycle(args.evaluate, [limb.name for limb in robot.limbs])
    except ValueError as e:
        raise GaitError(f"--evaluate: {e}") from None
    seq = [*cycle, cycle[0]]
    names = [table.label(x) for x in seq]
    try:
        gait = evaluate_sequence(table, seq)
    except GaitError as e:  # a bad gait is a usage error (exit 2), as the README says
        if not args.json:
            raise GaitError(f"--evaluate: {' → '.join(names)} is not a valid gait of {robot.name}: {e}") from None
        print(json.dumps({"robot": robot.name, "evaluation": {"states": names, "valid": False, "reason": str(e)}}))
        print(f"proleg: error: --evaluate: {' → '.join(names)} is not a valid gait of {robot.name}: {e}", file=sys.stderr)
        return 2
    if args.plot:
        from types import SimpleNamespace

        _plot(robot, [("evaluated", SimpleNamespace(gaits=[gait]))], args.cycles, args.plot, args.json)
    walk = " → ".join(table.label(s) for s in gait.states)
    problems, entry = _feasibility(robot, gait)
    errors = [p for p in problems if p.severity == "error"]
    if args.json:
        # "valid": the matrix allows every step; "feasible": the hardware can also make them
        print(json.dumps({"robot": robot.name, "evaluation": {"valid": True, "feasible": not errors,
                                                              **_gait_json(robot, gait)}}))
    else:
        # T as the listing shows it, where the file gives durations (it was in --json only)
        took = f"  T={gait.duration:.3g}s" if gait.duration is not None else ""
        print(f"{robot.name}: {walk}    J={_fmt(gait.reward)}{took}  N={gait.transitions}  rate={_fmt(gait.rate)}")
        steps = _opposing_text(table, gait)
        if steps:
            print(f"    note: raises one limb while lowering another in {steps}")
        for p in problems:
            print(f"    {p.severity}: {p.message}")
        if entry is not None and entry.transitions:
            names = " → ".join(table.label(s) for s in entry.states)
            print(f"    entry: entered from rest by {names} (joining at the gait's state {entry.gait_step + 1})")
    if errors:
        # a gait the hardware cannot run is a bad gait, like one the matrix forbids: exit 2
        # (one line: the text above lists every problem, the JSON carries them in "problems")
        kinds = ", ".join(dict.fromkeys(p.kind for p in errors))
        why = f"{len(errors)} errors ({kinds})" if len(errors) > 1 else errors[0].message
        if not args.json and len(errors) > 1:
            why += ", listed above"
        print(f"proleg: error: --evaluate: {walk} cannot run on {robot.name}'s hardware: {why}", file=sys.stderr)
        return 2
    return 0
