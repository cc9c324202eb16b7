"""Issue 15 in the console: a coil dies while the console watches R1 walk; the console
replans (the firmware's own fallback turned off, so the host must act), loads the best gait
of what is left and the robot keeps moving +x within three gait cycles. Headless (textual's
pilot) on the host-sim firmware paced at 8× real time."""

from __future__ import annotations

import asyncio
import io
from pathlib import Path

import pytest

from proleg.cli.main import main
from proleg.console import ConsoleApp, LimbView, RobotNames
from proleg.console.inject import Injector, parse_injection
from proleg.errors import SimError
from proleg.link.client import Received, RobotClient
from proleg.link.listeners import Listener
from proleg.link.sim_link import SimLink
from proleg.protocol.definition import EventKind
from proleg.robot import load_robot
from proleg.sim.simulators import open_host_sim

ROOT = Path(__file__).resolve().parents[1]
R1 = ROOT / "robots" / "paper-r1.toml"
LOSS_S = 10.0


def _r1(tmp_path: Path, fallback: bool) -> Path:
    p = tmp_path / "paper-r1.toml"
    text = R1.read_text()
    p.write_text(text if fallback else text.replace("telemetry_hz = 50", "telemetry_hz = 50\nfallback = false"))
    return p


class _Track(Listener):
    """(simulated time, displacement) of every message, the events, and the healthy cycles
    (the gait's start state reached before the loss)."""

    def __init__(self, sim):
        self.sim = sim
        self.points: list[tuple[float, float]] = []
        self.events: list[tuple[float, int, int]] = []
        self.cycle_s: list[float] = []
        self.sent: list[str] = []

    def on_message(self, rx: Received) -> None:
        t = self.sim.time_s
        self.points.append((t, self.sim.plant.displacement_mm))
        m = rx.message
        if m.name == "EVENT":
            self.events.append((t, m.kind, m.code))
            if m.kind == EventKind.STATE_REACHED and m.detail == 0 and t < LOSS_S:
                self.cycle_s.append(t)

    def x_at(self, t: float) -> float:
        return [x for s, x in self.points if s <= t][-1]


def _watch_r1_lose_its_right_coil(robot_file: Path, *, replan: bool = True) -> tuple[ConsoleApp, _Track, float]:
    robot = load_robot(robot_file)
    sim = open_host_sim(robot)
    client = RobotClient(SimLink(sim, step_s=sim.plant_dt_s, speed=8.0, description="sim paper-r1"))
    client.connect()
    track = _Track(sim)
    app = ConsoleApp(client, limbs=[LimbView(limb.name, limb.psi_star_deg) for limb in robot.limbs],
                     levels=robot.levels, names=RobotNames.for_robot(robot), robot=robot, replan=replan,
                     listeners=[track])
    app.extra_listeners.append(Injector(sim, [(LOSS_S, "dead-actuator:sma-right")], app.host_says))
    end = {}

    async def scenario() -> None:
        async with app.run_test(size=(80, 24)) as pilot:
            await pilot.press("s")  # gait 0 in +x
            for _ in range(1200):  # at most a minute of wall time
                await pilot.pause(0.05)
                acted = app.replanner is not None and any(a.startswith(("loaded", "firmware fell"))
                                                          for a in app.replanner.actions)
                if acted and "events" not in end:
                    await pilot.pause(0.2)
                    app.refresh_view()
                    end["events"] = str(app.query_one("#events").content)
                if len(track.cycle_s) >= 2 and sim.time_s > LOSS_S + 3 * _cycle(track) + 3.0:
                    break
            app.refresh_view()
            end["counters"] = str(app.query_one("#counters").content)
            await pilot.press("q")

    asyncio.run(scenario())
    client.close()
    app.end = end  # type: ignore[attr-defined]
    return app, track, _cycle(track)


def _cycle(track: _Track) -> float:
    c = track.cycle_s
    return (c[-1] - c[0]) / (len(c) - 1) if len(c) >= 2 else 5.0


def test_the_console_replans_after_a_limb_loss_and_r1_keeps_moving_plus_x(tmp_path):
    app, track, cycle = _watch_r1_lose_its_right_coil(_r1(tmp_path, fallback=False))
    said = app.replanner.actions
    assert any("suspects sma-right" in s for s in said), said
    assert any(s == "loaded and started 10→11→10 in +x" for s in said), said
    assert EventKind.FALLBACK not in [k for _t, k, _c in track.events]  # the host did it, not the firmware
    fault_t = next(t for t, k, _c in track.events if k == EventKind.FAULT and t > LOSS_S)
    restart = next(t for t, k, _c in track.events if k == EventKind.GAIT_STARTED and t > fault_t)
    gained = track.x_at(LOSS_S + 3 * cycle) - track.x_at(restart)
    assert gained > 0.5, f"+{gained:.2f} mm within three cycles ({cycle:.1f} s each) of the loss; {said}"
    assert "host: loaded and started 10→11→10" in app.end["events"]
    assert "replan on limb loss: on" in app.end["counters"]


def test_when_the_firmware_falls_back_by_itself_the_console_only_says_so(tmp_path):
    app, track, _cycle_s = _watch_r1_lose_its_right_coil(_r1(tmp_path, fallback=True))
    said = app.replanner.actions
    assert EventKind.FALLBACK in [k for _t, k, _c in track.events]
    assert any("fell back by itself" in s and "10→11→10" in s for s in said), said
    assert not any(s.startswith("loaded and started") for s in said), said


def test_no_replan_and_no_robot_file_are_told_and_nothing_is_replanned(tmp_path):
    from fake_board import FakeBoard

    client = RobotClient(SimLink(FakeBoard(), speed=4.0, description="sim fake"))
    client.connect()
    robot = load_robot(R1)
    for kwargs, shown in (({"robot": robot, "replan": False}, "replan: off (--no-replan)"),
                          ({}, "replan: off (needs --robot)")):
        app = ConsoleApp(client, **kwargs)

        async def scenario() -> None:
            async with app.run_test(size=(80, 24)) as pilot:
                await pilot.pause(0.2)
                app.refresh_view()
                assert shown in str(app.query_one("#counters").content)

        asyncio.run(scenario())
        assert app.replanner is None
    client.close()


def test_plain_mode_says_whether_it_replans(tmp_path, capsys):
    from proleg.cli.link_commands import console_main

    err = io.StringIO()
    console_main(sim=str(R1), plain=True, duration_s=0.2, out=io.StringIO(), err=err, fmt="jsonl")
    assert "proleg: replan on limb loss: on" in err.getvalue()
    err = io.StringIO()
    console_main(sim=str(R1), plain=True, duration_s=0.2, out=io.StringIO(), err=err, fmt="jsonl", replan=False)
    assert "proleg: replan: off (--no-replan)" in err.getvalue()


@pytest.mark.parametrize("argv, message", [
    (["--sim", str(R1), "--inject", "dead-actuator:sma-right+soon"], "fault needs an actuator (sma-left, sma-right, a limb's name, rear, front or its channel), got 'sma-right+soon'"),
    (["--sim", str(R1), "--inject", "dead-actuator:nosuch+0.05"], "--inject dead-actuator:nosuch: fault needs an actuator"),
    (["--sim", str(R1), "--inject", "melt:sma-right+1"], "unknown fault"),
    (["--port", "loop://", "--inject", "dead-actuator:sma-right"], "--inject needs --sim ROBOT"),
])
def test_console_inject_mistakes_are_one_line(capsys, argv, message):
    code = main(["console", "--plain", "--duration", "0.1", *argv])
    err = capsys.readouterr().err
    assert code == 2 and message in err and "Traceback" not in err and len(err.strip().splitlines()) == 1


def test_an_injection_spec_is_a_fault_and_a_time():
    assert parse_injection("dead-actuator:sma-right+10") == (10.0, "dead-actuator:sma-right")
    assert parse_injection("imu-silent:left") == (0.0, "imu-silent:left")
    with pytest.raises(SimError, match="≥ 0"):
        parse_injection("imu-silent:left+-3")
    # a '+' with nothing after it: a time left out, not part of the coil's name ("no actuator 'sma-right+'")
    with pytest.raises(SimError, match=r"--inject dead-actuator:sma-right\+: no time after '\+'"):
        parse_injection("dead-actuator:sma-right+")


def test_a_plus_that_is_not_followed_by_seconds_belongs_to_the_name():
    """A limb named "front+pad @2" could not be named in --inject: everything after the last
    '+' was taken for the time."""
    assert parse_injection("imu-silent:front+pad @2") == (0.0, "imu-silent:front+pad @2")
    assert parse_injection("imu-silent:front+pad @2+1.5") == (1.5, "imu-silent:front+pad @2")


def test_a_fault_due_later_that_names_no_coil_is_refused_before_the_run(capsys):
    """sim and console injected a timed fault only when it was due: a bad coil name then
    raised in the middle of the run (a traceback in the console)."""
    code = main(["sim", str(R1), "--duration", "1", "--inject", "dead-actuator:nosuch+0.5"])
    err = capsys.readouterr().err
    assert code == 2 and "--inject dead-actuator:nosuch: fault needs an actuator" in err and "Traceback" not in err
