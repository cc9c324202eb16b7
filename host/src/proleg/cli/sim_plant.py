"""``proleg sim``'s plant options: ``--plant``, ``--condition``, ``--calibrated``, ``--measure-matrix``
(``--hold-range``), ``--measure-climb``.

Kept apart from the rest of the sim subcommand (``cli/sim_command.py``) so that other options can be
added there without touching these. The keys ``--condition`` takes are the physical keys of
the robot file's ``[plant]`` schema (``proleg.robot_plant.PLANT_KEYS``, docs/robot-file.md);
the values given here go on top of the robot file's.
"""

from __future__ import annotations

import argparse
import json
import logging
import os
import sys
import time
from pathlib import Path
from typing import Any

from ..errors import UsageError
from ..names import counted
from .number_args import positive_int, worker_jobs

PLANT_CHOICES = ("physical", "table")


def add_plant_options(s: argparse.ArgumentParser) -> None:
    s.add_argument("--plant", choices=PLANT_CHOICES, default="physical",
                   help="the simulated body: 'physical' (default; displacement from friction mechanics) or "
                        "'table' (the robot's reward matrix as a lookup, e.g. to test learning)")
    s.add_argument("--condition", action="append", default=[], metavar="KEY=VALUE",
                   help="a physical-plant condition, repeatable (each key, or key and NAME, once), on top of the robot file's [plant] "
                        "(e.g. power=0.8, ambient_c=30, imu_bias_deg=front:3, incline_deg=5); "
                        "--condition help lists every key with its unit and range")
    s.add_argument("--calibrated", action="store_true",
                   help="start as a user does (docs/calibration.md): the board calibrated at rest on flat ground "
                        "first (proleg calibrate), then the robot put on the condition's ground (incline_deg) "
                        "for 2.5 s at rest, then START; the firmware levels itself there, and a robot file's "
                        "[control] max_climb_deg refuses too steep a climb (without it the board was never "
                        "calibrated: it cannot tell a slope from the IMUs' mounting tilt)")
    s.add_argument("--measure-climb", action="store_true",
                   help="measure the steepest grade gait 0 of each direction climbs on the physical plant "
                        "(idealised drive, within the safety envelope) and suggest [control] max_climb_deg; "
                        "--climb-gaits N / --all-gaits: more of each direction's built-in gaits, each its own "
                        "limit where they differ")
    s.add_argument("--all-gaits", action="store_true",
                   help="with --measure-climb: every gait the firmware carries, not gait 0 alone (minutes for robots "
                        "with tens of tied gaits)")
    s.add_argument("--climb-gaits", type=positive_int, metavar="N", default=None,
                   help="with --measure-climb: the first N gaits of each direction (in the firmware's order, "
                        "as proleg build lists them); the gaits past them take the smallest limit")
    s.add_argument("--measure-matrix", action="store_true",
                   help="measure the robot's transition reward matrix (mm) on the physical plant and print it")
    s.add_argument("--out", metavar="FILE.toml",
                   help="with --measure-matrix: also write the robot file with the measured matrix (mm) as its "
                        "[transitions], the old table kept below in comments (as proleg learn --out writes a "
                        "learned one): the file to build and walk a robot whose matrix is unmeasured")
    s.add_argument("--hold-range", action="store_true",
                   help="with --measure-matrix: measure it again holding raised limbs 2° and 8° past psi* (the "
                        "matrix is measured at 4°) and print each entry's range: how much it depends on the hold "
                        "(three measurements, so three times as long; --jobs measures them at once)")
    s.add_argument("--history-range", action="store_true",
                   help="with --measure-matrix: measure it again with its transitions made in reverse and in a "
                        "random order (each starts where the one before left the body) and print each entry's "
                        "range: how much it depends on what came before it (three measurements; --jobs measures "
                        "them at once)")
    s.add_argument("--jobs", type=worker_jobs, default=None, metavar="N",
                   help="with --measure-matrix --hold-range or --history-range: its three measurements at once, "
                        "in up to N worker processes (default: the machine's cores); the numbers do not depend on "
                        "N. One matrix is one chain of transitions on one body, each starting where the last "
                        "ended, so it is measured in one process")


def plant_kwargs(args: argparse.Namespace) -> dict[str, Any]:
    """``SimulatedRobot`` keyword arguments for the chosen plant and conditions."""
    return {"plant": args.plant, "conditions": list(args.condition)}


def conditions_json(robot: Any, args: argparse.Namespace, *, leave_out: tuple[str, ...] = ()) -> dict:
    """What a ``--json`` report says of its plant's conditions: ``plant``, ``conditions`` (the
    ``--condition`` strings as given) and ``effective_conditions`` (the robot file's ``[plant]``
    physical keys with those on top, as ``key=value`` strings ``--condition`` takes; keys at
    their defaults and ``leave_out`` are not listed; none on the table plant, which takes no
    conditions)."""
    from ..sim.closed_loop import condition_strings, plant_conditions

    effective = [] if args.plant != "physical" else [
        c for c in condition_strings(plant_conditions(robot, args.condition)) if c.partition("=")[0] not in leave_out]
    return {"plant": args.plant, "conditions": list(args.condition), "effective_conditions": effective}


def flat_conditions(args: argparse.Namespace) -> list[str]:
    """``--condition`` on flat ground: without incline_deg, and level over the robot file's
    [plant] (the ground a ``--calibrated`` board is calibrated on). The table plant takes no
    conditions (and has no slope): as given."""
    if args.plant != "physical":
        return list(args.condition)
    return [c for c in args.condition if c.partition("=")[0].strip() != "incline_deg"] + ["incline_deg=0"]


def calibrate_then_put_down(session: Any, sim: Any, robot: Any, args: argparse.Namespace) -> None:
    """``--calibrated``: the flat calibration (the board at rest on flat ground), then the robot
    on the condition's ground, at rest for ``claim.REST_ON_GROUND_S`` (the firmware levels on a
    ground it has rested on for 2 s). A refused calibration is a SimError saying why, in words
    (it printed the ``LevelOutcome``'s repr)."""
    from ..errors import SimError
    from ..link.level import calibrate_level
    from ..report.claim import REST_ON_GROUND_S
    from ..sim.closed_loop import make_plant

    outcome = calibrate_level(session.client)
    if not outcome.ok:
        raise SimError(f"--calibrated: the flat calibration was refused: "
                       f"{outcome.refusal_text([lb.name for lb in robot.limbs])}; it is made on flat ground under every "
                       f"other condition (imu_offset_deg, imu_bias_deg, a hot ambient_c tilt a limb there too)")
    sim.plant = make_plant(robot, args.plant, list(args.condition), seed=args.seed)
    session.advance(REST_ON_GROUND_S)


def wants_help(args: argparse.Namespace) -> bool:
    if "help" in args.condition:
        from ..sim.physical import describe_keys

        print(describe_keys())
        return True
    return False


def cmd_measure_matrix(args: argparse.Namespace, robot: Any) -> int:
    """``proleg sim ROBOT --measure-matrix [--json]``."""
    from ..errors import SimError
    from ..sim.closed_loop import plant_conditions
    from ..sim.physical import measure_matrix

    if args.plant != "physical":
        raise SimError("--measure-matrix: the matrix is measured on the physical plant (the table plant is the matrix)")
    if robot.transitions.n_transitions == 0:  # as learn says: it printed a table of dashes and wrote an all-"x" file, exit 0
        raise SimError(f"--measure-matrix: {robot.path}: the robot file allows no transition (its table forbids "
                       "every one): nothing to measure")
    if args.out is not None:  # known now, not after minutes of measuring
        from ..outputs import check_writable, refuse_inputs

        directory = Path(args.out).parent
        if not directory.is_dir():
            raise UsageError(f"--out {args.out}: directory {directory} does not exist")
        refuse_inputs("sim --measure-matrix", "--out", args.out, {"ROBOT": robot.path})
        check_writable(args.out, "sim --measure-matrix")
    conditions = plant_conditions(robot, args.condition)
    rng = None
    steps = _Steps()
    try:
        if args.hold_range:
            from dataclasses import replace

            from ..sim.physical.measure import MARGIN_DEG, hottest, measure_matrix_range

            rng = measure_matrix_range(robot, conditions=conditions, seed=args.seed, on_step=steps,
                                       jobs=args.jobs or os.cpu_count() or 1)
            # the 4° matrix, with the coils' hottest over every margin measured (pooled() keeps it so)
            m = replace(rng.at(MARGIN_DEG), coil_peak_c=hottest(rng.measured))
        elif args.history_range:
            from ..sim.physical.measure import measure_history_range, pooled

            rng = measure_history_range(robot, conditions=conditions, seed=args.seed, on_step=steps,
                                        jobs=args.jobs or os.cpu_count() or 1)
            m = pooled(rng.measured)  # every order's samples: the mean over histories, their spread in std
        else:
            m = measure_matrix(robot, conditions, seed=args.seed, on_step=steps)
    except KeyboardInterrupt:
        from ..errors import Interrupted

        margins = 3 if args.hold_range or args.history_range else 1
        raise Interrupted(steps.interrupted(robot.transitions.n_transitions, margins)) from None
    # allowed by the robot file, but the idealised drive did not make them on this body
    _, allowed = robot.transitions.dense()
    not_made = [(a, b) for a in range(len(m.states)) for b in range(len(m.states))
                if a != b and allowed[a][b] and not m.samples[a][b]]
    # none made: a measurement of nothing (R1 at ambient_c=100, its coils past Af before any heat) is a
    # failure, not a matrix; its --out was the robot file with every entry "kept" (an unmeasured
    # file's zeros, written as a measured table of zeros), and the command said so with exit 0
    nothing = bool(not_made) and len(not_made) == robot.transitions.n_transitions
    # whether the load warnings foresaw the transitions not made: the failure and the table both say
    warned = bool(not_made) and _load_warned(robot, not_made)
    # every one not made ended in a fault the envelope latched: that is why, whatever the load
    # warnings foresaw (tri-mixed at power=0.3 latched all 40, and the error pointed to its
    # warnings of one state the body cannot hold)
    all_latched = bool(not_made) and all(k in m.latched for k in not_made)
    failure = None
    if nothing:
        why = ("the safety envelope latched a fault on the way to each: " + _latched_text(m) if all_latched else
               "the load warnings above say which states the body cannot hold" if warned else
               "the warnings above, if any, say why")
        failure = (f"--measure-matrix: the idealised drive made none of the {robot.transitions.n_transitions} "
                   f"allowed transitions on the simulated body under these conditions ({why}): nothing was measured"
                   + (f"; --out {args.out} not written" if args.out is not None else ""))
    # a coil past the temperature that wears NiTi out while measuring (R1 at supply_v=60: 145 °C)
    # was said nowhere; a run of the firmware fails on it (proleg sim)
    if cooked := _cooked(m.coil_peak_c):
        log.warning("warning: --measure-matrix: %s", cooked)
    if args.out is not None and failure is None:  # written before the table is printed: a reader that goes away (| head) loses no file
        from ..learn.robotfile import write_measured_robot

        if args.condition:  # the robot file's own [plant] describes the robot; --condition is a day's weather
            log.warning("warning: --out: the matrix was measured under --condition %s, and %s holds it as the "
                        "robot's matrix", " ".join(flat_conditions(args)), args.out)
        log.info("wrote %s", write_measured_robot(robot, m, args.out))
    if args.json:
        extra = {} if rng is None else rng.to_json()
        print(json.dumps({"robot": robot.name, **conditions_json(robot, args), **m.to_json(),
                          "not_made": [f"{m.states[a]}->{m.states[b]}" for a, b in not_made], **extra}))
        return _measured(failure)
    pooled_over = f", pooled over {len(rng.orders)} orders" if args.history_range else ""
    print(f"{robot.name}: reward matrix measured on the physical plant (mm, row = from{pooled_over}; "
          f"mechanisms {'/'.join(m.mechanisms)}, {m.mechanism_source})")
    cells = [[None if x != x else _mm(x) for x in row] for row in m.matrix_mm]
    for a, b in not_made:
        cells[a][b] = "?"
    _table(m.states, cells)
    print(f"samples per entry: {int(m.samples.max()) if m.samples.size else 0} ('-': not an allowed transition)")
    if m.coil_peak_c:  # as proleg sim's summary says it; past 120 °C a warning said why above
        from ..physics.materials import shown_c

        print("coils, hottest while measuring: " + ", ".join(f"{name} {shown_c(t)} °C" for name, t in m.coil_peak_c.items()))
    if not_made:
        shown = ", ".join(f"{m.states[a]}->{m.states[b]}" for a, b in not_made[:6])
        more = f", … ({len(not_made) - 6} more)" if len(not_made) > 6 else ""
        # "see the warnings" pointed at nothing when the load checks passed every one of them
        # (their body model poses each state still, the plant's held coils overshoot)
        why = ("the safety envelope latched a fault on its way: below" if all_latched else
               "see the warnings when the robot file was loaded" if warned else
               "no warning when the robot file was loaded foresaw it: the load checks pose each state at rest "
               "with its raised limbs at their hold edge, and a held coil may overshoot it; proleg sim "
               f"{args.robot} --record run.csv shows each limb's ψ")
        print(f"'?': allowed, but not made on the simulated body ({len(not_made)} of "
              f"{robot.transitions.n_transitions}: {shown}{more}): its start or end state was not reached ({why})")
        if m.latched:  # the measuring drive keeps to the firmware's envelope: where it gave up, the firmware would stop
            print("the safety envelope latched a fault on the way (the firmware, keeping to it, would stop there "
                  "too; docs/safety.md): " + _latched_text(m))
    if rng is not None:
        over = (f"hold margins {'/'.join(f'{x:g}' for x in rng.margins_deg)}° past psi*" if args.hold_range else
                f"the orders the transitions were made in, {'/'.join(rng.orders)} (what came before each)")
        print(f"\neach entry's range over {over} (mm, low..high):")
        _table(m.states, [[None if lo != lo else f"{_mm(lo)}..{_mm(hi)}" for lo, hi in zip(rl, rh)]
                          for rl, rh in zip(rng.low_mm, rng.high_mm)])
    return _measured(failure)


def _latched_text(m: Any) -> str:
    """``MeasuredMatrix.latched`` in a line: each fault with the transitions it stopped."""
    by_code: dict[str, list[str]] = {}
    for (a, b), code in sorted(m.latched.items()):
        by_code.setdefault(code, []).append(f"{m.states[a]}->{m.states[b]}")
    return "; ".join(f"{code} on {', '.join(steps[:6])}{f', … ({len(steps) - 6} more)' if len(steps) > 6 else ''}"
                     for code, steps in by_code.items())


def _cooked(peaks: dict[str, float]) -> str:
    """The coils past ``NITI_OVERHEAT_C`` while measuring, said in a line ("" when none)."""
    from ..physics.materials import NITI_OVERHEAT_C, shown_c

    hot = [f"coil {name} reached {shown_c(t)} °C" for name, t in peaks.items() if t > NITI_OVERHEAT_C]
    return (f"{', '.join(hot)} while measuring, past the {NITI_OVERHEAT_C:.0f} °C that wears NiTi out. The "
            "idealised drive that measures is not the firmware: within the safety envelope, it heats at the drive "
            "duty until a step is made and held (up to 12 s), without the firmware's rules that stop heating a coil "
            "through its transformation; proleg sim ROBOT runs the firmware, and fails a run that heats a coil past "
            f"{NITI_OVERHEAT_C:.0f} °C") if hot else ""


def _load_warned(robot: Any, steps: list[tuple[int, int]]) -> bool:
    """Whether a load warning named one of ``steps`` (a state the body cannot hold, a step it
    cannot end), either way."""
    from ..robot_body import warned_step

    return any(warned_step(robot, a, b) or warned_step(robot, b, a) for a, b in steps)


def _measured(failure: str | None) -> int:
    """``--measure-matrix``'s exit code: 1 with ``failure`` said on stderr (nothing was measured), else 0."""
    if failure is None:
        return 0
    print(f"proleg: error: {failure}", file=sys.stderr)
    return 1


def _mm(x: float) -> str:
    """A matrix entry in mm, signed, two decimals; one that rounds to zero is +0.00 (a tiny
    negative printed "-0.00", a sign the entry does not have)."""
    return f"{x:+.2f}" if round(x, 2) != 0 else "+0.00"


log = logging.getLogger("proleg")

#: ``--measure-matrix`` says how far it has got at most this often (a 96-state robot takes
#: minutes: without a word a lab cannot tell it from a hang).
PROGRESS_EVERY_S = 10.0


class _Steps:
    """``measure_matrix``'s ``on_step``: how far the measurement got, said on stderr every
    ``PROGRESS_EVERY_S`` (with the time left) and in a Ctrl-C's line."""

    def __init__(self) -> None:
        self.tried = self.sampled = self.total = 0
        self.started = self.said = time.monotonic()

    def __call__(self, tried: int, sampled: int, total: int) -> None:
        self.tried, self.sampled, self.total = tried, sampled, total
        now = time.monotonic()
        if tried < total and now - self.said >= PROGRESS_EVERY_S:
            self.said = now
            left = (now - self.started) / tried * (total - tried)
            # trials: each allowed transition is measured several times (and at each hold margin)
            log.info("measure-matrix: %d/%s, about %d:%02d left", tried, counted(total, "trial"), left // 60, left % 60)

    def interrupted(self, allowed: int, margins: int) -> str:
        """The one line a Ctrl-C'd ``--measure-matrix`` ends with: how many trials were
        made, and that nothing was printed (the matrix comes out whole or not at all)."""
        nothing = "nothing printed: the matrix (text or --json) is printed only once every transition is measured"
        if not self.tried:
            return f"interrupted before the first transition was measured; {nothing}"
        each = self.total // max(1, allowed * margins)
        how = (f"{counted(allowed, 'allowed transition')}, {counted(each, 'time')} each"
               + (f" at each of {margins} hold margins" if margins > 1 else ""))
        return (f"interrupted after {self.tried} of {counted(self.total, 'trial')} ({how}; {self.sampled} "
                f"reached their target); {nothing}")


#: ``proleg sim`` options as given (not left at their defaults): name → test on the arguments.
_GIVEN = {
    "--gait": lambda a: a.gait != 0,
    "--direction": lambda a: a.direction != "+x",
    "--inject": lambda a: bool(a.inject),
    "--record": lambda a: a.record is not None,
    "--udp": lambda a: a.udp is not None,
    "--duration": lambda a: a.duration is not None,
    "--speed": lambda a: a.speed != 1.0,
    "--json": lambda a: a.json,
    "--board": lambda a: a.board != "host-sim",
}
#: What each mode does not use (besides the refusals each makes itself).
_UNUSED = {
    "--measure-matrix": ("--gait", "--direction", "--inject", "--record", "--udp", "--duration", "--speed",
                         "--board"),
    "--measure-climb": ("--gait", "--direction", "--inject", "--record", "--udp", "--duration", "--speed"),
    "--pty": ("--json", "--record", "--udp"),
}


def refuse_what_does_not_apply(args: argparse.Namespace) -> None:
    """SimError naming an option the chosen mode of ``proleg sim`` would silently ignore
    (``--measure-matrix --record FILE`` wrote no file; ``--speed`` without ``--pty``)."""
    from ..errors import SimError

    mode = ("--measure-matrix" if args.measure_matrix else "--measure-climb" if args.measure_climb
            else "--pty" if args.pty else None)
    for flag in _UNUSED.get(mode, ()):
        if _GIVEN[flag](args):
            raise SimError(f"{mode}: not with {flag} (it does not use it)")
    if mode != "--pty" and _GIVEN["--speed"](args):
        raise SimError("--speed: only with --pty (a plain sim runs as fast as it can)")
    if args.jobs is not None and not (mode == "--measure-matrix" and (args.hold_range or args.history_range)):
        raise SimError("--jobs: only with --measure-matrix --hold-range or --history-range (their measurements are "
                       "made at once; one matrix is one chain of transitions on one body, each starting where the "
                       "last ended, so it is measured in one process)")
    if args.hold_range and args.history_range:
        raise SimError("--hold-range and --history-range: one range at a time (each measures the matrix three times)")
    if mode != "--measure-matrix" and getattr(args, "out", None) is not None:
        raise SimError("--out: only with --measure-matrix (the robot file it writes holds the measured matrix)")
    if mode != "--measure-climb" and (args.all_gaits or args.climb_gaits is not None):
        raise SimError("--all-gaits / --climb-gaits: only with --measure-climb (which gaits it measures)")


def cmd_measure_climb(args: argparse.Namespace, robot: Any) -> int:
    """``proleg sim ROBOT --measure-climb [--all-gaits] [--json]``: the steepest grade gait 0 of
    each direction (or every built-in gait) climbs, and the ``max_climb_deg`` that suggests (per
    direction; with --all-gaits one per gait where they differ). A number holds every gait of a
    direction to it, so tie gaits that climb less are worth measuring (docs/calibration.md)."""
    from ..errors import SimError
    from ..firmware.build import firmware_gaits
    from ..robot_climb import climb_guard_refusal
    from ..sim.physical.climb import (
        BARELY_MOVES,
        RESOLUTION_DEG,
        TOP_DEG,
        steepest_climb,
        suggested_limits,
    )

    if args.plant != "physical":
        raise SimError("--measure-climb: grades are climbed on the physical plant (the table plant has no slope)")
    for flag, given in (("--calibrated", args.calibrated), ("--measure-matrix", args.measure_matrix),
                        ("--hold-range", args.hold_range), ("--history-range", args.history_range), ("--pty", args.pty),
                        ("--board", args.board != "host-sim")):
        if given:
            raise SimError(f"--measure-climb: not with {flag} (an idealised drive on the plant climbs, no board)")
    if any(c.partition("=")[0].strip() == "incline_deg" for c in args.condition):
        raise SimError("--measure-climb: it sets the incline itself; leave incline_deg out of --condition")
    if why := climb_guard_refusal(len(robot.limbs), robot.library):
        raise SimError(f"--measure-climb: {robot.name} cannot carry [control] max_climb_deg: {why}")
    if args.all_gaits and args.climb_gaits is not None:
        raise SimError("--measure-climb: --all-gaits or --climb-gaits N, not both")
    every = firmware_gaits(robot, args.objective, args.max_transitions)
    first = None if args.all_gaits else (args.climb_gaits or 1)
    gaits = {d: list(every.get(d, ()))[:first] for d in ("+x", "-x")}
    if not any(gaits.values()):  # nothing measured: it said "no gait moves" with exit 0, as if measured so
        why = every.left_out_line("+x") or f"{robot.name} has no gait in +x or -x"
        raise SimError(f"--measure-climb: {robot.path}: the firmware carries no gait to climb with: {why}")
    climbs: dict[str, list[float | None]] = {
        d: [steepest_climb(robot, g.states, d, list(args.condition)) for g in gs] for d, gs in gaits.items() if gs}
    limit = suggested_limits(climbs)
    have = robot.control.max_climb_deg
    if args.json:
        print(json.dumps({"robot": robot.name, **conditions_json(robot, args, leave_out=("incline_deg",)),
                          "resolution_deg": RESOLUTION_DEG,
                          "climb_deg": climbs, "suggested_max_climb_deg": None if limit is None else limit.to_json(),
                          "max_climb_deg": None if have is None else have.to_json()}))
        return 0
    which = ("every built-in gait" if first is None else
             "gait 0 of each direction (--climb-gaits N: the first N; --all-gaits: every one)" if first == 1 else
             f"the first {first} gaits of each direction")
    print(f"{robot.name}: the steepest grade climbed by {which} on the physical plant (idealised drive within the "
          f"safety envelope, {RESOLUTION_DEG:g}° steps up to {TOP_DEG:g}°; climbed: at least {BARELY_MOVES:.0%} of the "
          "flat's speed up the slope)")
    for direction, per in climbs.items():
        for i, climb in enumerate(per):
            text = ("does not move that way even on the flat (not counted)" if climb is None
                    else f"{climb:g}° or more" if climb >= TOP_DEG else f"{climb:g}° (not {climb + RESOLUTION_DEG:g}°)")
            print(f"  {direction} gait {i}: {text}")
    if limit is None:
        print("no gait moves: no max_climb_deg to suggest")
        return 0
    floor = " (the smallest the firmware takes: a gait barely climbs at all)" if any(
        c is not None and c < limit.toward(d, i if limit.gaits_toward(d) else None)
        for d, per in climbs.items() for i, c in enumerate(per)) else ""
    print(f"suggested: [control] max_climb_deg = {limit}{floor}   (the robot file: "
          f"{'none' if have is None else have}; a list gives each gait of that way its own limit, "
          "a number holds them all to it)")
    if any(len(every.get(d, ())) > len(gaits[d]) for d in ("+x", "-x")):
        print("note: the firmware carries other gaits too; they take the smallest limit of their direction, and "
              "they may climb less (--all-gaits measures each)")
    return 0


def _table(states: list[str], cells: list[list[str | None]]) -> None:
    """Rows and columns named by state; '.' on the diagonal, '-' where there is no value."""
    width = max(6, *(len(s) for s in states), *(len(c) for row in cells for c in row if c))
    print(" " * width + "".join(f"{s:>{width + 3}}" for s in states))
    for a, row in enumerate(cells):
        text = ["." if a == b else c or "-" for b, c in enumerate(row)]
        print(f"{states[a]:<{width}}" + "".join(f"{t:>{width + 3}}" for t in text))
