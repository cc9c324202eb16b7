"""The link watchdog, on by default, on the simulated board running the real firmware: a host
that goes silent for longer than ``link_watchdog_ms`` (default 2000) stops the coils; a
connected client's heartbeat keeps an idle session from tripping it. And the console's check
of a robot file against the board's INFO."""

from __future__ import annotations

import io
import json
import shutil

import pytest

from proleg.cli.link_commands import console_main
from proleg.console.identity import IdentityMismatch, expected_identity
from proleg.link import RobotClient
from proleg.link.sim_link import SimLink
from proleg.paths import resolve_robot
from proleg.protocol.definition import EventKind, FaultCode, Flag, StopReason
from proleg.robot import Safety, load_robot
from proleg.sim.closed_loop import SimulatedRobot


def _running_robot(heartbeat_s: float | None):
    robot = load_robot(resolve_robot("paper-r1"))
    sim = SimulatedRobot(robot, seed=3)
    client = RobotClient(SimLink(sim, step_s=sim.plant_dt_s), heartbeat_s=heartbeat_s)
    client.connect()
    assert client.wait_known_state()  # the board refuses START before it has read its IMUs
    while client.recv(0.0) is not None:  # what came before the gait: not the running robot's
        pass
    client.start(0, "+x")
    return robot, sim, client


def _duties(sim: SimulatedRobot) -> list[float]:
    return [sim.board.pwm(ch) for ch in sim.channels]


def _events(client: RobotClient) -> list:
    out = []
    while (m := client.recv(0.0)) is not None:
        if m.name == "EVENT":
            out.append(m)
    return out


def test_the_watchdog_is_on_by_default_at_two_seconds():
    assert Safety().link_watchdog_ms == 2000
    assert load_robot(resolve_robot("paper-r1")).safety.link_watchdog_ms == 2000


def test_the_firmware_stops_driving_when_the_host_goes_silent_for_over_two_seconds():
    robot, sim, client = _running_robot(heartbeat_s=None)
    _events(client)
    driven = 0.0
    for _ in range(round(1.9 / sim.plant_dt_s)):  # the host says nothing for 1.9 s: still walking
        sim.step()
        driven = max(driven, *_duties(sim))
    assert driven > 0.2
    for _ in range(round(0.2 / sim.plant_dt_s)):  # past 2 s: stopped
        sim.step()
    assert _duties(sim) == [0.0] * len(sim.channels)
    for _ in range(round(1.0 / sim.plant_dt_s)):  # and it stays cold
        sim.step()
        assert max(_duties(sim)) == 0.0
    events = _events(client)
    assert any(e.kind == EventKind.FAULT and e.code == FaultCode.LINK_WATCHDOG for e in events)
    assert any(e.kind == EventKind.GAIT_STOPPED and e.code == StopReason.WATCHDOG for e in events)
    tel = next(client.telemetry(timeout=1.0))
    assert tel.flags & Flag.LINK_WATCHDOG and not tel.flags & Flag.RUNNING
    client.close()


def test_an_idle_session_with_the_heartbeat_never_trips_the_watchdog():
    robot, sim, client = _running_robot(heartbeat_s=0.5)
    seen = []
    deadline = client.link.clock() + 6.0
    while client.link.clock() < deadline:  # only reading, as an idle console does
        m = client.recv(0.1)
        if m is not None and m.name in ("EVENT", "TELEMETRY"):
            seen.append(m)
    assert client.heartbeats >= 10
    assert not any(m.name == "EVENT" and m.kind == EventKind.FAULT for m in seen)
    assert all(m.flags & Flag.RUNNING for m in seen if m.name == "TELEMETRY")
    assert not any(m.name == "ACK" for m in seen)  # the heartbeat's ACKs are not in the stream
    client.close()


class _FastBoardLink(SimLink):
    """A board whose clock runs ``SPEED`` × the link's (``proleg sim --pty --speed 5`` seen
    over the pty, where the host counts wall time)."""

    SPEED = 5.0

    def read(self, timeout: float) -> bytes:
        return super().read(timeout * self.SPEED)

    def clock(self) -> float:
        return super().clock() / self.SPEED


def test_the_heartbeat_keeps_pace_with_a_board_whose_clock_runs_faster_than_the_hosts():
    """At --speed 5 a 0.5 s heartbeat is 2.5 s of board time, past the 2 s watchdog: every
    run over a fast simulated board ended in LINK_WATCHDOG. The client measures the board's
    clock rate from TELEMETRY and pings in proportion."""
    robot = load_robot(resolve_robot("paper-r1"))
    sim = SimulatedRobot(robot, seed=3)
    client = RobotClient(_FastBoardLink(sim, step_s=sim.plant_dt_s), heartbeat_s=0.5)
    client.connect()
    client.start(0, "+x")
    seen = []
    deadline = client.link.clock() + 4.0  # 20 s of board time
    while client.link.clock() < deadline:
        m = client.recv(0.05)
        if m is not None and m.name in ("EVENT", "TELEMETRY"):
            seen.append(m)
    assert 4.0 < client.board_rate <= 5.5
    assert not any(m.name == "EVENT" and m.kind == EventKind.FAULT for m in seen)
    assert all(m.flags & Flag.RUNNING for m in seen[-20:] if m.name == "TELEMETRY")
    client.close()


def _watchdog_robot(tmp_path, ms: int):
    text = (resolve_robot("paper-r1")).read_text()
    path = tmp_path / f"r1-watchdog-{ms}.toml"
    path.write_text(text.replace("[safety]\n", f"[safety]\nlink_watchdog_ms = {ms}\n"))
    return path


@pytest.mark.parametrize("command", [["sim", "--json"], ["run", "--sim", "--format", "jsonl"]])
def test_a_robot_files_shorter_watchdog_is_fed_by_sim_and_run(tmp_path, capsys, command):
    """Only the console pinged in step with the robot file's watchdog: with 400 ms, proleg sim
    and proleg run (0.5 s heartbeat) stopped every gait with LINK_WATCHDOG 0.4 s after START."""
    from proleg.cli import main

    path = _watchdog_robot(tmp_path, 400)
    code = main([command[0], str(path), *command[1:], "--duration", "8"])
    out = capsys.readouterr().out
    assert code == 0, out
    result = json.loads(out.splitlines()[-1])
    assert result["faults"] == [] and result["cycles"] >= 1


def test_a_watchdog_under_100_ms_is_refused_and_100_is_fed(tmp_path):
    from proleg.errors import RobotFileError

    with pytest.raises(RobotFileError, match=r"safety.link_watchdog_ms: expected 0 \(off\) or at least 100 ms, got 50"):
        load_robot(_watchdog_robot(tmp_path, 50))
    robot = load_robot(_watchdog_robot(tmp_path, 100))
    client = RobotClient(SimLink(SimulatedRobot(robot, seed=1)), watchdog_ms=robot.safety.link_watchdog_ms)
    assert client.heartbeat_s == pytest.approx(0.025)


def test_set_param_shortening_the_watchdog_shortens_the_heartbeat():
    robot, sim, client = _running_robot(heartbeat_s=0.5)
    client.set_param("link_watchdog_ms", 0, 300)
    assert client.heartbeat_s == pytest.approx(0.075)
    deadline = client.link.clock() + 3.0
    faults = []
    while client.link.clock() < deadline:  # reading only, as an idle console does
        m = client.recv(0.1)
        if m is not None and m.name == "EVENT" and m.kind == EventKind.FAULT:
            faults.append(m)
    assert not faults
    client.close()


# --------------------------------------------------------------------------- identity
def test_the_identity_computed_from_the_robot_file_is_what_the_firmware_reports():
    robot, sim, client = _running_robot(heartbeat_s=0.5)
    info = client.info
    want = expected_identity(robot, info.board)
    client.close()
    assert (want.robot_name, want.gait_hash, want.build_id) == (info.robot_name, info.gait_hash, info.build_id)


def test_the_console_refuses_a_robot_file_the_board_was_not_built_from(tmp_path):
    edited = tmp_path / "paper-r1.toml"
    shutil.copy(resolve_robot("paper-r1"), edited)
    edited.write_text(edited.read_text() + "\n# edited after flashing\n")
    sim_robot = load_robot(resolve_robot("paper-r1"))
    lib_info = expected_identity(sim_robot, "host-sim")
    mine = expected_identity(load_robot(edited), "host-sim")
    assert mine.gait_hash == lib_info.gait_hash and mine.build_id != lib_info.build_id
    with pytest.raises(IdentityMismatch) as e:
        console_main(sim="paper-r1", robot_file=str(edited), plain=True, duration_s=0.1, out=io.StringIO(),
                     err=io.StringIO())
    text = str(e.value)
    assert f"build id {lib_info.build_id:08x} on the board, {mine.build_id:08x} from {edited}" in text
    assert "--force" in text and "\n" not in text
    err = io.StringIO()
    assert console_main(sim="paper-r1", robot_file=str(edited), plain=True, duration_s=0.1, out=io.StringIO(),
                        err=err, force=True) == 0
    assert "warning: --force: build id" in err.getvalue() and "robot stopped" in err.getvalue()


def test_the_console_refuses_another_robots_file():
    with pytest.raises(IdentityMismatch, match="robot 'paper-r1' on the board, 'paper-r3'"):
        console_main(sim="paper-r1", robot_file=str(resolve_robot("paper-r3")), plain=True, duration_s=0.1,
                     out=io.StringIO(), err=io.StringIO())


def test_force_does_not_read_a_board_with_another_robot_files_shape():
    """--force with inchworm-3's file on R1's board printed 3-digit states beside 2 ψ."""
    out = io.StringIO()
    with pytest.raises(IdentityMismatch, match="has 2 limbs and 2 actuators, .*inchworm-3.toml 3 and 3: --force cannot"):
        console_main(sim="paper-r1", robot_file=str(resolve_robot("inchworm-3")), plain=True, duration_s=0.5,
                     force=True, out=out, err=io.StringIO())
    assert out.getvalue() == ""
    # the same shape: --force reads it (R3 is R1's body with other pads)
    code = console_main(sim="paper-r1", robot_file=str(resolve_robot("paper-r3")), plain=True, duration_s=0.5,
                        force=True, out=out, err=io.StringIO())
    assert code == 0 and "state=" in out.getvalue()


def test_a_100_ms_watchdog_with_slow_telemetry_is_fed_between_frames(tmp_path):
    """A read waited up to 0.1 s for the next frame before the heartbeat looked again: with
    telemetry at 7 Hz (143 ms apart) and link_watchdog_ms = 100 (both in range) every gait
    stopped with LINK_WATCHDOG 0.2 s after START. The read now ends when the next PING is due."""
    path = _watchdog_robot(tmp_path, 100)
    path.write_text(path.read_text().replace("telemetry_hz = 50", "telemetry_hz = 7"))
    robot = load_robot(path)
    assert robot.control.telemetry_hz == 7
    sim = SimulatedRobot(robot, seed=3)
    client = RobotClient(SimLink(sim, step_s=sim.plant_dt_s), watchdog_ms=robot.safety.link_watchdog_ms)
    client.connect()
    assert client.wait_known_state()
    client.start(0, "+x")
    faults = []
    deadline = client.link.clock() + 2.0
    while client.link.clock() < deadline:  # reading only, as proleg sim and an idle console do
        m = client.recv(0.5)
        if m is not None and m.name == "EVENT" and m.kind == EventKind.FAULT:
            faults.append(m.fields)
    client.close()
    assert faults == []
