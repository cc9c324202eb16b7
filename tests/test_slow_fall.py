"""A fall still coming down is not a timeout (ctl.h, CTL_FALL_PROGRESS_MS; docs/control.md, "Slow
falls"): R1 at full strokes in a warm enclosure comes down from 11 to 00 in about 8.5 s, and
the 8 s state timeout stopped it 0.5 s short of 00 while both ends still fell at 3-12°/s. A
fall that does not come down (coils that cannot cool below As) still times out, one
CTL_FALL_PROGRESS_MS at most after the state timeout, with cold coils afterwards."""

from __future__ import annotations

from pathlib import Path

from proleg.report import claim
from proleg.report.gait_run import SimSession
from proleg.robot import load_robot
from proleg.sim.closed_loop import SimulatedRobot

STROKE = Path(__file__).resolve().parents[1] / "robots" / "paper-r1-stroke.toml"
#: ctl.h CTL_FALL_PROGRESS_MS
FALL_PROGRESS_S = 1.5


def test_a_slow_fall_in_a_warm_enclosure_completes_its_step():
    robot = load_robot(STROKE)
    out = claim.feedback_run(robot, claim.point("hot ambient + enclosure (strong)"), duration_s=30.0)
    assert out.completed and not out.fault and not out.reported, out
    assert out.speed_mm_s > 1.0, out


def test_a_fall_that_does_not_come_down_still_times_out():
    """At 60 °C the coils never cool below As: both ends stay at their strokes after 11."""
    robot = load_robot(STROKE)
    point = claim.GridPoint("hot", (), "custom", ("ambient_c=60",))
    sim = SimulatedRobot(robot, seed=1, plant=claim._plant(robot, point))
    session = SimSession(sim)
    run = session.run_gait("+x", 0, 16.0)
    assert [f.code for f in run.faults] == ["STATE_TIMEOUT"], run.faults
    # 11 is reached within ~1.5 s and held 0.1 s; 00 is then demanded, and never comes
    timeout_s = robot.safety.state_timeout_ms / 1000.0
    assert timeout_s < run.faults[0].time_s < 2.0 + timeout_s + FALL_PROGRESS_S, run.faults
    session.advance(5.0)
    assert max(sim.plant.temperature_c) < 65.0


def test_the_idealised_drives_step_clock_stands_only_while_a_fall_comes_down():
    """``envelope.StepClock``, the firmware's rule for the claim bench's idealised drive."""
    from proleg.sim.physical.envelope import FALL_PROGRESS_S, StepClock

    dt = 0.01

    def level(psi):  # one threshold at 20° a limb
        return [int(p >= 20.0) for p in psi]

    clock = StepClock([70.0, 60.0], pause=True)
    psi = [70.0, 60.0]
    for _ in range(300):  # both coming down 10°/s: after the first degree, not counted
        psi = [p - 10.0 * dt for p in psi]
        away = clock.tick(dt, psi, level(psi), [0, 0], heating=False)
    assert 0.09 < away < 0.11
    for _ in range(300):  # they stop: counted again once FALL_PROGRESS_S has passed
        away = clock.tick(dt, psi, level(psi), [0, 0], heating=False)
    assert 0.0 <= away - (0.1 + 3.0 - FALL_PROGRESS_S) <= 0.11  # from its last whole degree down
    before = away
    for _ in range(100):  # coming down again, but a coil heats: counted
        psi = [psi[0] - 0.1, psi[1]]
        away = clock.tick(dt, psi, level(psi), [0, 1], heating=True)
    assert abs(away - before - 1.0) < 1e-9
    plain = StepClock([70.0, 60.0], pause=False)  # a build without the pause: all counted
    for k in range(100):
        psi = [70.0 - k, 60.0 - k]
        away = plain.tick(dt, psi, level(psi), [0, 0], heating=False)
    assert abs(away - 1.0) < 1e-9
