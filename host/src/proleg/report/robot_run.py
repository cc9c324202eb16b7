"""Run a gait on any robot (serial, CAN, simulated) headless: ``proleg run``.

``run_gait_on(client, ...)`` STARTs the gait, hands every received message to the listeners
(recorders, UDP streamers, printers) and to a ``GaitRunListener`` for the report, reports
progress every ``progress_every_s`` seconds of the link's clock, STOPs (ESTOP when the STOP is
not acknowledged) and returns the ``GaitRun``: ``ok`` is False when a command failed or the
firmware reported a fault. Ctrl-C stops the robot the same way and raises ``RunInterrupted``
saying how far the run got and which command, if any, the robot acknowledged. ``check_gait``
refuses a gait index the robot does not have.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable

from ..errors import GaitError, Interrupted, LinkError
from ..link.client import RobotClient, RobotInfo
from ..link.direction import UNSTATED, direction_code
from ..link.listeners import Listener
from ..names import counted
from ..protocol.definition import GAIT_USER
from .gait_run import GaitRun, GaitRunListener

COMMAND_RETRIES = 2
#: how long after a STOP the link is still read, its ACK and the firmware's GAIT_STOPPED handed
#: to the recording and streams (run, and the console leaving a gait running)
STOP_TAIL_S = 0.1
#: how long ``run_gait_on`` waits, before START, for a telemetry frame whose measured state is
#: known: a board just reset (opening a Nano's port resets it) refuses START until it has read
#: every IMU, then picks the gait's step, or its entry path from rest, from that state
KNOWN_STATE_WAIT_S = 2.0
_EPS = 1e-9


class RunInterrupted(Interrupted):
    """Ctrl-C during ``run_gait_on``, raised once the robot was told to stop: the run so far
    (``run``), the seconds it ran on the link's clock (``ran_s``), whether the robot had
    acknowledged START (``started``) and the command that stopped it, STOP or ESTOP (``stopped``;
    None when neither was acknowledged). The caller says it in a line with what it kept."""

    def __init__(self, run: GaitRun, ran_s: float, started: bool, stopped: str | None):
        super().__init__(f"interrupted {ran_s:.1f} s into the run; " + stop_text(stopped))
        self.run, self.ran_s, self.started, self.stopped = run, ran_s, started, stopped


def stop_text(stopped: str | None, watchdog_ms: int | None = None) -> str:
    """What the robot was left doing after a Ctrl-C, from the command it acknowledged
    (``watchdog_ms``: the robot file's ``[safety] link_watchdog_ms``, when known)."""
    if stopped == "STOP":
        return "STOP acknowledged: the gait is stopped and the coils are off"
    if stopped == "ESTOP":
        return ("STOP unanswered, ESTOP acknowledged: the coils are off and the E-stop stays latched until a "
                "CLEAR (proleg console)")
    if watchdog_ms == 0:
        return ("neither STOP nor ESTOP was acknowledged and the firmware has no link watchdog ([safety] "
                "link_watchdog_ms = 0): the coils may still be on, switch the robot's power off")
    within = "its [safety] link_watchdog_ms" if watchdog_ms is None else f"{watchdog_ms} ms"
    return (f"neither STOP nor ESTOP was acknowledged: the board's link watchdog stops the gait and turns the "
            f"coils off within {within} of the last frame")


def check_gait(info: RobotInfo, gait: int, direction: str, per_direction: dict[str, int] | None = None,
               left_out: str | None = None) -> None:
    """``GaitError`` when gait ``gait`` does not exist: beyond INFO's count of compiled gaits,
    or (when the robot file is known) beyond the gaits in ``direction``; ``left_out``: why the
    build carries none in ``direction`` (``FirmwareGaits.left_out_line``), said instead."""
    if gait == GAIT_USER:
        return
    if per_direction is not None and not 0 <= gait < per_direction.get(direction, 0):
        if left_out is not None:
            raise GaitError(f"--gait {gait} of {direction}: {info.robot_name}: {left_out}")
        from ..firmware.gaits import no_such_gait

        raise GaitError(no_such_gait(gait, info.robot_name, direction, per_direction))
    if gait < 0 or gait >= info.gaits:  # without the robot file: INFO counts both directions' gaits
        have = f"at most {counted(info.gaits, 'gait')} in a direction" if info.gaits else "no gaits"
        raise GaitError(f"--gait {gait}: {info.robot_name} has {have} (INFO reports {info.gaits} compiled gaits "
                        "in all; give the robot file with --robot for the count in each direction)")


def run_gait_on(
    client: RobotClient,
    gait: int,
    direction: str,
    duration_s: float,
    *,
    listeners: Iterable[Listener] = (),
    progress: Callable[[str], None] | None = None,
    progress_every_s: float = 1.0,
    replanner: Listener | None = None,
) -> GaitRun:
    """``replanner`` (proleg.learn.replan.Replanner): sees every message and is polled
    between them, so it can carry the gait on after an actuator loss."""
    info = client.info
    run = GaitRun(info.robot_name if info else "", direction, gait, duration_s)
    report = GaitRunListener(run)
    targets = [*listeners, report] + ([replanner] if replanner is not None else [])
    clock = client.link.clock

    def pump(seconds: float, report_progress: bool = True) -> None:
        deadline = clock() + seconds
        next_progress = clock() + progress_every_s
        while True:
            remaining = deadline - clock()
            if remaining <= _EPS:
                return
            rx = client.recv_received(min(remaining, progress_every_s))
            if rx is not None:
                for listener in targets:
                    listener.on_message(rx)
            if replanner is not None:
                replanner.poll()  # type: ignore[attr-defined]
            if report_progress and progress is not None and clock() >= next_progress - _EPS:
                # one line however many periods a stalled loop missed; the next on the same period grid
                missed = math.floor((clock() - next_progress) / progress_every_s + _EPS)
                next_progress += (max(0, missed) + 1) * progress_every_s
                progress(f"{clock() - t0:6.1f} s: {counted(run.telemetry_frames, 'frame')}, "
                         f"{counted(max(0, len(run.states_reached)), 'state')} reached, "
                         f"{counted(len(run.faults), 'fault')}")

    def command(name: str, **fields: int) -> bool:
        try:
            client.request(name, retries=COMMAND_RETRIES, **fields)
            return True
        except LinkError as e:
            run.errors.append(f"{name} failed: {e}")
            return False

    client.wait_known_state(KNOWN_STATE_WAIT_S)  # queued for pump: the listeners get them in order
    lost_before = client.stats.lost  # the run's own losses: the link's count runs from connecting
    t0 = clock()
    started = False
    try:
        if command("START", gait=gait, direction=direction_code(direction, gait)):
            started = True
            if progress is not None:
                what = "the loaded gait" if gait == GAIT_USER else f"gait {gait}"
                way = "its way unstated" if direction == UNSTATED else f"in {direction}"
                progress(f"started {what} {way} for {duration_s:g} s on {client.link.description}")
            pump(duration_s)
        else:
            run.duration_s = 0.0  # it never ran
    except KeyboardInterrupt:  # also while START waited for its ACK: the board may have started
        ran_s = clock() - t0
        stopped = _stop_after_ctrl_c(command)
        if stopped is not None:
            # as after a run's end: the STOP's ACK and GAIT_STOPPED (queued while STOP waited) reach the
            # recording, which otherwise ended on a running gait with no word of its stop
            try:
                pump(STOP_TAIL_S, report_progress=False)
            except KeyboardInterrupt:
                pass  # a second Ctrl-C: the robot is already stopped, the tail is not worth waiting for
        raise RunInterrupted(run, ran_s, started, stopped) from None
    t_stop = clock()
    if not command("STOP"):
        command("ESTOP")  # the coils must go cold whatever the link does
    pump(STOP_TAIL_S - (clock() - t_stop), report_progress=False)  # the run's lines end with it
    run.telemetry_lost = client.stats.lost - lost_before
    # the board's rate, as SimSession takes the robot file's: with under two frames there is no interval to measure
    run.end_silence(t0, clock(), client.info.telemetry_hz if client.info is not None else None)
    return run


def _stop_after_ctrl_c(command: Callable[..., bool]) -> str | None:
    """STOP, else ESTOP, whatever the user presses meanwhile (a second Ctrl-C goes on to the
    ESTOP rather than leave the coils on): the command acknowledged, or None."""
    for name in ("STOP", "ESTOP"):
        try:
            if command(name):
                return name
        except KeyboardInterrupt:
            continue
    return None
