"""The claim bench's oracle keeps to the firmware's safety envelope (``sim.physical.envelope``):
a condition counts as physically possible only if an idealised drive completes the gait
within the on-time debt, the mean-duty window and the state timeout the firmware is built
with, or if the firmware itself completes it."""

from __future__ import annotations

from types import SimpleNamespace

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from proleg.firmware.render import MAX_ON_LIMIT_LATCH
from proleg.paths import robots_dir
from proleg.report import claim
from proleg.robot import Control, load_robot
from proleg.sim.physical.envelope import Envelope, EnvelopeLatched

R1 = robots_dir() / "paper-r1.toml"
DT = 0.01


def _robot(max_on_ms=3000, cooldown_ms=800, timeout_ms=8000, mean=0.5, window_ms=10_000, latch=3):
    safety = SimpleNamespace(max_on_ms=max_on_ms, min_cooldown_ms=cooldown_ms, max_duty=0.8,
                             state_timeout_ms=timeout_ms, link_watchdog_ms=0, hold_max_duty=None,
                             max_mean_duty=mean, duty_window_ms=window_ms, on_limit_latch=latch)
    ctl = Control(hold_duty=0.25, drive_duty=0.6)  # 1 kHz
    return SimpleNamespace(name="test", safety=safety, control=ctl)


def _run(env: Envelope, requests):
    out = []
    for r in requests:
        out.append(env.gate([r])[0])
    return out


@settings(max_examples=60, deadline=None)
@given(st.lists(st.tuples(st.sampled_from([0.0, 0.2, 0.6, 0.8]), st.integers(1, 150)), min_size=1, max_size=25))
def test_what_the_envelope_lets_through_keeps_every_rule(bursts):
    """Against a brute-force reading of docs/safety.md's rules over the whole output: never
    more than asked; no on-period longer than max_on_ms; the duty over any window at most the
    cap; on/off games never on for more than max_on / (max_on + cooldown) of the time beyond
    one full on-period. (Tick by tick the model is checked against the compiled sma.c itself:
    tests/test_envelope_vs_sma.py.)"""
    robot = _robot(max_on_ms=500, cooldown_ms=400, window_ms=2000, mean=0.4, latch=MAX_ON_LIMIT_LATCH)  # as late as it goes
    env = Envelope(robot, 1, DT)
    requests = [d for d, n in bursts for _ in range(n)]
    out = _run(env, requests)
    assert all(o <= r + 1e-12 for o, r in zip(out, requests))
    ceiling = env.hold_ceiling_pm / 10000
    run = longest = 0
    for o in out:
        run = run + 1 if o > ceiling else 0
        longest = max(longest, run)
    assert longest * DT <= 0.5 + 1e-9
    n = round(2.0 / DT)
    for i in range(len(out)):
        assert sum(out[max(0, i - n + 1):i + 1]) * DT <= 0.4 * 2.0 + 1e-9
    on_s = sum(DT for o in out if o > ceiling)
    assert on_s <= 0.5 + len(out) * DT * 500 / 900 * 1.01 + DT


def test_a_hold_below_the_ceiling_is_never_on_time():
    env = Envelope(_robot(max_on_ms=200, mean=1.0), 1, DT)
    assert _run(env, [0.25] * 1000) == [0.25] * 1000


def test_repeated_on_limit_hits_latch_sma_on_limit():
    env = Envelope(_robot(max_on_ms=200, cooldown_ms=100, mean=1.0, latch=3), 1, DT)
    with pytest.raises(EnvelopeLatched) as e:
        _run(env, [0.6] * 1000)
    assert e.value.code == "SMA_ON_LIMIT" and "max_on_ms 200 ms" in str(e.value)


def test_hits_on_different_coils_count_together_as_in_the_firmware():
    """core/safety.c counts on-limit hits of every actuator in one tally (hits_since_reached)."""
    env = Envelope(_robot(max_on_ms=200, cooldown_ms=100, mean=1.0, latch=3), 2, DT)
    with pytest.raises(EnvelopeLatched):
        for _ in range(100):  # both coils asked to heat: both hit at 0.2 s, paid back 0.1 s later, one more hit ends it
            env.gate([0.6, 0.6])
    assert env.hits == 3


def test_the_payback_is_capped_as_sma_c_caps_refill():
    env = Envelope(_robot(max_on_ms=60_000, cooldown_ms=10, mean=1.0), 1, DT)
    assert env.refill_q8 == 10000  # paid back at most 39× as fast as it was run up


def test_reaching_a_state_resets_the_hit_count():
    env = Envelope(_robot(max_on_ms=200, cooldown_ms=100, mean=1.0, latch=2), 1, DT)
    for _ in range(5):  # one hit per state, never two in a row
        _run(env, [0.6] * 25)
        env.reached()
        _run(env, [0.0] * 30)


def _r1_with_safety(tmp_path, **keys):
    text = R1.read_text(encoding="utf-8")
    for k, v in keys.items():
        text = text.replace(f"\n{k} = ", f"\n{k} = {v}  # was ", 1)
    path = tmp_path / "r1.toml"
    path.write_text(text, encoding="utf-8")
    return load_robot(path)


def test_a_gait_the_state_timeout_forbids_is_impossible_and_says_so(tmp_path):
    robot = _r1_with_safety(tmp_path, state_timeout_ms=300)
    possible, why = claim.physically_possible(robot, claim.NOMINAL)
    assert not possible and "state_timeout_ms (300 ms)" in why and "STATE_TIMEOUT" in why


def test_a_gait_the_on_time_limit_forbids_is_impossible_and_says_so(tmp_path):
    robot = _r1_with_safety(tmp_path, max_on_ms=60, min_cooldown_ms=2000)
    possible, why = claim.physically_possible(robot, claim.NOMINAL)
    assert not possible and "max_on_ms 60 ms" in why and "SMA_ON_LIMIT" in why


def test_the_nominal_robot_is_possible_within_its_envelope():
    assert claim.physically_possible(load_robot(R1), claim.NOMINAL) == (True, "")


def test_a_condition_the_firmware_completes_is_possible_whatever_the_oracle_says(monkeypatch):
    robot = load_robot(R1)
    monkeypatch.setattr(claim, "idealised_walk", lambda *a, **k: claim.IdealisedWalk(False, "the oracle says no", None))
    drive = claim.OpenLoopDrive((0.0, 0.0), (0.5, 0.5), (2.0, 2.0), (0.0, 1.0))
    result = claim.run_condition(robot, drive, claim.NOMINAL, duration_s=12.0)
    assert result.feedback.completed
    assert result.possible and result.why_not == ""
    assert result.extra["possible_by"] == "the firmware's own run"
    assert result.extra["idealised_drive_why_not"] == "the oracle says no"
