"""``proleg sim``: its parser, the run (the robot's firmware on a simulated board in closed
loop with its plant, or served on a pty with ``--pty``) and the report it prints (text or
``--json``). The plant options and the measurements (``--plant``, ``--condition``,
``--measure-matrix``, ``--measure-climb``, ``--calibrated``) are in ``sim_plant``; this module
only runs what they set up. Exit codes as in ``main``.
"""

from __future__ import annotations

import argparse
import json
import sys

from ..names import counted
from .main import EXIT_FAILED, EXIT_OK, add_udp_options, robot_arg, udp_options
from .number_args import MAX_SIM_S, gait_number, max_transitions, positive_float, speed_factor
from .. import interrupts
from ..report.matrix_check import check, remark_text

def add_sim_parser(sub) -> None:
    """Add ``proleg sim`` to the one parser's subcommands."""
    s = sub.add_parser("sim", help="run the robot's firmware on the simulated board, in closed loop with its plant")
    s.add_argument("robot", metavar="ROBOT", type=robot_arg)
    s.add_argument("--duration", type=positive_float, default=None, metavar="S",
                   help=f"simulated seconds (default 60, at most {MAX_SIM_S:g}; with --pty: until Ctrl-C)")
    s.add_argument("--gait", type=gait_number, default=0, metavar="N", help="gait index in the firmware's table (default 0)")
    s.add_argument("--direction", choices=("+x", "-x"), default="+x")
    add_sim_board_options(s)
    s.add_argument("--inject", action="append", default=[], metavar="FAULT",
                   help="fault to inject, optionally at a time: imu-silent:LIMB, imu-stuck:LIMB, imu-garbage:LIMB, "
                        "dead-actuator:ACTUATOR, drift[:ACTUATOR][@RATE], link-drop[:P], link-corrupt[:P] (a LIMB or "
                        "ACTUATOR by name, spaces at its ends not counting, a LIMB by index, an ACTUATOR by channel "
                        "or its limb's name, or rear/front where no limb or coil has that name: the first/last limb, "
                        "or its coil, as --condition reads them); "
                        "append +T for T simulated seconds after the start, at most --duration (e.g. dead-actuator:sma-right+10)")
    s.add_argument("--seed", type=int, default=1)
    s.add_argument("--record", metavar="FILE", help="record every frame (.csv, .jsonl or .mcap)")
    add_udp_options(s)
    s.add_argument("--json", action="store_true", help="print the report as one JSON object")
    s.add_argument("--pty", action="store_true",
                   help="serve the simulated board on a pseudo-terminal in real time instead (for proleg console)")
    s.add_argument("--speed", type=speed_factor, default=1.0, help="with --pty: times real time (default 1, at least 0.001)")
    from .sim_plant import add_plant_options

    add_plant_options(s)  # --plant, --condition, --measure-matrix
    s.set_defaults(run=cmd_sim)


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


def cmd_sim(args: argparse.Namespace) -> int:
    from ..report import SimSession
    from ..robot import load_robot
    from ..firmware.gaits import firmware_gaits
    from ..sim.simulators import open_simulated
    from ..sim.simulated_boards import clear_ticks, tick_budget

    robot = load_robot(args.robot)
    from .sim_plant import (calibrate_then_put_down, cmd_measure_climb, cmd_measure_matrix, conditions_json,
                            flat_conditions, plant_kwargs, refuse_what_does_not_apply, wants_help)

    refuse_what_does_not_apply(args)  # an option the mode would ignore is a mistake, not a no-op
    from .gait import check_speed_objective

    check_speed_objective(robot, args.objective)
    args.udp, args.udp_format = udp_options(args)
    pty_limit_s = args.duration  # --pty serves until Ctrl-C unless a duration is given
    if not args.pty and (args.duration or 0) > MAX_SIM_S:
        from ..errors import SimError

        raise SimError(f"--duration {args.duration:.12g}: expected at most {MAX_SIM_S:g} simulated seconds (an hour "
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
    if args.hold_range or args.history_range:
        from ..errors import SimError

        flag = "--hold-range" if args.hold_range else "--history-range"
        raise SimError(f"{flag}: it is an option of --measure-matrix (measure the matrix "
                       f"{'at several hold margins' if args.hold_range else 'in several orders'})")
    if not args.pty:
        every = firmware_gaits(robot, args.objective, args.max_transitions)
        gaits = every.get(args.direction, ())
        have = len(gaits)
        if args.gait >= have:
            from ..errors import GaitError

            why = every.left_out_line(args.direction)
            if why is not None:  # the build leaves the direction out: say why, as the build did
                raise GaitError(f"--gait {args.gait} of {args.direction}: {robot.where}: {why}")
            from ..firmware.gaits import no_such_gait

            raise GaitError(no_such_gait(args.gait, robot.name, args.direction, {d: len(g) for d, g in every.items()}))
    if args.record and not args.pty:
        from ..record import check_suffix

        check_suffix(args.record)  # a folder that does not exist is a usage mistake: before the build
    plant = plant_kwargs(args)
    if args.calibrated:
        if args.pty:
            from ..errors import SimError

            raise SimError("--calibrated: not with --pty (calibrate through the pseudo-terminal: proleg calibrate)")
        plant["conditions"] = flat_conditions(args)  # calibrated on the flat, put down on the slope below
    try:
        sim = open_simulated(robot, args.board, seed=args.seed, objective=args.objective,
                             max_transitions=args.max_transitions, **plant)
    except KeyboardInterrupt:  # building or loading the simulated board's firmware
        from ..errors import Interrupted

        raise Interrupted("interrupted before the run started; nothing recorded") from None
    # --pty may be stopped early (Ctrl-C) and names what it did not inject; a plain run would not say
    timed, at_once = _injections(args.inject, None if args.pty else args.duration, sim.check_fault)
    for spec in [*at_once, *(fault for _, fault in timed)]:
        sim.check_fault(spec)  # a bad name fails now, not halfway through the run
    if not args.calibrated:
        for spec in at_once:
            sim.inject(spec)
    if args.pty:
        return _serve_pty(sim, args, timed, pty_limit_s)
    held = _Held()  # the boot messages, until the board's INFO has named its firmware
    recorder = None
    listeners: list = []
    start = None
    try:
        session = SimSession(sim, listeners=[held])
        booted = session.until_info(BOOT_S) if args.record or args.udp else 0.0
        if args.record:
            with interrupts.whole():  # a Ctrl-C in between: the recording is already ours to close
                recorder = _recorder(robot, args.record, session, args.board)
                listeners.append(recorder)
        if args.udp:
            from ..record import UdpStreamer

            listeners.append(UdpStreamer(args.udp, args.udp_format, _meta(robot, session, args.board)))
        for listener in listeners:
            for rx in held:
                listener.on_message(rx)
        session.listeners[:] = listeners
        session.advance(BOOT_S - booted)  # boot
        if args.calibrated:
            calibrate_then_put_down(session, sim, robot, args)
            for spec in at_once:  # on the plant the robot walks on
                sim.inject(spec)
        clear_ticks(sim)  # the tick budget is measured over the gait run
        start = sim.time_s
        for at, fault in timed:
            session.schedule_fault(start + at, fault)
        report = session.run_gait(args.direction, args.gait, args.duration)
    except KeyboardInterrupt:
        for listener in listeners:
            if start is None:  # before START: a recording of nothing is not kept (as proleg run)
                getattr(listener, "discard", listener.stop)()
            else:
                listener.stop()  # the recording is closed whole (an MCAP gets its footer)
        from ..errors import Interrupted

        raise Interrupted(_interrupted(sim, start, args.duration, None if start is None else recorder)) from None
    finally:
        for listener in listeners:
            listener.stop()
    budget = tick_budget(sim)
    # the run against what the matrix promises for its gait (report/matrix_check.py)
    agreement = check(robot, args.plant, gaits[args.gait].reward, report.cycle_displacements_mm,
                      len(gaits[args.gait].states) - 1)
    peaks = coil_peaks(robot, sim.plant)
    cooked = _overheated(peaks)  # a run that wears a coil out failed, as the claim bench counts it
    if args.json:
        out = {**_report_json(robot, report, args.board), **(budget or {}), **conditions_json(robot, args)}
        out["matrix_check"] = agreement.as_json() if agreement else None
        out["coil_peak_c"] = peaks
        out["errors"] = [*out["errors"], *cooked]
        print(json.dumps(out))
    else:
        print(_report_text(robot, report, args.board, budget))
        if agreement is not None and agreement.remark is not None:
            print(f"  {remark_text(agreement)}")
        print("\n".join(_peaks_text(peaks)))
    for e in [*report.errors, *cooked]:
        print(f"proleg: error: {e}", file=sys.stderr)
    if recorder is not None and recorder.error is not None:
        print(f"proleg: error: {recorder.error}", file=sys.stderr)
        return EXIT_FAILED
    return EXIT_OK if report.ok and not cooked else EXIT_FAILED


def _interrupted(sim, start: float | None, duration_s: float, recorder) -> str:
    """The one line a Ctrl-C'd run ends with: how far it got and what was kept."""
    when = ("before the run started" if start is None else
            f"{sim.time_s - start:.1f} s into the {duration_s:g} s run (simulated time)")
    from ..record.base import what_was_kept

    return f"interrupted {when}; {what_was_kept(recorder)}"


def _injections(specs: list[str], run_s: float | None,
                check_fault) -> tuple[list[tuple[float, str]], list[str]]:
    """``--inject`` as (timed: (T, FAULT) for FAULT+T, checked to fall within ``run_s``; at once: FAULT).
    ``check_fault``: the simulated robot's, which tells a name ending in ``+2`` from a time."""
    from ..console.inject import fault_checker, parse_injection

    names_fault = fault_checker(check_fault)
    timed: list[tuple[float, str]] = []
    at_once: list[str] = []
    for spec in specs:
        at, fault = parse_injection(spec, run_s, names_fault) if "+" in spec else (0.0, spec)
        if fault == spec:  # no +T (a limb called leg+2 or front+pad): at once, as any name without a '+'
            at_once.append(spec)  # (it went to START: imu-silent:leg+2 let the firmware boot, imu-silent:leg did not)
        else:
            timed.append((at, fault))
    return timed, at_once


def _serve_pty(sim, args, timed=(), limit_s: float | None = None) -> int:
    from ..sim.pty import PtyServer

    say = lambda line: print(line, flush=True)  # noqa: E731
    interrupted = False
    with PtyServer(sim, speed=args.speed, faults=timed, say=say) as server:
        print(f"simulated {sim.robot.name} on {server.path} (115200 8N1; Ctrl-C to stop)", flush=True)
        print(f"  connect with: proleg console --port {server.path}", flush=True)
        try:
            server.serve(limit_s)
        except KeyboardInterrupt:  # Ctrl-C, or SIGTERM/SIGHUP delivered as one (cli.main)
            interrupted = True
        for at, fault in server.due:  # never dropped silently
            print(f"proleg: not injected: {fault}+{at:g} (the simulation stopped at "
                  f"{server.elapsed_s:.1f} s)", file=sys.stderr)
    if interrupted:  # 130 (143, 129) as every command but console: a script sees it did not end by itself
        from ..errors import Interrupted

        raise Interrupted(f"interrupted after serving {server.elapsed_s:.1f} s (simulated) on {server.path}; "
                          "nothing recorded")
    return 0


#: virtual seconds the simulated board runs before the gait starts (its boot)
BOOT_S = 0.2


class _Held(list):
    """A listener keeping what the board sends until the recorders exist."""

    def on_message(self, rx) -> None:
        self.append(rx)

    def stop(self) -> None:
        pass


def _meta(robot, session, board: str):
    """A recording's metadata: the firmware's INFO (build id, gait-table hash, protocol
    version, rates; docs/data.md), the robot file's names, the simulated board as the link."""
    from dataclasses import replace

    from ..record import RecordingMeta

    info = session.client.info
    truth = tuple(session.link.truth())  # displacement_mm, then each coil's temp_<name>_c in the duties' order
    if info is None:  # no boot INFO (a board that never booted): what the robot file says
        return RecordingMeta.for_robot(robot=robot, board=board, truth=truth)
    meta = RecordingMeta.for_robot(info=info, robot=robot, truth=truth)
    return replace(meta, info={**meta.info, "link": f"simulated {board} board"})


def _recorder(robot, path: str, session, board: str):
    from ..record import Logger

    return Logger(path, _meta(robot, session, board))


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
        "telemetry_silent_s": round(report.telemetry_silent_s, 3),
        "link_errors": report.link_errors,
        "errors": report.errors,
    }


def coil_peaks(robot, plant) -> dict[str, float]:
    """Each coil's hottest in the simulated run, °C to 0.1, by the robot file's actuator names."""
    return {a.name: round(float(t), 1) for a, t in zip(robot.actuators, plant.peak_temperature_c)}


def _overheated(peaks: dict[str, float]) -> list[str]:
    """An error for each coil past the 120 °C that wears NiTi out: the firmware senses no
    temperature, so the run did what no fault reports (docs/safety.md)."""
    from ..physics.materials import NITI_OVERHEAT_C, shown_c

    return [f"coil {name} reached {shown_c(t)} °C in the simulated run, past the {NITI_OVERHEAT_C:.0f} °C that "
            f"wears NiTi out (no board senses it: docs/safety.md)" for name, t in peaks.items() if t > NITI_OVERHEAT_C]


def _peaks_text(peaks: dict[str, float]) -> list[str]:
    """The coils' hottest, and a WARNING for each past the 120 °C that wears NiTi out: the firmware
    senses no temperature, so only the simulator can tell (docs/safety.md)."""
    from ..physics.materials import NITI_OVERHEAT_C, shown_c

    lines = ["  coils, hottest: " + ", ".join(f"{name} {shown_c(t)} °C" for name, t in peaks.items())]
    lines += [f"  WARNING: coil {name} reached {shown_c(t)} °C, past the {NITI_OVERHEAT_C:.0f} °C that wears NiTi out"
              for name, t in peaks.items() if t > NITI_OVERHEAT_C]
    return lines


def _no_cycle_note(robot, report) -> list[str]:
    """A NOTE when the run completed no cycle and nothing went wrong (no fault, no error): why,
    where the robot file says it (a step's hold_ms), else where to look."""
    if report.cycles or report.faults or report.errors:
        return []
    hold_s = robot.control.hold_ms / 1000.0
    if 2 * hold_s >= report.duration_s:
        return [f"  NOTE: no cycle completed in {report.duration_s:g} s, and no fault: each step holds its state "
                f"control.hold_ms = {robot.control.hold_ms} ms once reached, so a cycle of two or more steps takes "
                f"at least {2 * hold_s:g} s; run longer (--duration) or shorten hold_ms"]
    return [f"  NOTE: no cycle completed in {report.duration_s:g} s, and no fault: a cycle may take longer than "
            f"this run (--duration), or the gait did not get round its steps (states reached above; --record FILE "
            f"shows each limb's ψ and duty)"]


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
    lines += _no_cycle_note(robot, report)
    errs = ", ".join(f"{k} {v}" for k, v in report.link_errors.items()) or "none"
    lines.append(
        f"  telemetry: {counted(report.telemetry_frames, 'frame')}, {report.lost_text()}; link errors: {errs}"
    )
    if budget is not None:
        period, busy = budget["tick_period_us"], budget["tick_busy_us"]
        lines.append(
            f"  tick busy (µs of a {period:g} µs tick, {busy['ticks']} ticks): mean {busy['mean']:g}, "
            f"p99 {busy['p99']:g} ({100 * busy['p99'] / period:.0f} %), max {busy['max']:g} "
            f"({100 * busy['max'] / period:.0f} %)"
        )
    return "\n".join(lines)

