"""``proleg learn``: measure a robot's transition matrix on the robot (docs/learning.md).

Three things, in this order, each optional after the first:

1. **explore** (when a link is given: ``--port``, ``--can`` or ``--sim``): drive the robot
   through randomised Euler tours until every allowed transition has ``--repeats`` trials
   in ``--log`` (``--adaptive``: the same budget, spent where the intervals are widest;
   ``--more`` with ``--half-width``: the fewest extra trials that reach that half-width).
   The log is append-only: run the same command again to resume;
2. **report** (``--report``, or always after exploring): per transition n, mean and 95 %
   interval of Δx (Δy, Δθ when measured), flagged transitions, extra trials for
   ``--half-width``;
3. **write** (``--out``): the learned robot file.

Position sources (``--source``): ``sim`` (the simulator's ground truth; the default with
``--sim``), ``tracker`` (no pose during the run; ``--track FILE.csv`` gives the motion,
clocks aligned by ``proleg.learn.tracker``), ``manual`` (asked after each transition).

This module parses the command, checks its options, opens the log and the link and explores;
the report and the learned file (2 and 3) are ``learn_report``'s.
"""

from __future__ import annotations

import argparse
import logging
import os
import sys
import warnings
from pathlib import Path
from typing import Any, TextIO

import numpy as np

from ..errors import LearnError, LinkError
from ..paths import not_a_regular_file
from ..names import counted
from .learn_report import FLAGGED_SHOWN, _fmt, report_and_write, with_track  # noqa: F401 (first two re-exported)
from .learn_scope import check_explorable, explored, faulted_hint, stopped_hint

log = logging.getLogger("proleg")


def add_arguments(subparsers: Any) -> None:
    from .main import robot_arg
    from .number_args import positive_float, positive_int, repeats, tracker_offset
    from .gait import _penalty
    from .robot_link import add_link_options

    p = subparsers.add_parser(
        "learn", help="measure the robot's transition matrix (explore, report, write a learned robot file)",
        description="Explore the robot's allowed transitions (randomised Euler tours, resumable from --log), "
                    "estimate each transition's motion with confidence intervals, and write a learned robot file.")
    p.add_argument("robot", metavar="ROBOT", type=robot_arg)
    add_link_options(p, sim_takes_robot=False, required=False,  # --report and --out need no robot
                     sim_help="ROBOT's firmware on the simulated board, in closed loop with the physical plant "
                              "(or --plant)")
    p.add_argument("--truth", metavar="TRUTH.toml", type=robot_arg,
                   help="with --sim: a robot file whose [transitions] matrix drives the plant, hidden from the learner")
    p.add_argument("--plant", choices=("table", "physical"), default=None,
                   help="with --sim: the physical plant (friction mechanics: learn what the simulated body "
                        "really does; the default) or the table plant (a matrix moves it: --truth's, the default "
                        "with --truth, or ROBOT's own, to test learning against a known matrix)")
    p.add_argument("--log", required=True, metavar="TRIALS.jsonl",
                   help="append-only trial log; an existing one is resumed, nothing recorded is lost")
    p.add_argument("--repeats", type=repeats, default=5, metavar="R",
                   help="trials per transition (default 5, at most 100,000)")
    p.add_argument("--source", choices=("sim", "tracker", "manual"),
                   help="position source (default: sim with --sim; required otherwise)")
    p.add_argument("--track", metavar="FILE.csv", help="tracker CSV (time,x,y,theta) for trials without motion")
    p.add_argument("--tracker-offset", type=tracker_offset, metavar="S",
                   help="tracker time − firmware time from a sync event (default: estimated)")
    p.add_argument("--adaptive", action="store_true",
                   help="spend the R × transitions budget where the intervals are widest (2 trials each first)")
    p.add_argument("--half-width", type=positive_float, metavar="H",
                   help="report the extra trials each transition needs for a 95 %% interval of ± H")
    p.add_argument("--more", action="store_true", help="with --half-width and a link: run those extra trials")
    p.add_argument("--report", action="store_true", help="print the estimates (always printed after exploring)")
    p.add_argument("--out", metavar="LEARNED.toml", help="write the robot file with the learned [transitions]")
    # bounded as proleg gait's (1e308 overflowed the gait search's sums: RuntimeWarnings)
    p.add_argument("--variance-weight", type=_penalty, default=0.0, metavar="λ",
                   help="report the best gait for mean − λ·σ per transition, λ in [0, 1e9] (default 0: the mean)")
    p.add_argument("--seed", type=int, default=1, help="tour randomisation and simulator seed (default 1)")
    p.add_argument("--max-pieces", type=positive_int, metavar="N",
                   help="stop after N pieces (resume later with the same --log)")
    p.add_argument("--try-unholdable", action="store_true",
                   help="also ask for the transitions into or out of states the body model says the robot cannot "
                        "hold, and the steps it says the body cannot end (the load warnings; left out and written "
                        "\"x\" by default): for a robot that holds them after all; a fault on one is recorded and "
                        "learning goes on")
    p.add_argument("--retry-faulted", action="store_true",
                   help="with a robot link: ask again for the transitions the robot faulted on in an earlier run "
                        "of this --log (left out by default)")
    p.set_defaults(run=cmd_learn)


# --------------------------------------------------------------------------- progress
class ProgressBar:
    """``[#####.....] 12/40 transitions, 1:23 left`` on stderr: redrawn in place on a
    terminal, one line per update otherwise."""

    def __init__(self, stream: TextIO | None = None, width: int = 24):
        self.stream = stream or sys.stderr
        self.width = width
        self.tty = bool(getattr(self.stream, "isatty", lambda: False)())
        self.drawn = False

    @staticmethod
    def _clock(seconds: float) -> str:
        s = max(0, int(round(seconds)))
        return f"{s // 3600}:{s // 60 % 60:02d}:{s % 60:02d}" if s >= 3600 else f"{s // 60}:{s % 60:02d}"

    def line(self, done: int, total: int, eta_s: float) -> str:
        total = max(total, 1)
        fill = min(self.width, int(self.width * done / total))
        return (f"[{'#' * fill}{'.' * (self.width - fill)}] {done}/{total} transitions, "
                f"{self._clock(eta_s)} left")

    def update(self, done: int, total: int, eta_s: float) -> None:
        text = self.line(done, total, eta_s)
        if self.tty:
            self.stream.write("\r" + text)
            self.drawn = True
        else:
            self.stream.write(text + "\n")
        self.stream.flush()

    def close(self) -> None:
        if self.drawn:
            self.stream.write("\n")
            self.stream.flush()
            self.drawn = False


# --------------------------------------------------------------------------- the command
def cmd_learn(args: argparse.Namespace) -> int:
    from ..robot import load_robot

    from .robot_link import link_settings

    link_settings(args)  # a --baudrate or --node of a link not chosen is refused, not ignored
    robot = load_robot(args.robot)
    linked = bool(args.port or args.can or args.sim)
    source = _check_options(args, linked)
    truth = _checked_truth(args, robot)  # before the log is created: a bad option leaves no file
    if args.sim and args.plant == "physical" and len(robot.limbs) < 2:  # the plant's own line named `proleg sim`
        raise LearnError(f"learn: {robot.path}: the physical plant needs two limbs at least (a body crawls on two "
                         f"contacts), and {robot.name} has one: learn it on the table plant, which a matrix moves: "
                         "--truth TRUTH.toml (a robot file whose matrix is the truth to learn)")
    if linked:
        check_explorable(robot, args.try_unholdable)
    # and so is the link: a board that does not answer, or runs another robot, leaves no file either
    client, pose = _connect(args, robot, truth, source) if linked else (None, None)
    try:
        trial_log = _open_log(args, robot, linked)
    except BaseException:
        if client is not None:
            client.close()
        raise
    with trial_log:
        if client is not None:
            try:
                _check_resumed_units(args, robot, trial_log.trials, source)
            except BaseException:
                client.close()
                raise
        if trial_log.trials and linked:
            log.info("%s: %s already recorded; resuming", args.log, counted(len(trial_log.trials), "trial"))
        if client is not None:
            _explore(args, robot, trial_log, source, client, pose)
        trials, failures = list(trial_log.trials), list(trial_log.failures)
    trials = with_track(args, trials)
    return report_and_write(args, robot, trials, failures)


def _check_resumed_units(args: argparse.Namespace, robot, trials: list, source: str) -> None:
    """A log resumed with a source whose Δx come in another unit than its trials' (the
    simulator's mm against a hand's or a tracker's, in a robot file counting steps) is refused
    before anything is explored: the report cannot average the two, and the new trials were
    appended first, leaving a log mixed for good (``LearnError``, exit 2)."""
    def unit(src: str | None) -> str:
        return "mm" if src == "sim" else robot.units

    old = next((tr for tr in trials if unit(tr.source) != unit(source)), None)
    if old is None:
        return
    raise LearnError(f"learn: --log {args.log}: its trials are {old.source or 'unsaid'} ones (Δx in "
                     f"{unit(old.source)}), --source {source}'s are in {unit(source)}: one log cannot average "
                     "the two; explore into another --log")


def _check_options(args: argparse.Namespace, linked: bool) -> str | None:
    """The position source; ``LearnError`` for options that do not go together."""
    from ..outputs import check_writable, refuse_inputs

    source = args.source or ("sim" if args.sim else None)
    if linked and source is None:
        raise LearnError("learn: --source is required with --port/--can (tracker or manual; sim needs --sim)")
    if source == "sim" and linked and not args.sim:
        raise LearnError("learn: --source sim needs --sim (the simulator's ground truth)")
    if args.truth and not args.sim:
        raise LearnError("learn: --truth needs --sim")
    if args.plant is not None and not args.sim:
        raise LearnError("learn: --plant needs --sim (it picks the simulated body)")
    # the physical plant learns what the simulated body does; the table plant is moved by a
    # matrix, so it is the default only where one is given to hide from the learner (--truth)
    args.plant = args.plant or ("table" if args.truth else "physical")
    if args.more and (args.half_width is None or not linked):
        raise LearnError("learn: --more needs --half-width and a robot (--port, --can or --sim)")
    if args.track is not None and source not in (None, "tracker"):
        raise LearnError("learn: --track goes with --source tracker")
    if args.tracker_offset is not None and args.track is None:
        raise LearnError("learn: --tracker-offset goes with --track")
    if args.retry_faulted and not linked:
        raise LearnError("learn: --retry-faulted needs a robot (--port, --can or --sim): it asks for transitions "
                         "again")
    if not (linked or args.report or args.out or args.half_width):
        raise LearnError("learn: nothing to do: give a robot link to explore, or --report / --out / --half-width")
    if args.out is not None:
        directory = Path(args.out).parent
        if not directory.is_dir():  # known now, not after hours of exploring
            raise LearnError(f"learn: --out {args.out}: directory {directory} does not exist")
        refuse_inputs("learn", "--out", args.out,
                      {"ROBOT": args.robot, "--log": args.log, "--track": args.track, "--truth": args.truth})
        check_writable(args.out, "learn")
    if linked:
        _check_log_writable(args.log)
    return source


def _check_log_writable(path: str) -> None:
    """The log exploring appends to, checked as every output is before anything is opened or
    created: a folder that does not exist is a usage mistake (``LearnError``, exit 2; it was
    created, parents and all), a place the log cannot be written a ``LinkError`` (exit 1)."""
    p = Path(path)
    for directory in (p.parent, Path(os.path.realpath(p)).parent):  # "." for a bare name; a symlink's target
        if not directory.is_dir():
            raise LearnError(f"learn: --log {path}: directory {directory} does not exist")
    why = ("Is a directory" if p.is_dir() else
           not_a_regular_file(p) or ("Permission denied" if not os.access(p.parent, os.W_OK | os.X_OK)
                                     or (p.exists() and not os.access(p, os.R_OK | os.W_OK)) else ""))
    if why:
        raise LinkError(f"learn: cannot write trial log {path}: {why}")


def _checked_truth(args: argparse.Namespace, robot):
    """``--truth``'s robot (None without it), checked against ``--plant`` and ROBOT's levels."""
    if not args.sim:
        return None
    from ..learn.runner import ExplorationError
    from ..learn.simulated import check_plant
    from ..robot import load_robot

    truth = load_robot(args.truth) if args.truth else None
    if truth is None and args.plant == "table" and getattr(robot, "n_trials", None) is not None:
        # a learned file (it carries n_trials): the table plant hands its own means back
        log.warning("warning: learn: %s was learned (it has n_trials), and the table plant moves by its matrix: "
                    "these trials give back the file's own means, not the robot's motion; the physical plant "
                    "(the default) learns the simulated body again, and more trials of the robot go into the "
                    "first run's --log (docs/learning.md)", robot.path)
    try:
        check_plant(robot, truth, args.plant)
    except ExplorationError as e:
        raise LearnError(f"learn: {e}") from None
    return truth


def _open_log(args: argparse.Namespace, robot, linked: bool):
    """The trial log: read (a report) or opened to append (exploring)."""
    from ..learn.measure import TrialLog, TrialLogError

    try:
        with warnings.catch_warnings(record=True) as torn:
            warnings.simplefilter("always")
            if not linked and not Path(args.log).exists():
                raise LearnError(f"learn: {args.log}: no such trial log (a report reads one; give a robot link "
                                 "(--port, --can or --sim) to record one)")
            t = robot.transitions
            trial_log = TrialLog(args.log, append=linked, robot=robot.name,  # a report only reads
                                 states=t.labels(), transitions=zip(map(t.label, t.src), map(t.label, t.dst)),
                                 levels=[lb.levels for lb in robot.limbs])
    except TrialLogError as e:
        raise LearnError(f"learn: {e}") from None
    except OSError as e:  # exploring writes the log (exit 1, as any output); a report only reads it (exit 2)
        if linked:
            raise LinkError(f"learn: cannot write trial log {args.log}: {e.strerror or e}") from None
        raise LearnError(f"learn: cannot read trial log {args.log}: {e.strerror or e}") from None
    for w in torn:
        log.warning("%s", w.message)
    return trial_log


def _connect(args: argparse.Namespace, robot, truth, source: str):
    """The connected robot to explore (the simulator with --sim) and, with ``--source sim``,
    its ground-truth pose: (client, pose or None)."""
    from ..learn.runner import ExplorationError
    from ..learn.simulated import simulated_robot
    from .robot_link import open_client

    if not args.sim:
        return open_client(args, args.robot, robot=robot), None
    try:
        _sim, client, sim_pose = simulated_robot(robot, truth, seed=args.seed, plant=args.plant)
    except ExplorationError as e:
        raise LearnError(f"learn: {e}") from None
    client.connect()
    return client, sim_pose if source == "sim" else None


def _explore(args: argparse.Namespace, robot, trial_log, source: str, client, pose) -> None:
    from ..learn.estimate import estimate
    from ..learn.plan import adaptive_demand, extra_plan
    from ..learn.runner import ExplorationError, Explorer, Progress

    if source == "tracker" and args.track is None:
        log.warning("learn: --source tracker: the trials recorded now have no motion (Δx) until the tracker's "
                    "track is attached: give --track FILE.csv (time,x,y,theta) now, or later with --report "
                    "and the same --log")
    bar = ProgressBar() if log.isEnabledFor(logging.INFO) else None

    def progress(p: Progress) -> None:
        if bar is not None:
            bar.update(p.done, p.done + p.to_do, p.eta_s)

    ask = None
    if source == "manual":
        def ask(prompt: str) -> str:
            if bar is not None:
                bar.close()
            sys.stderr.write(prompt)
            sys.stderr.flush()
            line = sys.stdin.readline()
            if not line:
                raise LearnError("learn: no more input (stdin closed); the trials so far are in the log")
            return line

    with client:
        ex = Explorer(client, robot, trial_log, pose, repeats=args.repeats, source=source, seed=args.seed,
                      on_progress=progress, ask=ask, try_unholdable=args.try_unholdable,
                      retry_faulted=args.retry_faulted)
        t = ex.robot.transitions  # the transitions the hardware can make: goals and plans are aligned with them
        done, todo = ex.tally()
        lim = ex.limits
        log.info("learn: exploring %s on %s: %s = %s, %d to do; pieces of up to %s, %.1f s rest "
                 "after each; Ctrl-C pauses (nothing recorded is lost: run the same command to go on)",
                 robot.name, client.link.description, explored(robot, ex.left_out, args.repeats), counted(done + todo, "trial"), todo,
                 counted(lim.max_transitions, "transition"), lim.rest_s)
        try:
            if args.adaptive:
                _adaptive(ex, args, t, trial_log, estimate, adaptive_demand)
            elif args.more:
                # the R trials of each transition first: the extra trials are planned from their
                # variances (on a fresh log the plan was "2 of each", --more ran no extra trial and
                # the report then asked for hundreds "with --more and a robot link")
                ex.run(max_pieces=args.max_pieces)
                if ex.tally()[1] == 0:
                    need, _plan = extra_plan(estimate(t, trial_log.trials), args.half_width, seed=args.seed)
                    _run_to(ex, need + _counts(t, trial_log.trials), args.max_pieces)
            else:
                ex.run(max_pieces=args.max_pieces)
        except ExplorationError as e:
            again = "" if args.sim and getattr(e, "fault", False) else "; run the same command to resume"
            raise LinkError(f"learn: {e}{stopped_hint(args, e)} ({args.log} keeps the {_recorded(trial_log)}{again})") from None
        except LinkError as e:  # a cable pulled, a board that stopped answering: said alone, it hid the log
            raise LinkError(f"learn: {e} ({args.log} keeps the {_recorded(trial_log)}; run the "
                            "same command to resume)") from None
        except OSError as e:  # the log's disk filled: "cannot write: No space left on device", no file named
            raise LinkError(f"learn: cannot write trial log {args.log}: {e.strerror or e} (it keeps "
                            f"the {_recorded(trial_log)} before, whole; the robot was "
                            "stopped; make room and run the same command to resume)") from None
        except KeyboardInterrupt:
            if bar is not None:
                bar.close()
            from ..link.leave import stop_robot

            what = stop_robot(client)  # run_piece stops it too; a Ctrl-C may have cut that short
            done, todo = ex.tally()
            from ..errors import Interrupted
            from .main import interruption

            raise Interrupted(f"learn: paused by {interruption()} ({what}): {counted(len(trial_log.trials), 'trial')} kept in {args.log}, "
                              f"{done} of {done + todo} done; run the same command to go on") from None
        finally:
            if bar is not None:
                bar.close()
        done, todo = ex.tally()
        failed = [(t.label(int(t.src[e])), t.label(int(t.dst[e]))) for e in sorted(ex.failed)]
        faulted = (f"; the robot faulted making {counted(len(failed), 'transition')} "
                   f"({', '.join(f'{a}->{b}' for a, b in failed)}), recorded as not made, not asked for "
                   f"again{faulted_hint(args, robot, failed)}") if failed else ""
        if ex.left_for_tracker:  # manual entry's normal end: the rest cannot be measured by eye
            log.warning("learn: manual entry is done: %s in %s%s; %s start where the robot does not rest (it "
                        "passes through on its way): record them with --source tracker into the same --log (a "
                        "camera's track gives each transition of a piece its motion)",
                        counted(len(trial_log.trials), "trial"), args.log, faulted,
                        ", ".join(ex.left_for_tracker))
        elif todo == 0 or args.max_pieces is None:
            log.info("learn: exploration done: %s in %s%s", counted(len(trial_log.trials), "trial"), args.log, faulted)
        else:
            log.info("learn: stopped after %s (--max-pieces): %d of %d done; run the same command "
                     "to go on", counted(ex.pieces_run, "piece"), done, done + todo)


def _recorded(trial_log) -> str:
    """"3 trials recorded", "1 trial recorded": what the log keeps, for the lines that say so."""
    return f"{counted(len(trial_log.trials), 'trial')} recorded"


def _counts(table, trials) -> np.ndarray:
    from ..learn.measure import counts

    return counts(table, trials)


def _run_to(ex, goal: np.ndarray, max_pieces: int | None) -> None:
    """Run until each transition has ``goal`` trials (or ``max_pieces`` in all)."""
    ex.goal = goal
    ex.run(max_pieces=max_pieces)


def _adaptive(ex, args, table, trial_log, estimate, adaptive_demand) -> None:
    """Two trials of each transition, then one more for the widest quarter of the intervals,
    round after round, until the budget R × transitions is spent (bench/bench_learn.py)."""
    budget = args.repeats * table.n_transitions
    _run_to(ex, np.full(table.n_transitions, min(2, args.repeats), dtype=np.int64), args.max_pieces)
    while len(trial_log.trials) < budget and (args.max_pieces is None or ex.pieces_run < args.max_pieces):
        demand = adaptive_demand(estimate(table, trial_log.trials))
        before = len(trial_log.trials)
        _run_to(ex, _counts(table, trial_log.trials) + demand, args.max_pieces)
        if demand.sum() == 0 or len(trial_log.trials) == before:
            break
