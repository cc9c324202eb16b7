"""The small robots the firmware core's host tests build against, and their rendering.

``CONFIGS[name]()`` gives (robot, gaits by direction, board dict) for the simulated board;
``renderer(tmp_path_factory)`` gives ``get(name)``: the directory holding that config's
robot_config.h, gait_table.c and the protocol's rendered C (rendered once per session). Shared by test_firmware_core.py (the C unit tests) and
test_firmware_on_sim_board.py (the whole firmware); no test lives here.
"""

from __future__ import annotations

import dataclasses
import shutil
from collections.abc import Callable
from pathlib import Path
from types import SimpleNamespace

import numpy as np

from proleg.firmware.render import render_config
from proleg.protocol.render import render_c
from proleg.robot import robot_from_dict
from proleg.transitions import TransitionTable

ROOT = Path(__file__).resolve().parents[1]
CORE = ROOT / "firmware_templates" / "core"
SIM = ROOT / "firmware_templates" / "hal" / "sim"
CC = shutil.which("cc") or shutil.which("gcc")

SIM_BOARD = {
    "name": "host-sim",
    "family": "sim",
    "pwm_channels": ["SIM0", "SIM1", "SIM2", "SIM3"],
    "i2c": {"hz": 400000, "imu_addresses": [0x68, 0x69]},
    "uart_baud": 115200,
    "clock_hz": 0,
}


def robot_doc(**over):
    doc = {
        "robot": {"name": "test-r1"},
        "limb": [
            {"name": "left", "psi_star_deg": [20.0], "hysteresis_deg": 2.0, "actuator": "a0"},
            {"name": "right", "psi_star_deg": [20.0], "hysteresis_deg": 2.0, "actuator": "a1"},
        ],
        "actuator": [{"name": "a0", "channel": 0}, {"name": "a1", "channel": 1}],
        "transitions": {"matrix": [[0, -1, 1, 0], [1, 0, 0, -1], [-1, 0, 0, 1], [0, 0, 0, 0]]},
        "safety": {"max_on_ms": 50, "min_cooldown_ms": 20, "max_duty": 0.8, "state_timeout_ms": 200},
        "control": {
            "tick_hz": 1000,
            "drive_duty": 0.6,
            "debounce_ticks": 3,
            "hold_ms": 10,
            "telemetry_hz": 50,
            "hold_margin_deg": 1.0,
            "boost_ms": 0,  # the unit tests' rules are the drive duty's; r1-boost's config runs the boost
        },
    }
    doc.update(over)
    return doc


def gait(*states):
    return SimpleNamespace(states=tuple(states))


def r1_fast():
    robot = robot_from_dict(robot_doc(), Path("tests/r1-fast.toml"))
    return robot, {"+x": [gait(0, 2, 3, 1, 0), gait(0, 2, 0)], "-x": []}, SIM_BOARD


def r1_stroke():
    """R1 with full strokes ([[limb]] stroke_deg: left 60°, right 50°, the right leading the way
    down; test_ctl_stroke.c)."""
    doc = robot_doc()
    doc["limb"][0]["stroke_deg"] = 60.0
    doc["limb"][1]["stroke_deg"] = 50.0
    doc["control"]["stroke_fall_lead"] = "right"
    robot = robot_from_dict(doc, Path("tests/r1-stroke.toml"))
    return robot, {"+x": [gait(0, 3, 0)], "-x": []}, SIM_BOARD


def r1_heat():
    """r1-fast with the paper robots' envelope (max_on 3000 ms, min_cooldown 800 ms, state timeout
    8 s) and ``[safety] coil_heat_ceiling = true``: the coils' time constant CFG_COIL_TAU_MS is
    built into core/sma.c (test_sma_heat.c). No knee watch: the ceiling stands alone."""
    doc = robot_doc(safety={"max_on_ms": 3000, "min_cooldown_ms": 800, "max_duty": 0.8, "state_timeout_ms": 8000,
                            "coil_heat_ceiling": True})
    robot = robot_from_dict(doc, Path("tests/r1-heat.toml"))
    return robot, {"+x": [gait(0, 2, 3, 1, 0), gait(0, 2, 0)], "-x": []}, SIM_BOARD


def r1_swapped():
    """r1-fast with its coils crossed (left on a1, right on a0): a limb map that is not the
    identity, so the fallback's hold rule takes limbmap_given_up, not its identity shortcut
    (test_ctl_given_up.c)."""
    doc = robot_doc()
    doc["limb"][0]["actuator"] = "a1"
    doc["limb"][1]["actuator"] = "a0"
    robot = robot_from_dict(doc, Path("tests/r1-swapped.toml"))
    return robot, {"+x": [gait(0, 2, 3, 1, 0)], "-x": []}, SIM_BOARD


def r1_one_actuator():
    doc = robot_doc(
        actuator=[{"name": "a0", "channel": 0}],
        transitions={"matrix": [[0, "x", 1, "x"], ["x", "x", "x", "x"], [-1, "x", 0, 1], ["x", "x", 0, 0]]},
    )
    doc["limb"][1]["actuator"] = "a0"
    robot = robot_from_dict(doc, Path("tests/r1-1act.toml"))
    return robot, {"+x": [gait(0, 2, 3, 2, 0)], "-x": []}, SIM_BOARD


def r1_worn():
    """R1 with ψ* = 50°, within a worn coil's stroke loss of its own coil's reach (58° on the 80 mm body): the
    renderer builds the hold watch in (robot_body.worn_holds; test_ctl_hold.c)."""
    doc = robot_doc()
    for limb in doc["limb"]:
        limb["psi_star_deg"] = [50.0]
    doc["control"]["hold_margin_deg"] = 2.0
    robot = robot_from_dict(doc, Path("tests/r1-worn.toml"))
    return robot, {"+x": [gait(0, 2, 3, 1, 0)], "-x": []}, SIM_BOARD


def r1_boost():
    """r1-fast with control.boost_ms = 200: a lagging rise heats at the duty ceiling
    (test_ctl.c's boost test)."""
    doc = robot_doc()
    doc["control"]["boost_ms"] = 200
    robot = robot_from_dict(doc, Path("tests/r1-boost.toml"))
    return robot, {"+x": [gait(0, 2, 3, 1, 0)], "-x": []}, SIM_BOARD


def multi_level():
    doc = robot_doc(
        limb=[
            {"name": "left", "levels": 3, "psi_star_deg": [-10.0, 15.0], "hysteresis_deg": 4.0, "actuator": "a0"},
            {"name": "right", "psi_star_deg": [30.0], "hysteresis_deg": 2.0, "actuator": "a1"},
        ],
        transitions={"matrix": [[0 if a == b else 1 for b in range(6)] for a in range(6)]},
    )
    robot = robot_from_dict(doc, Path("tests/multi.toml"))
    return robot, {"+x": [gait(0, 3, 5, 0)], "-x": [gait(0, 1, 0)]}, SIM_BOARD


def big():
    """128 states (7 binary limbs): the allowed transitions become a sorted key list."""
    base = robot_from_dict(robot_doc(), Path("tests/big.toml"))
    limb = base.limbs[0]
    limbs = tuple(dataclasses.replace(limb, name=f"l{i}", actuator="a0") for i in range(7))
    src, dst = [], []
    for a in range(128):
        for b in {(a + 1) % 128, (3 * a + 7) % 128}:
            if a != b:
                src.append(a)
                dst.append(b)
    table = TransitionTable.from_edges((2,) * 7, src, dst, np.ones(len(src)))
    robot = dataclasses.replace(base, limbs=limbs, actuators=base.actuators[:1], transitions=table)
    board = dict(SIM_BOARD, i2c={"imu_addresses": list(range(0x68, 0x6F))})
    return robot, {"+x": [gait(0, 1, 0)], "-x": []}, board


def inchworm_entry():
    """robots/inchworm-3.toml with gaits off the rest state (entry paths, test_seq_entry.c)."""
    from proleg.robot import load_robot

    robot = load_robot(Path(__file__).resolve().parents[1] / "robots" / "inchworm-3.toml")
    board = dict(SIM_BOARD, i2c={"imu_addresses": [0x68, 0x69, 0x6A]})
    return robot, {"+x": [gait(3, 7, 3), gait(7, 3, 7)], "-x": [gait(1, 5, 1)]}, board


CONFIGS = {"inch-entry": inchworm_entry, "r1-fast": r1_fast, "r1-stroke": r1_stroke, "r1-heat": r1_heat, "r1-1act": r1_one_actuator, "r1-swapped": r1_swapped, "r1-worn": r1_worn, "r1-boost": r1_boost, "multi": multi_level, "big": big}


def renderer(tmp_path_factory) -> Callable[[str], Path]:
    """``get(name)``: config ``name`` (a key of CONFIGS) rendered into a directory of its own,
    once (the session fixture ``rendered`` of the tests that build against it)."""
    cache: dict[str, Path] = {}

    def get(name: str) -> Path:
        if name not in cache:
            robot, gaits, board = CONFIGS[name]()
            out = tmp_path_factory.mktemp(f"cfg-{name}")
            for fname, text in render_config(robot, gaits, board).items():
                (out / fname).write_text(text)
            for fname, text in render_c(len(robot.limbs), len(robot.actuators)).items():
                (out / fname).write_text(text)
            cache[name] = out
        return cache[name]

    return get
