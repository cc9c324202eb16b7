"""The claim bench's envelope model (``sim.physical.envelope``) against the firmware's own
``core/sma.c``, compiled for the host: the same per-tick duty requests through both, and tick
by tick the duties let through and the on-limit hits must be the same. With R1's
window (10 s: out of reach of these sequences), with a 200 ms window at a 30 % mean that the
bursts run into all the time, at 600 Hz, a tick that does not divide a millisecond, and with a
cool-down 40 times the on-time, whose pay-back per tick is a fraction of a µs."""

from __future__ import annotations

import dataclasses
import subprocess
from types import SimpleNamespace

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from proleg.firmware.render import render_config
from proleg.protocol.render import render_c
from proleg.sim.physical.envelope import Envelope
from core_configs import CC, CORE, SIM, r1_fast, r1_heat
from test_firmware_core import CDIR, CFLAGS

pytestmark = pytest.mark.skipif(CC is None, reason="no host C compiler")


def _short_window(robot):
    """The robot with a 200 ms mean-duty window at 30 % (docs/safety.md's thermal budget)."""
    s = robot.safety
    safety = SimpleNamespace(max_on_ms=s.max_on_ms, min_cooldown_ms=s.min_cooldown_ms, max_duty=s.max_duty,
                             state_timeout_ms=s.state_timeout_ms, link_watchdog_ms=s.link_watchdog_ms,
                             duty_window_ms=200, max_mean_duty=0.3)
    return dataclasses.replace(robot, safety=safety)


def _slow_payback(robot):
    """Cool-down 2 s for 50 ms on (40×): a pay-back rate of 6.4/256 µs per µs, where the
    fraction of a µs each tick pays must carry on to the next to match the firmware."""
    return dataclasses.replace(robot, safety=dataclasses.replace(robot.safety, min_cooldown_ms=2000))


@pytest.fixture(scope="module", params=["r1-window", "short-window", "600-hz", "250-hz", "slow-payback",
                                        "heat-ceiling"])
def replay(request, tmp_path_factory):
    robot, gaits, board = r1_heat() if request.param == "heat-ceiling" else r1_fast()  # r1_fast: max_on 50 ms, cooldown 20 ms, 1 kHz
    if request.param == "short-window":
        robot = _short_window(robot)
    elif request.param == "600-hz":  # a tick of 1667 µs: max_on is 30 ticks, 50,010 µs
        robot = dataclasses.replace(robot, control=dataclasses.replace(robot.control, tick_hz=600))
    elif request.param == "250-hz":  # 4 ms ticks, and the short window
        robot = dataclasses.replace(_short_window(robot), control=dataclasses.replace(robot.control, tick_hz=250))
    elif request.param == "slow-payback":
        robot = _slow_payback(robot)
    gen = tmp_path_factory.mktemp("gen")
    for name, text in {**render_config(robot, gaits, board), **render_c(2, 2)}.items():
        (gen / name).write_text(text)
    exe = gen / "sma_replay"
    cmd = [CC, *CFLAGS, f"-I{CORE}", f"-I{gen}", f"-I{SIM}", f"-I{CDIR}",
           str(CDIR / "sma_replay.c"), str(CDIR / "fake_hal.c"), str(CORE / "sma.c"), str(CORE / "elapsed.c"),
           "-o", str(exe)]
    build = subprocess.run(cmd, capture_output=True, text=True)
    assert build.returncode == 0, build.stderr

    def run(requests: list[tuple[int, int]]) -> list[tuple[int, int, int]]:
        out = subprocess.run([str(exe)], input="".join(f"{a} {b}\n" for a, b in requests),
                             capture_output=True, text=True, timeout=60, check=True).stdout
        return [tuple(int(x) for x in line.split()) for line in out.splitlines()]

    return robot, run


def _model(robot, requests):
    env = Envelope(robot, 2, robot.control.tick_hz and 1.0 / robot.control.tick_hz)
    env.latch = 10**9  # sma.c reports hits; safety.c latches them (compared in test_envelope_oracle)
    out = []
    for a, b in requests:
        hits = env.hits
        o = env.gate([a / 10000, b / 10000])
        assert env.hits - hits == bin(env.hit_bits).count("1")  # every hit counted once
        out.append((round(o[0] * 10000), round(o[1] * 10000), env.hit_bits))
    return out


@settings(max_examples=40, deadline=None)
@given(st.lists(st.tuples(st.sampled_from([0, 2000, 3000, 6000, 8000, 9000]),
                          st.sampled_from([0, 2000, 3000, 6000, 8000, 9000]),
                          st.integers(1, 120)), min_size=1, max_size=30))
def test_the_model_cuts_where_the_firmware_cuts(replay, bursts):
    robot, run = replay
    requests = [(a, b) for a, b, n in bursts for _ in range(n)]
    fw = run(requests)
    model = _model(robot, requests)
    assert fw == model  # tick by tick: the duty each coil gets and the on-limit hits


@pytest.mark.parametrize("replay", ["250-hz"], indirect=True)
def test_stepped_finer_than_the_tick_the_model_cuts_no_later_than_the_firmware(replay):
    """The idealised drive steps at 2 ms; at 250 Hz the firmware decides for 4 ms ticks. The
    same requests through both: the model's first on-limit cut and first mean-duty block come
    no later than the firmware's."""
    robot, run = replay
    requests = [(8000, 0)] * 30 + [(0, 0)] * 5 + [(3000, 0)] * 200  # heat, rest, then hold against the window
    fw = run(requests)
    env = Envelope(robot, 2, 0.002)
    model = [env.gate([a / 10000, 0.0])[0] for a, _ in requests for _ in range(2)]

    def first_off_us(out, step_us, start):
        return next(k for k in range(start, len(out)) if out[k] == 0) * step_us

    assert first_off_us(model, 2000, 0) <= first_off_us([a for a, _, _ in fw], 4000, 0)  # the on-limit
    blocked_fw = first_off_us([a for a, _, _ in fw], 4000, 35)                             # the window
    assert first_off_us(model, 2000, 70) <= blocked_fw < 235 * 4000


@pytest.mark.parametrize("replay", ["short-window"], indirect=True)
def test_the_short_window_is_in_reach(replay):
    """The second robot's window does cut: a guard against comparing two envelopes that never
    block anything."""
    robot, run = replay
    requests = [(3000, 0)] * 600  # 0.3 duty, below the hold ceiling: never on-time, only the window
    fw = run([(8000, 0)] * 30 + [(0, 0)] * 10 + requests)
    assert fw == _model(robot, [(8000, 0)] * 30 + [(0, 0)] * 10 + requests)
    assert any(a == 0 for a, _, _ in fw[40:]), "the window never blocked"


@pytest.mark.parametrize("replay", ["heat-ceiling"], indirect=True)
def test_the_heat_ceiling_cuts_where_the_firmware_cuts(replay):
    """With ``[safety] coil_heat_ceiling = true`` sma.c gives a coil whose heat (its duty
    smoothed with its time constant) reached max_mean_duty at most that. The model left it out:
    the idealised drive, boosted to max_duty on such a body by default, heated on at 0.8 where
    the firmware gives 0.45, and --measure-matrix measured caterpillar-4 at power 0.5 in full
    where the firmware timed out at its first step. 2.5 s at 0.8 (under max_on 3 s), a rest,
    then 0.6: tick by tick the same, and the ceiling does cut in."""
    robot, run = replay
    requests = [(8000, 6000)] * 2500 + [(0, 0)] * 500 + [(6000, 6000)] * 2000
    fw = run(requests)
    assert fw == _model(robot, requests)
    mean_pm = round(robot.safety.max_mean_duty * 10000)
    assert any(a == mean_pm for a, _, _ in fw[:2500]), "the heat ceiling never cut in"


@pytest.mark.parametrize("replay", ["heat-ceiling"], indirect=True)
def test_an_idle_coils_heat_cools_as_the_firmwares(replay):
    """A coil off and paid up still cools in sma.c's heat_step: a rest long enough to pay the
    on-time debt back (2.5 s on pays back in about 0.7 s) and then some, before heating again.
    The model's skip of idle coils left their heat where it was."""
    robot, run = replay
    requests = [(8000, 8000)] * 2500 + [(0, 0)] * 2000 + [(8000, 8000)] * 2500
    fw = run(requests)
    assert fw == _model(robot, requests)
