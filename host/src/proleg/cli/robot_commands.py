"""``proleg run``, ``proleg load-gait``, ``proleg set-param`` and ``proleg robots``: scripting
a robot over serial, CAN or the simulated board (``--sim``), headless.

``run`` starts a gait, reports progress on stderr (``-q`` silences it), stops it after
``--duration`` seconds and exits 1 when a command failed or the robot reported a fault.
``--format jsonl`` prints every message as one JSON line (the JSONL recording's field names,
physical units) and a last ``{"msg": "RESULT", ...}`` line.
"""

from __future__ import annotations

import argparse
import json
import logging
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

from .. import interrupts
from ..errors import GaitError, Interrupted, LinkError, UsageError
from ..names import counted
from .number_args import (MAX_SIM_S, gait_index, heading_deg, param_index, param_value, positive_float,
                          progress_period, speed_factor)
from .robot_link import add_link_options, link_settings, open_client

log = logging.getLogger("proleg")


# --------------------------------------------------------------------------- shared
def gaits_per_direction(robot: Any, fw: Any = None) -> dict[str, int]:
    """How many gaits the robot's firmware carries in each direction (``fw``: its
    ``firmware_gaits``, computed when not given)."""
    from ..firmware.build import firmware_gaits

    return {d: len(g) for d, g in (fw if fw is not None else firmware_gaits(robot)).items()}


def heading_choice(args: argparse.Namespace, robot: Any) -> tuple[Any, Any]:
    """(firmware gaits, HeadingChoice or None) for ``run --heading/--rotate`` (issue 17)."""
    from ..firmware.gaits import choose_heading, firmware_gaits
    from ..gait.library import library_spec

    if args.exact_heading and args.heading is None:
        raise GaitError("--exact-heading: only with --heading (it says what to do with a heading the library lacks)")
    if args.heading is None and args.rotate is None:
        if args.library:
            raise GaitError("--library: only with --heading or --rotate (it is the library they choose from)")
        return None, None
    if args.gait is not None or args.direction is not None:
        raise GaitError("--heading/--rotate choose the gait: leave out --gait and --direction")
    spec = None
    if args.library:
        spec = library_spec(args.library, **(robot.library.as_kwargs() if robot.library is not None else {}))
    fw = firmware_gaits(robot, library=spec)
    choice = choose_heading(robot, fw, args.heading, args.rotate, exact=args.exact_heading)
    (log.warning if choice.warned else log.info)(choice.message)
    return fw, choice


def check_library_hash(info: Any, robot: Any, fw: Any, where: str, simulated: bool = False) -> None:
    """A library gait is started by its index: refuse unless the board's gait table is the one
    this robot file and library give (its hash in INFO), else the index may name another gait."""
    from ..firmware.boards import load_board
    from ..firmware.render import render_context

    want = int(render_context(robot, fw, load_board("host-sim")).gait.gait_hash, 16)  # board-independent
    if want == info.gait_hash:
        return
    fix = ("the simulated board is built from the robot file's [gaits] library: put the library there, or leave "
           "out --library" if simulated else "build and flash with the same [gaits] library (or --library)")
    raise LinkError(f"{where}: the board's gait table (hash {info.gait_hash:08x}) is not the one {robot.path} "
                    f"and this gait library give ({want:08x}); {fix}, or run with --exact-heading to compute "
                    f"and load the gait")


# --------------------------------------------------------------------------- run
def cmd_run(args: argparse.Namespace) -> int:
    from ..link.direction import UNSTATED
    from ..protocol.definition import GAIT_USER
    from ..record import JsonlPrinter, Logger, RecordingMeta, UdpStreamer, check_suffix
    from ..report import check_gait, run_gait_on
    from ..report.robot_run import RunInterrupted
    from ..robot import load_robot

    from .main import udp_options

    robot = load_robot(args.robot)
    if args.record:
        check_suffix(args.record)
    args.udp, args.udp_format = udp_options(args)
    link_settings(args)  # before the gait is chosen: an option of another link is refused first
    if args.speed is not None and not args.sim:  # a real board keeps its own time
        raise UsageError("--speed: only with --sim (a simulated board's pace; a real one runs in real time)")
    if args.sim and args.speed is None and args.duration > MAX_SIM_S:
        # flat out, as proleg sim runs (an hour in about a minute): 1e9 ran for ever, no refusal,
        # where sim refuses it; paced by --speed the run lasts what the user asked for in real time
        raise UsageError(f"--duration {args.duration:.12g}: with --sim, expected at most {MAX_SIM_S:g} simulated "
                         "seconds (an hour takes about a minute to simulate; run several shorter runs instead, "
                         "or pace a longer one in real time with --speed)")
    # before the heading's gait is computed (it said "loaded with LOAD_GAIT" before this refusal)
    if args.states is not None and (args.gait is not None or args.heading is not None or args.rotate is not None):
        raise UsageError("--states: the gait to run; leave out --gait, --heading and --rotate")
    fw, choice = heading_choice(args, robot)
    own = None
    if args.states is not None:  # loaded in this session: a Nano resets on each open, a --sim board is new
        own = user_gait(robot, args.states, "--states")
        args.gait = GAIT_USER
        says = _matrix_way(robot.transitions, own)
        if args.direction is None:
            if says:
                log.info("--states: the robot file's matrix says it walks %s: give --direction %s", says, says)
        elif says and says != args.direction:  # the climb guard would check the other way
            log.warning("warning: --states: the robot file's matrix says this sequence walks %s, and --direction "
                        "states %s: the climb guard ([control] max_climb_deg) checks the way stated", says,
                        args.direction)
    gait = args.gait if args.gait is not None else 0
    # the loaded sequence's way is stated only by --direction (the climb guard checks it)
    direction = args.direction or (UNSTATED if gait == GAIT_USER else "+x")
    if choice is not None:
        gait, direction = (choice.index, choice.direction) if choice.index is not None else (GAIT_USER, UNSTATED)
    elif gait == GAIT_USER and args.sim and own is None:  # --states loads one in this session
        # a --sim board is this command's alone: no load-gait can have reached it (QA hunt: the
        # NACK's "load one first" could not be followed); the refusal below still stands, exit 1
        log.warning("warning: --gait user --sim: the simulated board lives for this command only, so no gait was loaded "
                    "into it and START will be refused (NO_GAIT); give the sequence to run itself: --states SEQ")
    try:
        client = open_client(args, args.robot, speed=args.speed, robot=robot)
    except KeyboardInterrupt:
        raise Interrupted("interrupted while connecting, before the gait started: nothing was started on the "
                          "robot; nothing recorded") from None
    with client, _before_the_gait():
        info = client.info
        if fw is None:
            from ..firmware.gaits import firmware_gaits

            fw = firmware_gaits(robot)
        check_gait(info, gait, direction, gaits_per_direction(robot, fw), fw.left_out_line(direction)
                   if direction in fw else None)
        if choice is not None and choice.index is not None:
            check_library_hash(info, robot, fw, client.link.description, simulated=bool(getattr(args, "sim", False)))
        loaded = own if own is not None else choice.states if choice is not None and choice.index is None else None
        if loaded is not None:
            from ..gait.feasibility import loaded_start

            known = client.wait_known_state()  # a loaded gait starts where the robot stands (no entry path)
            client.load_gait(loaded if known is None else loaded_start(robot, loaded, known.measured))
        meta = RecordingMeta.for_robot(info=info, robot=robot, link=client.link)
        listeners: list[Any] = []
        try:
            if args.record:
                with interrupts.whole():  # a Ctrl-C in between: the recording is already ours to close
                    listeners.append(Logger(args.record, meta))
            if args.udp:
                listeners.append(UdpStreamer(args.udp, args.udp_format, meta))
            if args.format == "jsonl":
                listeners.append(JsonlPrinter(meta, sys.stdout))
            replanner = None
            if args.replan:
                from ..learn.replan import Replanner

                replanner = Replanner(robot, client, None if direction == UNSTATED else direction,
                                      say=lambda t: print(f"  {t}", flush=True) if args.format != "jsonl" else log.info(t))
            run = run_gait_on(client, gait, direction, args.duration, listeners=listeners,
                              progress=log.info, progress_every_s=args.progress, replanner=replanner)
        except RunInterrupted as e:
            for listener in listeners:
                listener.stop()  # the recording is closed whole (an MCAP gets its footer)
            raise Interrupted(_run_interrupted(e, args, robot, listeners)) from None
        except LinkError as e:  # the link died mid-run (a cable pulled): no STOP can reach the robot
            from ..record.base import Writer, what_was_kept

            for listener in listeners:
                listener.stop()
            kept = what_was_kept(next((w for w in listeners if isinstance(w, Writer)), None), args.record)
            watchdog_ms = robot.safety.link_watchdog_ms
            left = (f"the board's link watchdog stops the gait and turns the coils off within {watchdog_ms} ms of the "
                    "last frame" if watchdog_ms else "the firmware has no link watchdog ([safety] link_watchdog_ms "
                    "= 0): the coils may still be on, switch the robot's power off")
            raise LinkError(f"{e}; the link was lost during the run, no STOP could be sent: {left}; {kept}") from None
        except KeyboardInterrupt:  # before START: a recording of nothing is not kept
            for listener in listeners:
                getattr(listener, "discard", listener.stop)()
            raise
        finally:
            for listener in listeners:
                listener.stop()
    errors = list(run.errors) + [str(w.error) for w in listeners if getattr(w, "error", None)]
    # the board's INFO carries the first 15 characters of the name (checked against the file on
    # connecting): a robot named at more length was reported by its truncation
    from ..robot import info_name

    name = robot.name if run.robot == info_name(robot.name) else run.robot
    doc = {
        "msg": "RESULT", "robot": name, "link": client.link.description, "gait": gait,
        "direction": direction, "duration_s": run.duration_s, "cycles": run.cycles,
        # the labels of the states reached, in order, as in proleg sim --json (it was their count)
        "states_reached": [_label(robot, s) for s in run.states_reached], "telemetry_frames": run.telemetry_frames,
        "telemetry_lost": run.telemetry_lost, "telemetry_silent_s": round(run.telemetry_silent_s, 3),
        "faults": [{"t_s": f.time_s, "code": f.code, "detail": f.detail} for f in run.faults],
        "start_time_s": run.started_s,  # the board's clock at START: fault times are on it
        "errors": errors, "ok": run.ok and not errors,
        "replanned": list(replanner.actions) if replanner is not None else [],
    }
    if choice is not None:
        doc["heading"] = {"asked": choice.asked, "ran": choice.heading.name, "loaded": choice.index is None,
                          "states": [robot.transitions.label(s) for s in choice.states]}
    pose = getattr(getattr(getattr(client.link, "board", None), "plant", None), "pose", None)
    if isinstance(pose, (tuple, list)):  # the simulated table plant's planar pose (x, y mm, θ°)
        doc["pose"] = {"x_mm": pose[0], "y_mm": pose[1], "theta_deg": pose[2]}
    if args.format == "jsonl":
        print(json.dumps(doc))
    else:
        if choice is not None and not choice.warned:
            print(choice.message)  # the others were said as a warning before the run (heading_choice)
        which = (f"gait {gait} in {direction}" if gait != GAIT_USER else
                 "the loaded gait" + (" (its way unstated)" if direction == UNSTATED else f" in {direction}"))
        ran = f"for {run.duration_s:g} s" if run.duration_s else "did not start"
        print(f"{name} on {doc['link']}: {which} {ran}: "
              f"{counted(run.cycles, 'cycle')}, {counted(run.telemetry_frames, 'telemetry frame')} "
              f"({run.lost_text()}), {counted(len(run.faults), 'fault')}")
        if "pose" in doc:
            pose = doc["pose"]["x_mm"], doc["pose"]["y_mm"], doc["pose"]["theta_deg"]
            print(f"  pose: x {pose[0]:+.1f} mm, y {pose[1]:+.1f} mm, theta {pose[2]:+.1f} deg")
        from ..console.names import RobotNames, fault_name_text

        names = RobotNames.for_robot(robot)
        for f in run.faults:
            print(f"  FAULT at {f.time_s:.3f} s{run.after_start(f.time_s)}: {fault_name_text(f.code, f.detail, names)}")
    for e in errors:
        print(f"proleg: error: {e}", file=sys.stderr)
    return 0 if doc["ok"] else 1


@contextmanager
def _before_the_gait() -> Iterator[None]:
    """Ctrl-C between connecting and START (checking the board, loading a gait): nothing was
    started on the robot. A Ctrl-C of the run itself is ``run_gait_on``'s to report."""
    try:
        yield
    except KeyboardInterrupt as e:
        if isinstance(e, Interrupted):
            raise
        raise Interrupted("interrupted before the gait started: nothing was started on the robot and no "
                          "coil was driven; nothing recorded") from None


def _run_interrupted(e: Any, args: argparse.Namespace, robot: Any, listeners: list[Any]) -> str:
    """The one line a Ctrl-C'd ``proleg run`` ends with: how far it got, what the robot was
    left doing, and what was kept."""
    from ..record.base import Writer, what_was_kept
    from ..report.robot_run import stop_text

    clock = " (simulated time)" if getattr(args, "sim", False) else ""
    if e.started:
        when = (f"interrupted {e.ran_s:.1f} s into the {args.duration:g} s run{clock}, after "
                f"{counted(e.run.cycles, 'cycle')}")
    else:
        when = "interrupted while starting the gait (START was not acknowledged yet)"
    kept = what_was_kept(next((w for w in listeners if isinstance(w, Writer)), None), args.record)
    if args.format == "jsonl":
        kept += "; no RESULT line printed"
    return f"{when}; {stop_text(e.stopped, robot.safety.link_watchdog_ms)}; {kept}"


def _label(robot: Any, state: int) -> str:
    """A state the board reports, by its label (by its number if the robot file has no such state)."""
    return robot.transitions.label(state) if 0 <= state < robot.transitions.n_states else str(state)


# --------------------------------------------------------------------------- load-gait, set-param
#: After a command that changes a --sim board: the next command's --sim is another, fresh one.
SIM_IS_FRESH = ("note: a --sim board lives for this command only; the next command's --sim starts afresh "
                "(proleg console --sim, or proleg sim --pty with --port, keeps one board running)")


def user_gait(robot: Any, text: str, what: str = "STATES") -> list[int]:
    """The closed walk ``text`` names (``00,10,11,01`` or with the start repeated), checked as
    the board would check it (GaitError naming ``what``: a forbidden step, too many steps), and
    warned of where proleg build would warn of its own gaits (a step the robot cannot make, a
    fault to expect; a loaded gait has no entry path from rest)."""
    table = robot.transitions
    try:
        states = table.cycle(text, [limb.name for limb in robot.limbs])
    except ValueError as e:
        raise GaitError(f"{what}: {e}") from None
    from ..protocol.definition import MAX_GAIT_STEPS

    if len(states) > MAX_GAIT_STEPS:
        raise GaitError(f"{what}: a gait of {len(states)} steps; the firmware holds a user gait of at most "
                        f"{MAX_GAIT_STEPS} (the start state is not repeated at the end)")
    for a, b in zip(states, [*states[1:], states[0]]):  # the board refuses these: say which, before sending
        if table.lookup(a, b) is None:
            raise GaitError(f"{what}: {table.label(a)} → {table.label(b)} is forbidden in {robot.name}'s robot file "
                            "(\"x\" in its matrix); the board refuses it (FORBIDDEN_TRANSITION)")
    from ..firmware.gaits import CANNOT_MAKE
    from ..gait.feasibility import gait_problems, rest_start_warning

    if (line := rest_start_warning(robot, states)) is not None:
        log.warning("warning: %s", line)
    # what proleg build says of its own gaits: a shared coil moving its limbs apart, a state out of
    # reach, a coil kept on past max_on_ms... (a loaded gait has no entry path: rest_start_warning's)
    for p in gait_problems(robot, states, from_rest=False):
        if p.severity == "error":
            why = "the robot cannot make it" if p.kind in CANNOT_MAKE else "expect a fault"
            log.warning("warning: %s: %s: %s", what, why, p.message)
    return states


def cmd_load_gait(args: argparse.Namespace) -> int:
    from ..robot import load_robot

    robot = load_robot(args.robot)
    table = robot.transitions
    states = user_gait(robot, args.states)
    with open_client(args, args.robot, robot=robot) as client:
        client.load_gait(states)
        print(f"loaded {' → '.join(table.label(x) for x in [*states, states[0]])} as the user gait on {client.link.description} "
              f"({_way_hint(table, states)})")
        if getattr(args, "sim", None):
            print(SIM_IS_FRESH)
    return 0


def _matrix_way(table: Any, states: list[int]) -> str | None:
    """The way the robot file's matrix says the closed walk ``states`` goes: "+x", "-x", "" for
    neither, None when the matrix cannot score it."""
    from ..gait import evaluate_sequence

    try:
        reward = evaluate_sequence(table, [*states, states[0]]).reward
    except GaitError:
        return None
    return "" if reward == 0 else "+x" if reward > 0 else "-x"


def _way_hint(table: Any, states: list[int]) -> str:
    """How to run a loaded sequence: with the way the robot file's matrix says it walks
    stated, so that the climb guard checks it (docs/calibration.md)."""
    way = _matrix_way(table, states)
    if way is None:
        return "run it with --gait user"
    if not way:
        return "the robot file's matrix says it walks neither way; run it with --gait user"
    return f"the robot file's matrix says it walks {way}: run it with --gait user --direction {way}"


def cmd_set_param(args: argparse.Namespace) -> int:
    from ..link.client import HEARTBEAT_S, WATCHDOG_SHARE
    from ..robot import MIN_LINK_WATCHDOG_MS

    watchdog = args.name == "link_watchdog_ms"
    if watchdog and 0 < args.value < MIN_LINK_WATCHDOG_MS:
        raise UsageError(f"link_watchdog_ms: expected at least {MIN_LINK_WATCHDOG_MS} ms (as in a robot file; the "
                         f"board takes 0 only when its build has no watchdog), got {args.value}")
    index = _param_index(args)
    with open_client(args) as client:
        client.set_param(args.name, index, args.value)
        print(f"set {args.name}[{index}] = {args.value} on {client.link.description}")
        if watchdog and 0 < args.value < HEARTBEAT_S * 1000 * WATCHDOG_SHARE:
            print(f"note: the board keeps {args.value} ms until it resets, and nothing tells a later session: one "
                  f"that knows only the robot file's watchdog pings every {HEARTBEAT_S:g} s or a quarter of that "
                  f"watchdog, and its gait stops with LINK_WATCHDOG; set it in the robot file ([safety] "
                  "link_watchdog_ms) and rebuild to keep it")
        if getattr(args, "sim", None):
            print(SIM_IS_FRESH)  # as load-gait and calibrate say: the setting ends with this command
        elif args.port:
            print(PORT_OPEN_RESETS)
    return 0


#: After set-param on a serial port: the value lasts until the board resets, and a Nano resets
#: whenever its port is opened. A max_on_ms narrowed this way for a fragile coil was silently
#: the robot file's again in the next command's session (proleg run), with no word.
PORT_OPEN_RESETS = ("note: the board keeps it until it resets, and a Nano resets whenever its port is opened: on a Nano "
                    "the next proleg command on this port (proleg run ...) starts with the robot file's value again; a script that "
                    "sets it and runs in one session (RobotClient.set_param, then start) keeps it, and the robot file "
                    "([safety], [control]) keeps it for good")


#: The parameters that take ``--index``, and what it counts (docs/control.md); the others have none.
INDEXED_PARAMS = {"psi_star_cdeg": "the threshold, counted limb by limb (a limb of k levels has k − 1)",
                  "hysteresis_cdeg": "the limb"}


def _param_index(args: argparse.Namespace) -> int:
    """``--index`` for SET_PARAM (0 when the parameter has none). An index on a parameter
    that has none is a UsageError, as is one past the robot's limbs or thresholds when the
    robot is known (``--sim ROBOT``; a board checks it itself, NACK OUT_OF_RANGE): it was
    sent and ignored, and ``set drive_duty[5]`` printed as if it meant something."""
    counts = INDEXED_PARAMS.get(args.name)
    if counts is None:
        if args.index is not None:
            raise UsageError(f"--index {args.index}: {args.name} has no index (only "
                             f"{' and '.join(INDEXED_PARAMS)} take one; docs/control.md)")
        return 0
    index = args.index or 0
    if isinstance(getattr(args, "sim", None), str):
        from ..robot import load_robot
        from .main import robot_arg

        robot = load_robot(robot_arg(args.sim))
        limbs = args.name == "hysteresis_cdeg"
        n = len(robot.limbs) if limbs else sum(limb.levels - 1 for limb in robot.limbs)
        if index >= n:
            raise UsageError(f"--index {index}: {args.name}'s index is {counts}; {robot.name} has "
                             f"{counted(n, 'limb' if limbs else 'threshold')}, expected 0..{n - 1}")
    return index


def _param_name(text: str) -> str:
    from ..protocol.definition import ParamId

    name = text.strip().lower().replace("-", "_")
    if name.upper() not in ParamId.__members__:
        raise argparse.ArgumentTypeError(
            f"unknown parameter {text!r}; known: {', '.join(p.name.lower() for p in ParamId)}")
    return name


# --------------------------------------------------------------------------- robots
def cmd_robots(args: argparse.Namespace) -> int:
    import tomllib

    from ..paths import bundled_robots, robots_dir

    for name in bundled_robots():
        path = robots_dir() / f"{name}.toml"
        try:
            doc = tomllib.loads(path.read_text(encoding="utf-8"))
            desc = str(doc.get("robot", {}).get("description", "")).strip().splitlines()[0:1]
            limbs = len(doc.get("limb", []))
        except (OSError, tomllib.TOMLDecodeError):
            desc, limbs = [], 0
        print(f"{name:24s} {counted(limbs, 'limb')}  {desc[0] if desc else ''}".rstrip())
    return 0


# --------------------------------------------------------------------------- argparse
def add_arguments(subparsers: Any) -> None:
    from .main import add_udp_options, robot_arg

    r = subparsers.add_parser("run", help="run a gait on a robot headless: progress on stderr, exit 1 on faults")
    r.add_argument("robot", metavar="ROBOT", type=robot_arg)
    add_link_options(r, sim_takes_robot=False)
    r.add_argument("--gait", type=gait_index, default=None, metavar="N",
                   help="gait index in the firmware's table for the direction, or 'user' (default 0)")
    r.add_argument("--direction", choices=("+x", "-x"), default=None,
                   help="default +x; with --gait user, the way the loaded sequence walks, which the "
                        "firmware's climb guard checks ([control] max_climb_deg; unstated by default)")
    r.add_argument("--states", metavar="SEQ",
                   help="run this closed walk of state labels (00,10,11,01 or with the start repeated), loaded "
                        "in this session (LOAD_GAIT) as load-gait would: a Nano resets when its port opens, so "
                        "a gait loaded by an earlier command is gone; --direction states its way")
    steer = r.add_mutually_exclusive_group()
    steer.add_argument("--heading", type=heading_deg, metavar="DEG",
                       help="run the gait library's gait for this heading (0 = +x, 90 = +y; the nearest the "
                            "library holds), or compute and load one (docs/planar.md)")
    steer.add_argument("--rotate", choices=("cw", "ccw"), help="run the library's rotation gait (turn on the spot)")
    r.add_argument("--exact-heading", action="store_true",
                   help="with --heading: a heading the library does not hold is computed and loaded (LOAD_GAIT)")
    r.add_argument("--library", metavar="HEADINGS",
                   help="the library the firmware was built with (proleg build --library), if not the robot file's")
    r.add_argument("--duration", type=positive_float, default=10.0, metavar="S",
                   help=f"seconds to run (default 10; with --sim and no --speed, at most {MAX_SIM_S:g})")
    r.add_argument("--record", metavar="FILE", help="record every frame (.csv, .jsonl or .mcap)")
    add_udp_options(r)
    r.add_argument("--format", choices=("text", "jsonl"), default="text",
                   help="text: a summary; jsonl: every message as a JSON line, then a RESULT line")
    r.add_argument("--progress", type=progress_period, default=1.0, metavar="S",
                   help="progress every S seconds of the run (at least 0.1; default 1)")
    r.add_argument("--speed", type=speed_factor, default=None,
                   help="with --sim: times real time, at least 0.001 (default: as fast as possible)")
    r.add_argument("--no-replan", dest="replan", action="store_false",
                   help="do not replan after an actuator loss (default: on a fault naming an actuator, "
                        "load the best gait of what the robot can still do and go on; docs/learning.md)")
    r.set_defaults(run=cmd_run)

    lg = subparsers.add_parser("load-gait", help="store a user gait (state labels) on the robot")
    lg.add_argument("robot", metavar="ROBOT", type=robot_arg)
    lg.add_argument("states", metavar="STATES",
                    help="state labels of a closed walk, the start repeated at the end or not: 00,10,11,01 or "
                         "00,10,11,01,00")
    add_link_options(lg, sim_takes_robot=False)
    lg.set_defaults(run=cmd_load_gait)

    from ..protocol.definition import ParamId

    sp = subparsers.add_parser("set-param", help="set a firmware parameter (within the build's safety envelope)",
                               epilog="parameters: " + ", ".join(p.name.lower() for p in ParamId))
    sp.add_argument("name", metavar="NAME", type=_param_name, help="parameter name (see below)")
    sp.add_argument("value", metavar="VALUE", type=param_value, help="value in the parameter's unit (permyriad, ms, 0.01°)")
    sp.add_argument("--index", type=param_index, default=None, metavar="N",
                    help="hysteresis_cdeg: the limb, from 0 = the first; psi_star_cdeg: the threshold, counted limb "
                         "by limb (a limb of k levels has k-1); default 0. The other parameters have none. "
                         "Every parameter, unit and range: docs/control.md")
    add_link_options(sp, sim_takes_robot=True)
    sp.set_defaults(run=cmd_set_param)

    rb = subparsers.add_parser("robots", help="list the example robots bundled with proleg (usable as ROBOT)")
    rb.set_defaults(run=cmd_robots)
