"""``proleg sim --board``: the simulated-board registry (host-sim, avr-emu, arm-emu) and what
the emulated MCUs add to the report (the tick budget, measured in emulated CPU cycles)."""

from __future__ import annotations

import json

import numpy as np
import pytest
from build_checks import cli as run

from proleg.cli import main
from proleg.errors import SimError
from proleg.paths import robots_dir
from proleg.report.gait_run import STOP_TAIL_S
from proleg.sim.simulated_boards import SIMULATED_BOARDS, SimulatedBoard, simulated_board, simulated_robot

R1 = str(robots_dir() / "paper-r1.toml")


def needs(board: str):
    reason = SIMULATED_BOARDS[board].missing()
    return pytest.mark.skipif(reason is not None, reason=reason or "")


def test_every_simulated_board_runs_firmware_built_for_a_board_file():
    from proleg.firmware.boards import load_board

    assert list(SIMULATED_BOARDS) == ["host-sim", "avr-emu", "arm-emu"]
    for entry in SIMULATED_BOARDS.values():
        assert load_board(entry.firmware_board).name == entry.firmware_board
    assert [b.name for b in SIMULATED_BOARDS.values() if b.emulated] == ["avr-emu", "arm-emu"]


def test_an_unknown_simulated_board_is_one_line_naming_the_choices():
    with pytest.raises(SimError, match=r"unknown simulated board 'uno' \(expected one of: host-sim, avr-emu, arm-emu\)"):
        simulated_board("uno")


def test_a_board_whose_emulator_is_not_installed_says_what_to_install():
    entry = SimulatedBoard("x-emu", "nowhere:Nothing", "host-sim", "test", emulated=True,
                           needs="the Debian package x", requires=("/nonexistent/x.h", "py:no_such_module_x", "cc"))
    assert entry.missing() == "board x-emu needs /nonexistent/x.h, no_such_module_x: install the Debian package x"


def test_proleg_sim_refuses_an_unknown_board_as_a_usage_error(capsys):
    with pytest.raises(SystemExit) as e:
        main(["sim", R1, "--board", "uno"])
    assert e.value.code == 2
    assert "invalid choice: 'uno'" in capsys.readouterr().err


def test_host_sim_reports_no_tick_budget(capsys):
    code, out, err = run(capsys, "sim", R1, "--duration", "1", "--json")
    assert code == 0, err
    doc = json.loads(out)
    assert doc["board"] == "host-sim"
    assert "tick_busy_us" not in doc and "tick_period_us" not in doc


def test_the_tick_period_is_a_float_in_the_json_of_both_emulated_mcus():
    """The sweep's 7: arm-emu gave tick_period_us as an int (1000), avr-emu as a float
    (1000.0; 1e6 / tick_hz need not be whole, 398 Hz is 2512.563 µs): one type in the JSON."""
    from types import SimpleNamespace

    from proleg.emu.arm.ticks import TickBudget as ArmBudget
    from proleg.emu.avr.budget import summarize
    from proleg.sim.simulated_boards import tick_budget

    arm = ArmBudget(1000, 5, 100.0, 120.0, 130.0)
    avr = summarize(np.array([0, 16000, 32000]), np.array([1600, 1700, 1800]), np.array([800, 800, 800]),
                    freq_hz=16_000_000, tick_period_us=1e6 / 398, stack_peak_bytes=100, stack_margin_bytes=900,
                    emulated_s=1.0, wall_s=1.0, cpu_s=1.0)
    docs = [json.loads(json.dumps(tick_budget(SimpleNamespace(board=SimpleNamespace(tick_budget=lambda b=b: b)))))
            for b in (arm, avr)]
    assert [type(d["tick_period_us"]) for d in docs] == [float, float]
    assert docs[0]["tick_period_us"] == 1000.0 and docs[1]["tick_period_us"] == 2512.563
    assert [type(d["tick_busy_us"]["ticks"]) for d in docs] == [int, int]
    assert json.dumps(arm.as_dict()).startswith('{"tick_period_us": 1000.0,')


def _check_budget(doc: dict, duration_s: float) -> None:
    assert doc["tick_period_us"] == 1000 and isinstance(doc["tick_period_us"], float)  # paper-r1: tick_hz = 1000
    busy = doc["tick_busy_us"]
    assert 0 < busy["mean"] <= busy["p99"] <= busy["max"]
    # one record per completed tick over the run (START, the gait, STOP and its tail);
    # overrunning ticks make fewer records than periods
    run_s = duration_s + STOP_TAIL_S + 0.02
    assert 0.5 * duration_s * 1000 < busy["ticks"] <= run_s * 1000


@pytest.mark.parametrize("board", [pytest.param("avr-emu", marks=needs("avr-emu")),
                                   pytest.param("arm-emu", marks=needs("arm-emu"))])
def test_proleg_sim_on_an_emulated_mcu_walks_injects_faults_and_reports_the_tick_budget(capsys, board):
    code, out, err = run(capsys, "sim", R1, "--board", board, "--duration", "1.5", "--json",
                         "--inject", "imu-silent:right+1.0")
    doc = json.loads(out)
    assert doc["board"] == board
    assert doc["states_reached"][:2] == ["00", "10"] and doc["true_transitions"] >= 1  # it walked
    # the injection reached the bus: between reads the IMU's address is not ACKed (IMU_NO_ACK);
    # silenced in the middle of a burst read, the rest of the bytes read 0xFF from the pull-ups,
    # |g| out of range (IMU_BAD_DATA). Which one depends on where the reads fall against t = 1.0 s.
    assert [f["code"] for f in doc["faults"]][:1] in (["IMU_NO_ACK"], ["IMU_BAD_DATA"])
    assert code == 1  # a faulted run fails
    _check_budget(doc, 1.5)


@needs("avr-emu")
def test_proleg_sim_text_report_names_the_board_and_the_tick_budget(capsys):
    code, out, err = run(capsys, "sim", R1, "--board", "avr-emu", "--duration", "0.5")
    assert code == 0, err
    assert out.startswith("paper-r1 on avr-emu: gait 0 in +x for 0.5 s (simulated)")
    assert "  tick busy (µs of a 1000 µs tick, " in out


@needs("avr-emu")
def test_the_registry_puts_the_exact_nano_firmware_in_closed_loop_with_the_plant():
    from proleg.emu.avr import AvrEmuBoard
    from proleg.robot import load_robot

    sim = simulated_robot("avr-emu", load_robot(R1), seed=3)
    assert isinstance(sim.board, AvrEmuBoard) and sim.board.elf.name == "firmware.elf"
    assert sim.board_info.name == "arduino-nano"
    sim.advance(0.05)
    assert sim.board.read()  # INFO and BOOT went out over the emulated UART
