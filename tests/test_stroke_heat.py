"""A coil through its transformation is heated no more at full strokes (docs/control.md, "The
knee"): the two measured overheats of the stroke robot, with no fault, before the knee watch.

- A host moves the left ψ* to 70° (SET_PARAM, inside the band rules): the left end cannot
  cross its band alone, creeps at ≈ 3°/s on the other coil's warmth, and its coil was heated at
  the drive duty to the on-time limit every cycle: 166 °C.
- The random sweep's worn, heavy row (bench/bench_sweep.py seed 3): the left coil was heated
  0.5 s past the end of its worn travel, 125 °C.
"""

from __future__ import annotations

from pathlib import Path

from proleg.link.level import calibrate_level
from proleg.report import claim
from proleg.report.gait_run import SimSession
from proleg.robot import load_robot
from proleg.sim.closed_loop import SimulatedRobot
from proleg.physics.materials import NITI_OVERHEAT_C

STROKE = Path(__file__).resolve().parents[1] / "robots" / "paper-r1-stroke.toml"


def test_a_psi_star_the_limb_cannot_cross_alone_does_not_overheat_its_coil():
    robot = load_robot(STROKE)
    sim = SimulatedRobot(robot, seed=1, plant="physical")
    session = SimSession(sim)
    session.advance(0.2)
    assert calibrate_level(session.client).ok
    session.client.set_param("psi_star_cdeg", 0, 7000)
    session.advance(0.2)
    run = session.run_gait("+x", 0, 30.0)
    session.advance(2.0)
    peak = max(sim.plant.peak_temperature_c)
    # before: 166 °C, ≈ 7 s of every 30 above 120 °C; now its coil is left at the hold duty once
    # spent (≈ 95 °C) and the step times out, the coils cooling
    assert peak < NITI_OVERHEAT_C - 10, peak
    assert run.fault_stops > 0 and "STATE_TIMEOUT" in {str(f.code) for f in run.faults}, run.faults
    assert max(sim.plant.temperature_c) < 60  # 2 s after the stop


def test_the_worn_heavy_stroke_robot_of_the_sweep_walks_without_overheating():
    robot = load_robot(STROKE)
    row = claim.GridPoint("seed 3 worn heavy", (), "random",
                          ("fatigue_cycles=16229", "psi_star_shift_deg=front:-1.2", "mass_g=7.3"), ())
    out = claim.feedback_run(robot, row, duration_s=40.0)
    # before: 3.86 mm/s at 125 °C, no fault; now ≈ 4.7 mm/s at ≈ 101 °C
    assert out.completed and out.fault == "", out
    assert out.coil_peak_c < NITI_OVERHEAT_C - 10, out
    assert out.speed_mm_s > 3.0, out


class _Rig:
    """The stroke robot's host-sim firmware and the physical plant (``SimulatedRobot``), commands
    sent between control ticks; ``peak``: the hottest any coil has been (the plant's own record)."""

    def __init__(self, conditions=None):
        from proleg.protocol.codec import FrameDecoder

        self.robot = load_robot(STROKE)
        self.sim = SimulatedRobot(self.robot, seed=1, plant="physical", conditions=conditions)
        self.decoder = FrameDecoder(len(self.robot.limbs), len(self.robot.actuators))
        self.log = []
        self.token = 0

    @property
    def peak(self):
        return max(self.sim.plant.peak_temperature_c)

    def ticks(self, n):
        self.sim.run_ticks(n)
        self.log += self.decoder.feed(self.sim.read())

    def seconds(self, s):
        for _ in range(round(s * 4)):
            self.ticks(round(250_000 / self.sim.board.tick_us))
            self.send("PING")

    def send(self, name, **fields):
        from proleg.protocol.codec import Message, encode

        self.token = self.token % 255 + 1
        self.sim.write(encode(Message.new(name, token=self.token, **fields)))
        return self.token

    def request(self, name, **fields):
        token = self.send(name, **fields)
        self.ticks(20)
        return next(m for m in reversed(self.log) if m.name in ("ACK", "NACK") and m.token == token)


def test_a_hold_duty_above_the_hold_ceiling_is_refused_in_a_stroke_build():
    """The knee watch keeps a spent coil at the hold duty, trusting it to be one the coil may
    carry for ever. SET_PARAM took any hold duty up to max_duty: ψ* 70° and a hold duty of 0.4
    pre-warmed the left coil through its transformation, so the knee watch never saw a fast
    window, and the drive duty took it to 133 °C every cycle (9 s of 120 above 120 °C, no
    fault). Now a stroke build refuses a hold duty above its hold ceiling (SAFETY_LIMIT)."""
    from proleg.protocol.definition import ErrorCode, ParamId

    rig = _Rig()
    rig.seconds(0.3)
    ceiling = round(robot_hold_ceiling() * 10000)
    assert rig.request("SET_PARAM", param=int(ParamId.HOLD_DUTY), index=0, value=ceiling).name == "ACK"
    m = rig.request("SET_PARAM", param=int(ParamId.HOLD_DUTY), index=0, value=4000)
    assert m.name == "NACK" and m.error == ErrorCode.SAFETY_LIMIT, m
    assert rig.request("SET_PARAM", param=int(ParamId.PSI_STAR_CDEG), index=0, value=7000).name == "ACK"
    assert rig.request("START", gait=0, direction=0).name == "ACK"
    rig.seconds(60)
    assert rig.peak < NITI_OVERHEAT_C - 10, rig.peak  # before: 133 °C with the hold duty at 0.4


def robot_hold_ceiling() -> float:
    robot = load_robot(STROKE)
    return robot.safety.hold_ceiling(robot.control.hold_duty)


def test_a_spent_coil_shared_by_two_limbs_is_kept_at_the_hold_duty():
    """The knee watch judged a limb, not its coil: SET_ACTUATOR_MAP [0, 0] (both ends on the
    left coil) and gait 0 with debounce_ticks 1000 (SET_PARAM; the levels read 1.25 s late)
    kept the left coil at the drive duty for the right limb's climb after the left limb's
    watch had found it spent: 167 °C (210 °C at power 1.3), 4.5 s above 120 °C before any fault
    latched. Now a coil any limb found spent is kept at the hold duty for every limb on it."""
    from proleg.protocol.definition import ParamId

    for conditions in (None, ["power=1.3"]):
        rig = _Rig(conditions)
        rig.seconds(0.3)
        assert rig.request("START", gait=0, direction=0).name == "ACK"
        rig.seconds(2)
        assert rig.request("STOP").name == "ACK"
        rig.seconds(3)
        assert rig.request("SET_ACTUATOR_MAP", actuators=(0, 0)).name == "ACK"
        assert rig.request("START", gait=0, direction=0).name == "ACK"
        assert rig.request("SET_PARAM", param=int(ParamId.DEBOUNCE_TICKS), index=0, value=1000).name == "ACK"
        rig.seconds(20)
        assert rig.peak < NITI_OVERHEAT_C - 10, (conditions, rig.peak)  # before: 167 / 210 °C
