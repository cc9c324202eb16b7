"""The ``proleg`` command's parser and the build/flash commands: parse arguments, call the
library, print. ``gait`` is in ``gait``; ``sim`` in ``sim_command``; ``console``, ``plot`` and
``dbc`` in ``link_commands``; ``run``, ``load-gait``, ``set-param`` and ``robots`` in
``robot_commands``; ``check`` in ``check``.

Exit codes (also in ``proleg --help``): 0 ok; 1 failed (a link or command failed, the robot
faulted, an output could not be written where it is named (a directory in its place: every
output option alike), the board does not run the robot file's firmware: a
file that loads but is not the one the board was built from is found only over the link);
2 usage (a bad argument, a robot file, board file or recording that does not load, a bad
gait); 130 Ctrl-C, 143 SIGTERM, 129 SIGHUP. Every user mistake arrives here as a ``ProlegError`` and leaves as one line on stderr;
a closed pipe (``proleg … | head``), a full disk and a terminal that cannot show UTF-8 end
without a traceback.
"""

from __future__ import annotations

import argparse
import errno
import logging
import os
import shlex
import signal
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from .. import __version__
from ..errors import Interrupted, LinkError, ProlegError, WorkerLost
from .gait import add_gait_parser
from .number_args import max_transitions

if TYPE_CHECKING:
    from ..record.udp import UdpEndpoint

EXIT_OK, EXIT_FAILED, EXIT_USAGE = 0, 1, 2
EPILOG = """\
exit status:
  0    ok
  1    failed: a link or command failed, the robot faulted, an output could not be written
       where it is named (a directory in its place, a folder not writable, a full disk),
       the board does not run the firmware of the robot file given
  2    usage: a bad argument (an output directory that does not exist), a robot file,
       board file or recording that does not load, a bad gait
  130  interrupted: Ctrl-C (SIGINT), with one line saying what was kept (console: Ctrl-C
       is a way to leave, 0)
  143  ended by SIGTERM (kill, a CI job's timeout) the way Ctrl-C ends it (console too)
  129  ended by SIGHUP (a closed terminal) the way Ctrl-C ends it

ROBOT is a robot file or the name of a bundled example (proleg robots lists them).
"""
log = logging.getLogger("proleg")


#: The signal that ended the command (SIGTERM, SIGHUP), if not Ctrl-C: its exit status is 128 + it.
_ended_by: list[int] = []


def _as_ctrl_c(signum: int, frame: object) -> None:
    """SIGTERM (``kill``, a CI timeout) and SIGHUP (a closed terminal) end a command the way
    Ctrl-C does: the robot is stopped, a recording closed whole, one line says what was kept.
    Delivered as SIGINT, so that whatever takes Ctrl-C now (``interrupts.whole`` defers it)
    takes these too. Before, they killed a learn or run mid-piece, no STOP sent, nothing said."""
    _ended_by.append(signum)
    os.kill(os.getpid(), signal.SIGINT)


def _terminate(signum: int, frame: object) -> None:
    """``_as_ctrl_c`` for a process whose Ctrl-C is ignored (``proleg run … &`` in a script):
    raised as one directly, since a SIGINT would be ignored. Before, ``kill`` of such a job
    killed it mid-run: no STOP, no line, an MCAP without its footer."""
    from .. import interrupts

    _ended_by.append(signum)
    interrupts.terminate(signum, frame)


def _catch_termination() -> None:
    import threading

    from .. import interrupts

    if threading.current_thread() is not threading.main_thread():
        return  # main() called from another thread (a test): signals are the caller's
    sigint = signal.getsignal(signal.SIGINT)
    if sigint is signal.SIG_IGN:  # a background job: Ctrl-C stays ignored, SIGTERM still ends it whole
        handler = _terminate
        interrupts.take_terminations()
    elif sigint is signal.default_int_handler:
        handler = _as_ctrl_c
    else:
        return  # Ctrl-C taken by the caller: SIGTERM kills as before
    for name in ("SIGTERM", "SIGHUP"):
        sig = getattr(signal, name, None)
        if sig is not None and signal.getsignal(sig) in (signal.SIG_DFL, None):
            signal.signal(sig, handler)


def main(argv: Sequence[str] | None = None) -> int:
    try:
        _tolerant_streams()
        _catch_termination()
        argv = _hoist_verbosity(_join_signed_values(sys.argv[1:] if argv is None else list(argv)))
        args = build_parser().parse_args(argv)
        _setup_logging(args.verbose - args.quiet)
    except KeyboardInterrupt:  # before the command began: nothing to say but that
        _say("proleg: interrupted")
        return _interrupted_status()
    except BrokenPipeError:  # `proleg --help | head -1`: the reader went away, not an error
        _silence_stdout()
        return EXIT_OK
    except OSError as e:  # a --help or --version that could not be written (_Parser._print_message)
        _say(f"proleg: error: {os_error_line(e)}")
        _silence_stdout()
        return EXIT_FAILED
    try:
        code = args.run(args)
        sys.stdout.flush()
        return code
    except (LinkError, WorkerLost) as e:  # the robot, the link, a file to write or a worker process failed
        _say(f"proleg: error: {e}")
        return EXIT_FAILED
    except ProlegError as e:
        _say(f"proleg: error: {e}")
        return EXIT_USAGE
    except KeyboardInterrupt as e:  # Ctrl-C: one line, what was kept where the command says it
        _say(f"proleg: {e}" if isinstance(e, Interrupted) and str(e) else "proleg: interrupted")
        return _interrupted_status()
    except BrokenPipeError:  # the reader went away (`proleg … | head -1`): not an error
        _silence_stdout()
        return EXIT_OK
    except OSError as e:  # a full disk, a vanished directory... while writing an output
        _say(f"proleg: error: {os_error_line(e)}")
        _silence_stdout()
        return EXIT_FAILED
    finally:  # the handler stays for what runs after main in this process (a script, a test): all of it said
        for handler in log.handlers:
            for f in [f for f in handler.filters if isinstance(f, _SaidOnce)]:
                handler.removeFilter(f)


def _say(line: str) -> None:
    """The command's last line on stderr. A terminal closed under it (SIGHUP: the tty answers EIO)
    must not turn the exit status (129) into 1 with a traceback nobody sees."""
    try:
        print(line, file=sys.stderr, flush=True)
    except OSError:
        pass


def interruption() -> str:
    """What interrupted the command, for its last line: ``Ctrl-C``, or ``SIGTERM``/``SIGHUP``
    (delivered as a Ctrl-C; a line saying "paused by Ctrl-C" after a ``kill`` misled)."""
    return signal.Signals(_ended_by[0]).name if _ended_by else "Ctrl-C"


def _interrupted_status() -> int:
    """130 for Ctrl-C; 128 + the signal for SIGTERM or SIGHUP (the shell's convention)."""
    return 128 + _ended_by[0] if _ended_by else 130


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


class _StderrHandler(logging.StreamHandler):
    """A handler on whatever ``sys.stderr`` is when a line is logged, not on the stream it was
    at setup (as logging's own last resort): ``main`` called again in one process (the tests,
    a lab's script) with stderr replaced in between wrote later lines to a closed stream
    ("--- Logging error --- I/O operation on closed file")."""

    def __init__(self) -> None:
        super().__init__(sys.stderr)

    @property
    def stream(self):  # type: ignore[override]
        return sys.stderr

    @stream.setter
    def stream(self, _value) -> None:
        pass


class _SaidOnce(logging.Filter):
    """Each warning once per command: one made again by every plant a command makes (``sim
    --measure-climb``'s grades, ``check``'s rows) was printed again with each, word for word."""

    def __init__(self) -> None:
        super().__init__()
        self.said: set[str] = set()

    def filter(self, record: logging.LogRecord) -> bool:
        if record.levelno != logging.WARNING:
            return True
        text = record.getMessage()
        if text in self.said:
            return False
        self.said.add(text)
        return True


def _setup_logging(verbosity: int) -> None:
    """-v: debug; default: info (progress); -q: warnings only; -qq: errors only. A warning is
    said once per command (``_SaidOnce``)."""
    level = {1: logging.DEBUG, 0: logging.INFO, -1: logging.WARNING}.get(verbosity, logging.DEBUG if verbosity > 0
                                                                      else logging.ERROR)
    handler = _StderrHandler()
    handler.addFilter(_SaidOnce())
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


class _Parser(argparse.ArgumentParser):
    """argparse, but ``--option=--`` is a usage error: Python 3.11's argparse drops the ``--``
    and hands the option an empty list without its ``type`` (``sim --duration=--`` ran into a
    TypeError traceback, and ``--max-transitions=--`` said "got []")."""

    def _print_message(self, message: str, file: Any = None) -> None:
        """argparse's, but a help or version on stdout that cannot be written (a full disk) fails
        the command: argparse swallows the OSError, and `proleg --help > /dev/full` was an exit 0
        with nothing written and nothing said. What goes to stderr stays argparse's (there is no
        one left to tell)."""
        if not message:
            return
        if file is None or file is sys.stderr:
            super()._print_message(message, file)
            return
        file.write(message)
        file.flush()

    def _get_values(self, action: argparse.Action, arg_strings: list[str]) -> Any:
        if action.option_strings and arg_strings == ["--"] and action.nargs is None:
            raise argparse.ArgumentError(action, "expected a value, got '--'")
        return super()._get_values(action, arg_strings)


def build_parser() -> argparse.ArgumentParser:
    p = _Parser(prog="proleg", description="Gaits, firmware and simulation for soft crawling robots.",
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

    from .sim_command import add_sim_parser

    add_sim_parser(sub)

    from .link_commands import add_arguments as add_link_commands
    from .robot_commands import add_arguments as add_robot_commands

    add_link_commands(sub)  # console, plot, dbc
    add_robot_commands(sub)  # run, load-gait, set-param, robots
    __import__("proleg.cli.learn", fromlist=["add_arguments"]).add_arguments(sub)  # learn
    __import__("proleg.cli.calibrate", fromlist=["add_arguments"]).add_arguments(sub)  # calibrate
    __import__("proleg.cli.check", fromlist=["add_arguments"]).add_arguments(sub)  # check
    return p


def add_udp_options(p: argparse.ArgumentParser) -> None:
    p.add_argument("--udp", metavar="HOST:PORT", help="stream every telemetry frame over UDP to PlotJuggler or Teleplot")
    p.add_argument("--udp-format", choices=("plotjuggler", "teleplot"),
                   help="with --udp: plotjuggler: one JSON object per datagram (default); teleplot: "
                        ">name:timestamp_ms:value lines")


def udp_options(args: argparse.Namespace) -> tuple[UdpEndpoint | None, str]:
    """(``--udp`` endpoint, resolved, or None; ``--udp-format``); ``--udp-format`` without
    ``--udp`` is a UsageError (it would be ignored), and the endpoint is parsed and its host
    resolved here, before anything is opened (``record.udp.resolve_endpoint``)."""
    from ..errors import UsageError
    from ..record.udp import resolve_endpoint

    if args.udp is None:
        if args.udp_format is not None:
            raise UsageError("--udp-format: only with --udp HOST:PORT (it is the format of that stream)")
        return None, "plotjuggler"
    if isinstance(args.udp, str):
        return resolve_endpoint(args.udp), args.udp_format or "plotjuggler"
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


#: ``proleg build`` prints this many of the gaits' problems, then how many more (``-v``: all).
BUILD_WARNINGS_SHOWN = 6


def _firmware_request(args: argparse.Namespace, board=None):
    """(robot, board, library) of a build or flash, with what the command line itself must get
    right checked: the output's folder, the speed objective's durations, ``--library``."""
    from ..firmware.boards import load_board
    from ..robot import load_robot

    if args.out is not None and not Path(args.out).parent.is_dir():
        from ..errors import UsageError  # as every command's output: the folder it goes in must exist

        raise UsageError(f"-o {args.out}: directory {Path(args.out).parent} does not exist")
    robot = load_robot(args.robot)
    board = load_board(args.board) if board is None else board
    from .gait import check_speed_objective

    check_speed_objective(robot, args.objective)
    library = None
    if getattr(args, "library", None):
        from ..gait.library import library_spec

        library = library_spec(args.library, **(robot.library.as_kwargs() if robot.library is not None else {}))
    return robot, board, library


def _build(args: argparse.Namespace):
    from ..firmware.build import build

    robot, board, library = _firmware_request(args)
    result = build(robot, board, args.out, objective=args.objective, max_transitions=args.max_transitions,
                   library=library)
    print(f"built {robot.name} for {board.name}: {result.artifact}")
    print(f"  {result.size_report()}")
    if result.fit is not None:
        for line in result.fit.lines():
            print(f"  {line}")
    shown = result.warnings if args.verbose > 0 else result.warnings[:BUILD_WARNINGS_SHOWN]
    for line in shown:
        print(f"proleg: warning: {line}", file=sys.stderr)
    if len(shown) < len(result.warnings):  # a robot with tens of tied gaits, each with its problems
        print(f"proleg: warning: … and {len(result.warnings) - len(shown)} more like these (-v shows them; "
              f"proleg gait {args.robot} --json lists every gait's problems)", file=sys.stderr)
    for d, gaits in result.gaits.items():
        shown = "; ".join(" ".join(robot.transitions.label(s) for s in g.states) for g in gaits) or "none"
        if d in getattr(result.gaits, "left_out", {}):
            shown += " (left out: the hardware cannot make its optimal gaits, warned above)"
        elif not gaits and getattr(result.gaits, "unmeasured", False):
            shown += " (the matrix is unmeasured: learn or measure it, warned above)"
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
    from ..firmware.flash import check_tool, choose_method, flash, flash_command

    board = load_board(args.board)
    method = choose_method(board, args.tool, args.port)
    if args.dry_run:  # builds nothing, but names what the build would refuse (the robot file, the board, the
        # command line, the gaits' tables: everything the build checks before it compiles)
        from ..firmware.build import check_board_takes, check_tick_budget, default_out_dir, plan_build
        from ..firmware.fit import check_i2c_ticks, check_ram

        robot, board, library = _firmware_request(args, board)
        check_board_takes(robot, board)
        check_tick_budget(robot, board)
        check_i2c_ticks(robot, board)
        check_ram(robot, board)
        out = Path(args.out) if args.out else default_out_dir(robot, board)
        plan_build(robot, board, out, args.objective, args.max_transitions, library)
        print(shlex.join(flash_command(method, out / board.artifact, args.port)))
        return 0
    check_tool(method, args.port)  # a missing --port, tool or port fails before building
    result = _build(args)
    flash(method, result.artifact, args.port)
    print(f"flashed {result.artifact} with {method.tool}")
    return 0
