"""Limb loss: the transitions a dead actuator takes away, and the gait left (host side)."""

from __future__ import annotations

from pathlib import Path

import pytest

from proleg.learn.replan import replan, suspect, without_actuator
from proleg.protocol.definition import FaultCode
from proleg.robot import load_robot

ROOT = Path(__file__).resolve().parents[1]


def test_a_fault_names_the_actuator_to_suspect():
    r1 = load_robot(ROOT / "robots" / "paper-r1.toml")
    assert suspect(r1, FaultCode.SMA_ON_LIMIT, 1) == "sma-right"  # detail: the actuator
    assert suspect(r1, FaultCode.STATE_TIMEOUT, 0) == "sma-left"  # detail: the limb
    assert suspect(r1, FaultCode.IMU_NO_ACK, 0) is None


def test_an_on_limit_hit_names_the_actuator_by_its_index_not_its_channel(tmp_path):
    """The firmware's SMA_ON_LIMIT detail is the actuator's index (core/drive.c, as SUSPECT's
    code). Read as a PWM channel, R1 wired the other way round (left coil on channel 1) had a
    hit of its left coil blamed on its right one, and a coil on channel 6 on none."""
    text = (ROOT / "robots" / "paper-r1.toml").read_text(encoding="utf-8")
    swapped = text.replace("channel = 0", "channel = 9").replace("channel = 1", "channel = 0").replace("channel = 9", "channel = 1")
    path = tmp_path / "r1-swapped.toml"
    path.write_text(swapped, encoding="utf-8")
    robot = load_robot(path)
    assert [a.channel for a in robot.actuators] == [1, 0]
    assert suspect(robot, FaultCode.SMA_ON_LIMIT, 0) == "sma-left"
    assert suspect(robot, FaultCode.SMA_ON_LIMIT, 1) == "sma-right"
    assert suspect(robot, FaultCode.SMA_ON_LIMIT, 2) is None


def test_without_its_right_coil_r1_moves_on_only_with_the_left_coil_raising_both_ends():
    r1 = load_robot(ROOT / "robots" / "paper-r1.toml")
    t = without_actuator(r1, "sma-right")
    pairs = {(t.label(a), t.label(b)) for a, b in zip(t.src, t.dst)}
    assert pairs == {("00", "10"), ("10", "00")}  # brute force: no state with the right limb up
    plan = replan(r1, "sma-right")  # the compiled map cannot move it; the remapped one can
    assert plan.states == (2, 3, 2) and plan.actuator_map == (0, 0) and "sma-left" in plan.reason
    assert replan(r1, "sma-right", "-x").states is None


def test_a_robot_with_a_spare_way_to_move_gets_a_gait_for_what_is_left(tmp_path):
    # R3-like: give R1's right limb a second route by making 00<->10 asymmetric
    text = (ROOT / "robots" / "paper-r1.toml").read_text().replace("[-1,  0,  0,  1]", "[ 0,  0,  0,  1]")
    p = tmp_path / "r.toml"
    p.write_text(text)
    plan = replan(load_robot(p), "sma-right")
    assert plan.states == (0, 2, 0) and plan.rate == pytest.approx(0.5)
