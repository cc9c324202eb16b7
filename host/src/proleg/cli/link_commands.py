"""``proleg console``, ``proleg plot`` and ``proleg dbc`` (the CLI stays thin).

``add_arguments(subparsers)`` adds them to the one parser (``proleg.cli.main``); each sets ``run`` to a
function taking the parsed namespace, which calls ``console_main`` / ``plot_main`` /
``dbc_main`` with plain parameters. Errors are ``LinkError`` (or the robot/sim loaders'
``ProlegError``): one line, no traceback, no half-written output file.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any, TextIO

from .. import interrupts
from ..errors import LinkError
from ..link.client import RobotClient
from ..link.factory import link_url, open_link
from ..link.serial_link import DEFAULT_BAUDRATE
from .number_args import baudrate, can_bitrate, can_node, int_auto, positive_float

if TYPE_CHECKING:
    from ..record.udp import UdpEndpoint


def console_main(*, port: str | None = None, can_channel: str | None = None, interface: str | None = None,
                 node: int = 0, sim: str | None = None, robot_file: str | None = None, baudrate: int = DEFAULT_BAUDRATE,
                 record: str | None = None, plain: bool = False, duration_s: float | None = None,
                 timeout: float = 0.5, out: TextIO | None = None, fmt: str = "text",
                 udp: str | UdpEndpoint | None = None, udp_format: str = "plotjuggler", bitrate: int | None = None,
                 force: bool = False, leave_running: bool = False, err: TextIO | None = None,
                 replan: bool = True, inject: Sequence[str] = ()) -> int:
    """``proleg console``. ``plain`` (or a non-terminal stdout) prints one line per frame
    (``fmt="jsonl"``: one JSON object per frame, the recordings' field names); ``udp`` streams
    every frame to PlotJuggler or Teleplot.

    With ``robot_file`` the board's INFO must match it (robot name, gait table hash, build id;
    ``force`` overrides). Leaving — q, Ctrl-C, the window closed, the link lost, ``duration_s``
    over — sends STOP (ESTOP if unacknowledged) unless ``leave_running``; what happened is
    written to ``err``.

    ``replan`` (with a robot file, or the simulated robot's): after a limb loss, load and
    start the best gait of what the robot can still do (``proleg.console.replan``), telling
    each step. ``inject`` (simulator only): faults ``FAULT[+T]`` injected T simulated seconds
    after the start (``proleg.console.inject``)."""
    from ..console import ConsoleApp, LimbView, RobotNames, run_plain
    from ..console.plain import replan_state
    from ..console.inject import Injector, fault_checker, parse_injection
    from ..console.identity import check_identity
    from ..console.replan import ReplanWorker
    from ..errors import SimError
    from ..interrupts import hangup_as_exception
    from ..link.leave import stop_robot
    from ..link.listeners import FaultWatch
    from ..record import JsonlPrinter, Logger, RecordingMeta, UdpStreamer, check_suffix
    from ..record.udp import resolve_endpoint

    if record is not None:
        check_suffix(record)  # reject an unknown extension before opening anything
    if isinstance(udp, str):
        udp = resolve_endpoint(udp)  # a host that resolves to nothing: said before the link opens
    try:
        timed = [parse_injection(spec, duration_s) for spec in inject]  # a mistake fails before anything is opened
    except SimError:
        # unless the spec names a limb or coil whole ("dead-actuator:leg+2" with --duration 1 was refused
        # as "2 s is after the run ends"): on a simulator, parsed again below with the robot's names
        if sim is None and not (port or "").startswith("sim:"):
            raise
        timed = [(0.0, spec) for spec in inject]
    out = out or sys.stdout
    err = err or sys.stderr
    robot = None
    if robot_file is not None:
        from ..robot import load_robot

        robot = load_robot(robot_file)
    link = open_link(link_url(port=port, can_channel=can_channel, interface=interface, node=node, sim=sim,
                              bitrate=bitrate), baudrate=baudrate, speed=1.0, robot_file=robot_file)
    if robot is None:
        robot = getattr(getattr(link, "board", None), "robot", None)  # the simulated robot's description
    if timed and not hasattr(getattr(link, "board", None), "inject"):
        link.close()
        raise SimError("--inject needs --sim ROBOT (faults are injected into the simulated robot)")
    try:
        if timed:  # again with the robot's names: a limb called "leg+2" is no time
            names_fault = fault_checker(link.board.check_fault)  # type: ignore[attr-defined]
            timed = [parse_injection(spec, duration_s, names_fault) for spec in inject]
        for _, fault in timed:
            link.board.check_fault(fault)  # type: ignore[attr-defined]  # a bad name fails now, not mid-run
    except SimError:
        link.close()
        raise
    app: ConsoleApp | None = None

    def hang_up() -> None:
        if app is not None and app.is_running:
            # only a flag: the UI leaves on its next refresh. app.exit() from the signal handler ran
            # textual's code inside textual's own (a terminal write holding its output queue), and
            # the console hung for ever after its window was closed, pinging the board: the gait ran on
            app.leave_requested = True
        else:
            raise KeyboardInterrupt

    def tell(text: str) -> None:
        """One line on ``err``; a terminal that is gone (SIGHUP: EIO) does not stop the leaving."""
        try:
            print(text, file=err, flush=True)
        except OSError:
            pass

    watchdog_ms = robot.safety.link_watchdog_ms if robot is not None else None
    recorder = None
    with hangup_as_exception(hang_up) as ended_by, \
            RobotClient(link, timeout=timeout, watchdog_ms=watchdog_ms) as client:
        info = client.connect()
        if robot is not None:
            for problem in check_identity(info, robot, force=force, link=link.description):
                print(f"proleg: warning: --force: {problem}", file=err)
        faulted = FaultWatch()
        listeners: list = [faulted]
        try:
            meta = RecordingMeta.for_robot(info=info, robot=robot, link=link)
            if record is not None:
                with interrupts.whole():  # a Ctrl-C in between: the recording is already ours to close
                    recorder = Logger(record, meta)
                    listeners.append(recorder)
            if udp is not None:
                listeners.append(UdpStreamer(udp, udp_format, meta))
            levels = robot.levels if robot is not None else (2,) * info.limbs
            if plain or fmt == "jsonl" or not out.isatty():
                from ..states import label, state_count

                def say(text: str) -> None:
                    print(f"proleg: {text}", file=err, flush=True)

                if robot is not None:  # without a robot file there is nothing to replan with: stay quiet
                    say(replan_state(replan, True))
                listeners.append(_reset_watch(say))
                if timed:
                    listeners.append(Injector(link.board, timed, say, marks=listeners))  # type: ignore[attr-defined]
                if replan and robot is not None:
                    listeners.append(ReplanWorker(robot, client, say))
                if fmt == "jsonl":
                    listeners.append(JsonlPrinter(meta, out, telemetry_only=False))
                try:
                    run_plain(client, listeners=listeners, out=out, duration_s=duration_s, quiet=fmt == "jsonl",
                              keep_open=_takers(listeners),
                              labels=lambda s: label(s, levels) if s < state_count(levels) else str(s))
                except KeyboardInterrupt:
                    pass  # Ctrl-C ends the plain mode like the duration does
            else:
                limbs = [LimbView(limb.name, limb.psi_star_deg) for limb in robot.limbs] if robot is not None else []
                app = ConsoleApp(client, limbs=limbs, levels=levels, listeners=listeners,
                                 names=RobotNames.for_robot(robot), robot=robot, replan=replan,
                                 duration_s=duration_s)
                if timed:
                    app.extra_listeners.append(Injector(link.board, timed, app.host_says, marks=listeners))  # type: ignore[attr-defined]
                app.keep_open = _takers(listeners)
                app.run()
                if app.model.link_error is not None:
                    raise app.model.link_error
        finally:
            try:
                if not leave_running:
                    tell(f"proleg: {stop_robot(client)} on {link.description}")
                    _hand_on_the_stop(client, listeners)
                elif robot is None or robot.safety.link_watchdog_ms:
                    after = ("its link_watchdog_ms (2000 unless its robot file says otherwise)" if robot is None
                             else f"{robot.safety.link_watchdog_ms} ms")
                    print(f"proleg: left running on {link.description}: the firmware's link watchdog stops it "
                          f"{after} after the last frame from a host (a run to detach from needs firmware built "
                          "with [safety] link_watchdog_ms = 0)", file=err)
            finally:
                for listener in listeners:  # also those a Ctrl-C before the session left open
                    listener.stop()  # (a recording gets its MCAP footer; stopping twice is nothing)
        errors = [w.error for w in listeners if getattr(w, "error", None)]
        if errors:
            raise errors[0]
    if ended_by:  # SIGTERM (kill, a CI job's timeout) or SIGHUP: not a way to leave, as Ctrl-C and q are
        import signal

        from ..record.base import what_was_kept

        tell(f"proleg: ended by {signal.Signals(ended_by[0]).name}; {what_was_kept(recorder)}")
        return 128 + ended_by[0]
    if faulted.first is not None:  # exit 1: the robot faulted (README, "Exit status")
        what = "a fault was latched" if faulted.first == "latched" else f"fault {faulted.first}"
        print(f"proleg: the robot faulted during the console session ({what})", file=err)
        return 1
    return 0


def _takers(listeners: Sequence[Any]) -> list[Any]:
    """The recording and the streams: open until the leaving STOP has been handed on to them."""
    from ..record import JsonlPrinter, UdpStreamer
    from ..record.base import Writer

    return [w for w in listeners if isinstance(w, (Writer, JsonlPrinter, UdpStreamer))]


def _hand_on_the_stop(client: Any, listeners: Sequence[Any]) -> None:
    """The STOP's ACK and the firmware's GAIT_STOPPED come after the session's Notifier stopped:
    hand them (and the frames with them) to the recording and the streams, as ``proleg run`` does,
    else a recording of a session left with a gait running ended on it running. Not to the
    replanner or the injector: the session is over. A link that fails meanwhile ends it."""
    from ..report.robot_run import STOP_TAIL_S  # as long as proleg run reads after its STOP

    takers = _takers(listeners)
    if not takers:
        return
    clock = client.link.clock
    deadline = clock() + STOP_TAIL_S
    try:
        while (remaining := deadline - clock()) > 0:
            rx = client.recv_received(remaining)
            if rx is not None:
                for taker in takers:
                    taker.on_message(rx)
    except (LinkError, OSError, KeyboardInterrupt):
        pass  # the robot was stopped (or could not be, as said): the tail is not worth more


def _reset_watch(say: Any) -> Any:
    """A listener that says when the board resets mid-session (a BOOT event after telemetry): the
    plain lines showed only the board's clock starting again, and a gait it had stopped by
    rebooting went unmentioned."""
    from ..console.names import event_text
    from ..link.listeners import CallbackListener
    from ..protocol.definition import EventKind

    seen: list[bool] = []  # telemetry came: a BOOT from now on is a reset, not the board's first

    def on_message(rx: Any) -> None:
        m = rx.message
        if m.name == "TELEMETRY":
            if not seen:
                seen.append(True)
        elif m.name == "EVENT" and m.fields["kind"] == EventKind.BOOT and seen:
            say(f"the board reset: {event_text(m.fields)}; it boots idle (a gait it ran is stopped)")

    return CallbackListener(on_message)


def plot_main(*, record_file: str, out: str, title: str | None = None) -> int:
    """``proleg plot FILE -o OUT.png``."""
    from ..outputs import note_stream
    from ..plot import plot_recording

    path = plot_recording(record_file, out, title=title)
    print(f"wrote {path}", file=note_stream(path))
    return 0


def dbc_main(*, out: str, nodes: Sequence[int] = (0,), base: int = 0x100, robot_file: str | None = None) -> int:
    """``proleg dbc -o FILE [--robot ROBOT]`` (the robot names the ψ and duty signals)."""
    from ..outputs import note_stream, refuse_inputs
    from ..protocol.dbc import write_dbc

    refuse_inputs("dbc", "-o", out, {"--robot": robot_file})
    robot = None
    if robot_file is not None:
        from ..robot import load_robot

        robot = load_robot(robot_file)
    if out == "-":  # standard output, as the usual convention has it (it made a file named "-")
        from ..protocol.dbc import dbc_text

        sys.stdout.write(dbc_text(nodes, base, robot))
        return 0
    path = write_dbc(out, nodes, base, robot)
    print(f"wrote {path} ({len(nodes)} node(s), base id {base:#x})", file=note_stream(path))
    return 0


# --------------------------------------------------------------------------- argparse
CONSOLE_EPILOG = """\
Leaving (q, Ctrl-C, the window closed, the link lost, --duration over, SIGTERM) sends STOP,
ESTOP if it is not acknowledged, unless --leave-running; a recording is closed whole.

exit status:
  0    left with q, Ctrl-C or at the end of --duration
  1    failed: the link was lost or a command failed, the robot faulted during the session,
       a recording could not be written, the board does not run the --robot file's firmware
  2    usage: a bad argument, a robot file that does not load
  143  ended by SIGTERM (kill, a CI job's timeout), after the robot was stopped
  129  ended by SIGHUP (a closed terminal), after the robot was stopped
"""

def _robot(text: str) -> str:
    from .main import robot_arg

    return robot_arg(text)


def _console(a: Any) -> int:
    from .main import udp_options
    from .robot_link import link_settings

    link, (udp, udp_format) = link_settings(a), udp_options(a)
    return console_main(
        port=a.port, can_channel=a.can, interface=link["interface"], node=link["node"], sim=a.sim, robot_file=a.robot,
        baudrate=link["baudrate"], record=a.record, plain=a.plain, duration_s=a.duration, fmt=a.format,
        udp=udp, udp_format=udp_format, bitrate=link["bitrate"], force=a.force, leave_running=a.leave_running,
        replan=a.replan, inject=a.inject)


def add_arguments(subparsers: Any) -> None:
    """Add ``console``, ``plot`` and ``dbc`` to the CLI's subparsers."""
    from .main import add_udp_options

    c = subparsers.add_parser("console", help="live console (or --plain lines) on a robot over serial, CAN or the simulator",
                              epilog=CONSOLE_EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    src = c.add_mutually_exclusive_group(required=True)
    src.add_argument("--port", metavar="URL", help="serial port or pyserial URL: /dev/ttyUSB0, COM3, socket://host:port, loop://")
    src.add_argument("--can", metavar="CHANNEL", nargs="?", const="",
                     help="CAN channel (python-can), e.g. can0; alone: CAN_CHANNEL or ~/.canrc's channel")
    src.add_argument("--sim", metavar="ROBOT", type=_robot, help="run the robot's firmware on the simulated board")
    c.add_argument("--interface", help="python-can interface for --can (default: CAN_INTERFACE or ~/.canrc, "
                                       "else socketcan)")
    c.add_argument("--bitrate", type=can_bitrate, metavar="BIT/S",
                   help="with --can: CAN bit rate (default: CAN_BITRATE or ~/.canrc)")
    c.add_argument("--node", type=can_node, help="with --can: CAN node id of the robot, 0..15 (default 0)")
    c.add_argument("--baudrate", type=baudrate, help=f"with --port: serial baud rate (default {DEFAULT_BAUDRATE})")
    c.add_argument("--robot", metavar="ROBOT", type=_robot, help="robot file for limb names and ψ* (with --port/--can)")
    c.add_argument("--record", metavar="FILE", help="record every frame to FILE (.csv, .jsonl or .mcap)")
    c.add_argument("--plain", action="store_true", help="print one line per telemetry frame instead of the UI")
    c.add_argument("--format", choices=("text", "jsonl"), default="text",
                   help="with --plain: text lines, or one JSON object per message for scripts")
    add_udp_options(c)
    c.add_argument("--duration", type=positive_float, metavar="S",
                   help="leave after S seconds (the robot stopped as on q)")
    c.add_argument("--force", action="store_true",
                   help="connect even when the board's INFO does not match --robot (name, gait hash, build id)")
    c.add_argument("--leave-running", action="store_true",
                   help="do not STOP the robot when the console ends (default: STOP, ESTOP if unanswered)")
    c.add_argument("--no-replan", dest="replan", action="store_false",
                   help="do not replan after an actuator loss (default, with --robot or --sim: when a gait stops "
                        "on a fault naming an actuator, load and start the best gait of what the robot can "
                        "still do; docs/learning.md)")
    c.add_argument("--inject", action="append", default=[], metavar="FAULT",
                   help="with --sim: inject a fault, optionally T simulated seconds after the start "
                        "(e.g. dead-actuator:sma-right+10; the names of proleg sim --inject; T at most --duration)")
    c.set_defaults(run=_console)

    p = subparsers.add_parser("plot", help="plot a recording: ψ vs ψ*, states, SMA duty, displacement")
    p.add_argument("record_file", metavar="FILE", help="recording (.csv, .jsonl or .mcap) from --record")
    p.add_argument("-o", "--out", required=True, metavar="OUT.png", help="image to write (.png, .svg, .pdf)")
    p.add_argument("--title")
    p.set_defaults(run=lambda a: plot_main(record_file=a.record_file, out=a.out, title=a.title))

    d = subparsers.add_parser("dbc", help="write a DBC file describing the robot's CAN frames")
    d.add_argument("-o", "--out", required=True, metavar="FILE.dbc", help="the DBC file to write (- for standard output)")
    d.add_argument("--node", type=can_node, action="append", metavar="N",
                   help="robot node id(s) on the bus (repeatable; default 0)")
    d.add_argument("--base", type=int_auto, default=0x100, help="base CAN id (default 0x100)")
    d.add_argument("--robot", metavar="ROBOT", type=_robot, help="name ψ and duty signals after its limbs and actuators")
    d.set_defaults(run=lambda a: dbc_main(out=a.out, nodes=a.node or [0], base=a.base, robot_file=a.robot))
