"""The ``proleg`` command's parser and the build/flash/sim commands: parse arguments,
call the library, print. ``gait`` is in ``gait``; ``console``, ``plot`` and ``dbc`` in
``link_commands``; ``run``, ``load-gait``, ``set-param`` and ``robots`` in ``robot_commands``.

Exit codes (also in ``proleg --help``): 0 ok; 1 failed (a link or command failed, the robot
faulted, an output could not be written); 2 usage (a bad argument, robot file, board file,
recording or gait). Every user mistake arrives here as a ``ProlegError`` and leaves as one line on stderr;
a closed pipe (``proleg … | head``), a full disk and a terminal that cannot show UTF-8 end
without a traceback.
"""

from __future__ import annotations

import argparse
import errno
import json
import logging
import os
import shlex
import sys
from collections.abc import Sequence
from pathlib import Path

from .. import __version__
from ..errors import LinkError, ProlegError
from .gait import add_gait_parser
from .number_args import gait_number, max_transitions, positive_float

EXIT_OK, EXIT_FAILED, EXIT_USAGE = 0, 1, 2
#: The longest ``proleg sim`` run (simulated seconds): an hour takes about a minute on host-sim
#: (the emulated boards are slower); 1e12 never finished. ``--pty`` serves in real time, unbounded.
MAX_SIM_S = 3600.0
EPILOG = """\
exit status:
  0  ok
  1  failed: a link or command failed, the robot faulted, an output could not be written
  2  usage: a bad argument, robot file, board file, recording or gait

ROBOT is a robot file or the name of a bundled example (proleg robots lists them).
"""
log = logging.getLogger("proleg")


def main(argv: Sequence[str] | None = None) -> int:
    _tolerant_streams()
    argv = _hoist_verbosity(_join_signed_values(sys.argv[1:] if argv is None else list(argv)))
    args = build_parser().parse_args(argv)
    _setup_logging(args.verbose - args.quiet)
    try:
        code = args.run(args)
        sys.stdout.flush()
        return code
    except LinkError as e:  # the robot, the link or a file to write failed
        print(f"proleg: error: {e}", file=sys.stderr)
        return EXIT_FAILED
    except ProlegError as e:
        print(f"proleg: error: {e}", file=sys.stderr)
        return EXIT_USAGE
    except KeyboardInterrupt:
        return 130
    except BrokenPipeError:  # the reader went away (`proleg … | head -1`): not an error
        _silence_stdout()
        return EXIT_OK
    except OSError as e:  # a full disk, a vanished directory... while writing an output
        print(f"proleg: error: {os_error_line(e)}", file=sys.stderr)
        _silence_stdout()
        return EXIT_FAILED


#: What only a write fails with (a full disk or quota, a file too large, a read-only file system).
WRITE_ERRNOS = frozenset({errno.ENOSPC, errno.EDQUOT, errno.EFBIG, errno.EROFS})


def os_error_line(e: OSError) -> str:
    """An OSError no command caught, as one line naming the file. Input files are read and
    reported where they are read (board and robot files: exit 2); an OSError reaching here
    without a file name failed on a stream already open, an output (stdout, a full disk). With
    a file name, "write" only when only a write fails that way: a directory or a missing
    permission may be either."""
    why = e.strerror or str(e)
    if not e.filename:
        return f"cannot write: {why}"
    verb = "cannot write" if e.errno in WRITE_ERRNOS else "cannot access"
    return f"{verb} {e.filename}: {why}"


def _tolerant_streams() -> None:
    """Print with replacement on a terminal that cannot encode everything (LANG=C,
    PYTHONIOENCODING=ascii): ``→`` becomes ``?`` rather than a UnicodeEncodeError."""
    for stream in (sys.stdout, sys.stderr):
        reconfigure = getattr(stream, "reconfigure", None)
        if reconfigure is not None and (stream.encoding or "").lower().replace("-", "") != "utf8":
            try:
                reconfigure(errors="replace")
            except (ValueError, OSError):
                pass


def _silence_stdout() -> None:
    """Point stdout at /dev/null so the interpreter's last flush does not fail again."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)
    except (OSError, ValueError):
        pass


def _setup_logging(verbosity: int) -> None:
    """-v: debug; default: info (progress); -q: warnings only; -qq: errors only."""
    level = {1: logging.DEBUG, 0: logging.INFO, -1: logging.WARNING}.get(verbosity, logging.DEBUG if verbosity > 0
                                                                      else logging.ERROR)
    handler = logging.StreamHandler(sys.stderr)
    handler.setFormatter(logging.Formatter("proleg: %(message)s"))
    log.handlers[:] = [handler]
    log.setLevel(level)
    log.propagate = False


def _hoist_verbosity(argv: list[str]) -> list[str]:
    """Accept -v/-q anywhere (``proleg run … -q``): argparse takes them before the command."""
    flags = [a for a in argv if a in ("-v", "-vv", "-q", "-qq", "--verbose", "--quiet")]
    rest = [a for a in argv if a not in flags]
    return flags + rest


def _join_signed_values(argv: list[str]) -> list[str]:
    """Let ``--direction -x`` through: argparse would read ``-x`` as an option."""
    out: list[str] = []
    it = iter(argv)
    for a in it:
        if a == "--direction":
            nxt = next(it, None)
            out.append(a if nxt is None else f"--direction={nxt}")
        else:
            out.append(a)
    return out


def robot_arg(text: str) -> str:
    """A ROBOT argument: a robot file, or the name of a bundled example robot."""
    from ..paths import resolve_robot

    if not text.strip():
        raise argparse.ArgumentTypeError("expected a robot file or a bundled robot's name, got ''")
    return str(resolve_robot(text))


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="proleg", description="Gaits, firmware and simulation for soft crawling robots.",
                                epilog=EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--version", action="version", version=f"proleg {__version__}")
    p.add_argument("-v", "--verbose", action="count", default=0, help="more messages on stderr (-vv: debug)")
    p.add_argument("-q", "--quiet", action="count", default=0, help="fewer messages on stderr (no progress)")
    sub = p.add_subparsers(dest="command", required=True, metavar="COMMAND")

    add_gait_parser(sub)

    b = sub.add_parser("build", help="render and compile the robot's firmware for a board")
    _firmware_args(b)
    b.set_defaults(run=cmd_build)

    f = sub.add_parser("flash", help="build and flash the robot's firmware onto a board")
    _firmware_args(f)
    f.add_argument("--port", help="serial port of the board's bootloader, e.g. /dev/ttyUSB0")
    f.add_argument("--tool", help="flash tool when the board has several (e.g. openocd, pyocd)")
    f.add_argument("--dry-run", action="store_true", help="print the flash command instead of running it")
    f.set_defaults(run=cmd_flash)

    s = sub.add_parser("sim", help="run the robot's firmware on the simulated board, in closed loop with its plant")
    s.add_argument("robot", metavar="ROBOT", type=robot_arg)
    s.add_argument("--duration", type=positive_float, default=None, metavar="S",
                   help=f"simulated seconds (default 60, at most {MAX_SIM_S:g}; with --pty: until Ctrl-C)")
    s.add_argument("--gait", type=gait_number, default=0, metavar="N", help="gait index in the firmware's table (default 0)")
    s.add_argument("--direction", choices=("+x", "-x"), default="+x")
    add_sim_board_options(s)
    s.add_argument("--inject", action="append", default=[], metavar="FAULT",
                   help="fault to inject, optionally at a time: imu-silent:LIMB, imu-stuck:LIMB, imu-garbage:LIMB, "
                        "dead-actuator:ACTUATOR, drift[:ACTUATOR][@RATE], link-drop[:P], link-corrupt[:P]; "
                        "append +T for T simulated seconds after the start, at most --duration (e.g. dead-actuator:sma-right+10)")
    s.add_argument("--seed", type=int, default=1)
    s.add_argument("--record", metavar="FILE", help="record every frame (.csv, .jsonl or .mcap)")
    add_udp_options(s)
    s.add_argument("--json", action="store_true", help="print the report as one JSON object")
    s.add_argument("--pty", action="store_true",
                   help="serve the simulated board on a pseudo-terminal in real time instead (for proleg console)")
    s.add_argument("--speed", type=positive_float, default=1.0, help="with --pty: times real time (default 1)")
    from .sim_plant import add_plant_options

    add_plant_options(s)  # --plant, --condition, --measure-matrix
    s.set_defaults(run=cmd_sim)

    from .link_commands import add_arguments as add_link_commands
    from .robot_commands import add_arguments as add_robot_commands

    add_link_commands(sub)  # console, plot, dbc
    add_robot_commands(sub)  # run, load-gait, set-param, robots
    __import__("proleg.cli.learn", fromlist=["add_arguments"]).add_arguments(sub)  # learn
    __import__("proleg.cli.calibrate", fromlist=["add_arguments"]).add_arguments(sub)  # calibrate
    return p


def add_sim_board_options(p: argparse.ArgumentParser) -> None:
    """The simulated board and the gait selection its firmware is built with."""
    from ..sim.simulated_boards import SIMULATED_BOARDS

    p.add_argument("--board", choices=tuple(SIMULATED_BOARDS), default="host-sim",
                   help="host-sim: the firmware's C on the host (default); avr-emu / arm-emu: the exact "
                        "arduino-nano / bluepill firmware.elf on an emulated MCU (--json adds the tick budget)")
    p.add_argument("--objective", choices=("total", "rate", "speed"), default="total",
                   help="which optimal gaits the simulated firmware carries (default total)")
    p.add_argument("--max-transitions", type=max_transitions, metavar="N",
                   help="longest gait considered, 2..256 (default: the build's, see docs/gait-selection.md)")


def add_udp_options(p: argparse.ArgumentParser) -> None:
    p.add_argument("--udp", metavar="HOST:PORT", help="stream every telemetry frame over UDP to PlotJuggler or Teleplot")
    p.add_argument("--udp-format", choices=("plotjuggler", "teleplot"),
                   help="with --udp: plotjuggler: one JSON object per datagram (default); teleplot: "
                        ">name:timestamp_ms:value lines")


def udp_options(args: argparse.Namespace) -> tuple[str | None, str]:
    """(``--udp`` endpoint or None, ``--udp-format``); ``--udp-format`` without ``--udp`` is a
    UsageError (it would be ignored), and the endpoint is checked before anything is opened."""
    from ..errors import UsageError
    from ..record.udp import parse_endpoint

    if args.udp is None:
        if args.udp_format is not None:
            raise UsageError("--udp-format: only with --udp HOST:PORT (it is the format of that stream)")
        return None, "plotjuggler"
    parse_endpoint(args.udp)
    return args.udp, args.udp_format or "plotjuggler"


def _firmware_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("robot", metavar="ROBOT", type=robot_arg)
    p.add_argument("--board", required=True, help="board name (boards/NAME.toml) or a board file")
    p.add_argument("-o", "--out", metavar="DIR", help="project directory (default build/ROBOT-BOARD)")
    p.add_argument("--objective", choices=("total", "rate", "speed"), default="total",
                   help="which optimal gaits the firmware carries (default total)")
    p.add_argument("--max-transitions", type=max_transitions, metavar="N", help="longest gait, 2..256")
    p.add_argument("--library", metavar="HEADINGS",
                   help="also carry a gait library, e.g. 0,90,180,270,rot-cw (instead of the robot file's [gaits]; "
                        "docs/planar.md)")


# ---------------------------------------------------------------------------------------
# proleg build / flash


def _build(args: argparse.Namespace):
    from ..firmware.boards import load_board
    from ..firmware.build import build
    from ..robot import load_robot

    robot = load_robot(args.robot)
    board = load_board(args.board)
    from .gait import check_speed_objective

    check_speed_objective(robot, args.objective)
    library = None
    if getattr(args, "library", None):
        from ..gait.library import library_spec

        library = library_spec(args.library, **(robot.library.as_kwargs() if robot.library is not None else {}))
    result = build(robot, board, args.out, objective=args.objective, max_transitions=args.max_transitions,
                   library=library)
    print(f"built {robot.name} for {board.name}: {result.artifact}")
    print(f"  {result.size_report()}")
    if result.fit is not None:
        for line in result.fit.lines():
            print(f"  {line}")
    for line in result.warnings:
        print(f"proleg: warning: {line}", file=sys.stderr)
    for d, gaits in result.gaits.items():
        shown = "; ".join(" ".join(robot.transitions.label(s) for s in g.states) for g in gaits) or "none"
        print(f"  {d} gaits: {shown}")
    from ..firmware.gaits import fallback_lines

    for line in fallback_lines(robot):
        print(f"  {line}")
    for lg in getattr(result.gaits, "library", ()):
        print(f"  library {lg.describe(robot.transitions.label)}")
    return result


def cmd_build(args: argparse.Namespace) -> int:
    _build(args)
    return 0


def cmd_flash(args: argparse.Namespace) -> int:
    from ..firmware.boards import load_board
    from ..firmware.flash import choose_method, flash, flash_command

    board = load_board(args.board)
    method = choose_method(board, args.tool)
    if args.dry_run:
        from ..firmware.build import default_out_dir
        from ..robot import load_robot

        out = Path(args.out) if args.out else default_out_dir(load_robot(args.robot), board)
        print(shlex.join(flash_command(method, out / board.artifact, args.port)))
        return 0
    flash_command(method, Path("firmware"), args.port)  # a missing --port fails before building
    result = _build(args)
    flash(method, result.artifact, args.port)
    print(f"flashed {result.artifact} with {method.tool}")
    return 0


# ---------------------------------------------------------------------------------------
# proleg sim


def cmd_sim(args: argparse.Namespace) -> int:
    from ..report import SimSession
    from ..robot import load_robot
    from ..firmware.gaits import firmware_gaits
    from ..sim.simulators import open_simulated
    from ..sim.simulated_boards import clear_ticks, tick_budget

    robot = load_robot(args.robot)
    from .sim_plant import (calibrate_then_put_down, cmd_measure_climb, cmd_measure_matrix, flat_conditions,
                            plant_kwargs, refuse_what_does_not_apply, wants_help)

    refuse_what_does_not_apply(args)  # an option the mode would ignore is a mistake, not a no-op
    from .gait import check_speed_objective

    check_speed_objective(robot, args.objective)
    args.udp, args.udp_format = udp_options(args)
    pty_limit_s = args.duration  # --pty serves until Ctrl-C unless a duration is given
    if not args.pty and (args.duration or 0) > MAX_SIM_S:
        from ..errors import SimError

        raise SimError(f"--duration {args.duration:g}: expected at most {MAX_SIM_S:g} simulated seconds (an hour "
                       "takes about a minute to simulate; run several shorter simulations instead)")
    if args.duration is None:
        args.duration = 60.0

    if wants_help(args):
        return EXIT_OK
    if args.measure_climb:
        return cmd_measure_climb(args, robot)
    if args.measure_matrix:
        if args.calibrated:
            from ..errors import SimError

            raise SimError("--calibrated: not with --measure-matrix (the matrix is measured by an idealised drive "
                           "with true psi, no firmware to calibrate)")
        return cmd_measure_matrix(args, robot)
    if args.hold_range:
        from ..errors import SimError

        raise SimError("--hold-range: it is an option of --measure-matrix (measure the matrix at several hold margins)")
    if not args.pty:
        have = len(firmware_gaits(robot, args.objective, args.max_transitions).get(args.direction, ()))
        if args.gait >= have:
            from ..errors import GaitError

            shown = f"gaits 0..{have - 1}" if have else "no gait"
            raise GaitError(f"--gait {args.gait}: {robot.name} has {shown} in {args.direction}")
    plant = plant_kwargs(args)
    if args.calibrated:
        if args.pty:
            from ..errors import SimError

            raise SimError("--calibrated: not with --pty (calibrate through the pseudo-terminal: proleg calibrate)")
        plant["conditions"] = flat_conditions(args)  # calibrated on the flat, put down on the slope below
    sim = open_simulated(robot, args.board, seed=args.seed, objective=args.objective,
                         max_transitions=args.max_transitions, **plant)
    # --pty may be stopped early (Ctrl-C) and names what it did not inject; a plain run would not say
    timed, at_once = _injections(args.inject, None if args.pty else args.duration)
    for spec in [*at_once, *(fault for _, fault in timed)]:
        sim.check_fault(spec)  # a bad name fails now, not halfway through the run
    if not args.calibrated:
        for spec in at_once:
            sim.inject(spec)
    if args.pty:
        return _serve_pty(sim, args, timed, pty_limit_s)
    recorder = _recorder(robot, args.record, args.board) if args.record else None
    listeners = [recorder] if recorder else []
    if args.udp:
        from ..record import RecordingMeta, UdpStreamer

        meta = RecordingMeta.for_robot(robot=robot, board=args.board, truth=("displacement_mm",))
        listeners.append(UdpStreamer(args.udp, args.udp_format, meta))
    session = SimSession(sim, listeners=listeners)
    try:
        session.advance(0.2)  # boot
        if args.calibrated:
            calibrate_then_put_down(session, sim, robot, args)
            for spec in at_once:  # on the plant the robot walks on
                sim.inject(spec)
        clear_ticks(sim)  # the tick budget is measured over the gait run
        start = sim.time_s
        for at, fault in timed:
            session.schedule_fault(start + at, fault)
        report = session.run_gait(args.direction, args.gait, args.duration)
    finally:
        for listener in listeners:
            listener.stop()
    budget = tick_budget(sim)
    if args.json:
        print(json.dumps({**_report_json(robot, report, args.board), **(budget or {})}))
    else:
        print(_report_text(robot, report, args.board, budget))
    for e in report.errors:
        print(f"proleg: error: {e}", file=sys.stderr)
    if recorder is not None and recorder.error is not None:
        print(f"proleg: error: {recorder.error}", file=sys.stderr)
        return EXIT_FAILED
    return EXIT_OK if report.ok else EXIT_FAILED


def _injections(specs: list[str], run_s: float | None) -> tuple[list[tuple[float, str]], list[str]]:
    """``--inject`` as (timed: (T, FAULT) for FAULT+T, checked to fall within ``run_s``; at once: FAULT)."""
    from ..console.inject import parse_injection

    timed = [parse_injection(spec, run_s) for spec in specs if "+" in spec]
    return timed, [spec for spec in specs if "+" not in spec]


def _serve_pty(sim, args, timed=(), limit_s: float | None = None) -> int:
    from ..sim.pty import PtyServer

    say = lambda line: print(line, flush=True)  # noqa: E731
    with PtyServer(sim, speed=args.speed, faults=timed, say=say) as server:
        print(f"simulated {sim.robot.name} on {server.path} (115200 8N1; Ctrl-C to stop)", flush=True)
        print(f"  connect with: proleg console --port {server.path}", flush=True)
        try:
            server.serve(limit_s)
        except KeyboardInterrupt:
            pass
        for at, fault in server.due:  # never dropped silently
            print(f"proleg: not injected: {fault}+{at:g} (the simulation stopped at "
                  f"{server.elapsed_s:.1f} s)", file=sys.stderr)
    return 0


def _recorder(robot, path: str, board: str = "host-sim"):
    from ..record import Logger, RecordingMeta

    return Logger(path, RecordingMeta.for_robot(robot=robot, board=board, truth=("displacement_mm",)))


def _report_json(robot, report, board: str = "host-sim") -> dict:
    t = robot.transitions
    return {
        "robot": robot.name,
        "board": board,
        "direction": report.direction,
        "gait": report.gait,
        "duration_s": report.duration_s,
        "cycles": report.cycles,
        "cycle_displacements_mm": report.cycle_displacements_mm,
        "mean_cycle_mm": report.mean_cycle_mm,
        "displacement_mm": report.displacement_mm,
        "speed_mm_s": report.displacement_mm / report.duration_s if report.duration_s > 0 else 0.0,
        "states_reached": [t.label(s) for s in report.states_reached],
        "true_transitions": report.true_transitions,
        "unexpected_transitions": report.unexpected_transitions,
        "start_time_s": report.started_s,  # the board's clock at START: fault times are on it
        "faults": [{"time_s": f.time_s, "code": f.code, "detail": f.detail} for f in report.faults],
        "telemetry_frames": report.telemetry_frames,
        "telemetry_lost": report.telemetry_lost,
        "link_errors": report.link_errors,
        "errors": report.errors,
    }


def _report_text(robot, report, board: str = "host-sim", budget: dict | None = None) -> str:
    t = robot.transitions
    seq = [t.label(s) for s in report.states_reached]
    shown = " → ".join(seq[:13]) + (" …" if len(seq) > 13 else "")
    lines = [
        f"{robot.name} on {board}: gait {report.gait} in {report.direction} for {report.duration_s:g} s (simulated)",
        f"  states reached:   {shown or 'none'}",
        f"  cycles completed: {report.cycles}",
    ]
    if report.cycles:
        per = ", ".join(f"{d:+.1f}" for d in report.cycle_displacements_mm[:8])
        more = " …" if report.cycles > 8 else ""
        lines.append(f"  displacement per cycle (mm): {per}{more}   mean {report.mean_cycle_mm:+.2f}")
    lines.append(
        f"  displacement total: {report.displacement_mm:+.1f} mm over {report.true_transitions} true transitions"
        f" ({report.unexpected_transitions} not in the matrix)"
    )
    from ..console.names import RobotNames, fault_name_text

    for f in report.faults:
        lines.append(f"  FAULT at {f.time_s:.3f} s{report.after_start(f.time_s)}: "
                     f"{fault_name_text(f.code, f.detail, RobotNames.for_robot(robot))}")
    if report.limb_loss:  # EVENT SUSPECT / FALLBACK (issue 15), by name
        from ..console.names import describe_event

        lines += [f"  {describe_event(e, RobotNames.for_robot(robot), t.label).strip()}" for e in report.limb_loss]
    for e in report.errors:
        lines.append(f"  ERROR: {e}")
    errs = ", ".join(f"{k} {v}" for k, v in report.link_errors.items()) or "none"
    lines.append(
        f"  telemetry: {report.telemetry_frames} frames, {report.telemetry_lost} lost; link errors: {errs}"
    )
    if budget is not None:
        period, busy = budget["tick_period_us"], budget["tick_busy_us"]
        lines.append(
            f"  tick busy (µs of a {period:g} µs tick, {busy['ticks']} ticks): mean {busy['mean']:g}, "
            f"p99 {busy['p99']:g} ({100 * busy['p99'] / period:.0f} %), max {busy['max']:g} "
            f"({100 * busy['max'] / period:.0f} %)"
        )
    return "\n".join(lines)

