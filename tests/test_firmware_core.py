"""Host unit tests of the hand-written firmware core (firmware_templates/core, hal/sim).

Each C test in tests/c/ is compiled with the host cc (C99, -Wall -Wextra -Werror -pedantic,
AddressSanitizer/UBSan when the compiler has them) against a robot_config.h/gait_table.c
rendered by ``render_config`` from one of the small robots of core_configs.py, then run;
its output names every C test case. Then the renderer's own checks. The whole firmware on
the simulated board is tested in test_firmware_on_sim_board.py.
"""

from __future__ import annotations

import subprocess
from pathlib import Path

import pytest

from core_configs import CC, CORE, SIM, SIM_BOARD, r1_fast, renderer, robot_doc
from proleg.errors import BuildError
from proleg.firmware.render import render_config
from proleg.robot import robot_from_dict

CDIR = Path(__file__).resolve().parent / "c"
CFLAGS = ["-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic", "-g", "-O1"]

pytestmark = pytest.mark.skipif(CC is None, reason="no host C compiler")

# C test (FILE, or FILE@NAME: the same file against another config) → (config, core sources,
# extra sources, defines)
C_TESTS = {
    "test_psi.c": ("r1-fast", ["psi.c", "angle.c"], [], []),
    "test_psi_multilevel.c": ("multi", ["psi.c", "angle.c", "seq.c", "count.c"], ["gait_table.c"], []),
    "test_sma.c": ("r1-fast", ["sma.c", "elapsed.c"], [], []),
    "test_sma_heat.c": ("r1-heat", ["sma.c", "elapsed.c"], [], []),
    "test_sma_kept.c": ("r1-fast", ["elapsed.c"], [], []),  # includes sma.c: writes its kept RAM
    "test_sma_kept.c@r1-heat": ("r1-heat", ["elapsed.c"], [], []),
    "test_safety.c": ("r1-fast", ["safety.c", "elapsed.c"], [], []),
    "test_ctl.c": ("r1-fast", ["ctl.c", "stall.c", "psi.c", "angle.c", "limbmap.c", "sma.c", "elapsed.c"], [], []),
    "test_ctl_shared.c": ("r1-1act", ["ctl.c", "stall.c", "psi.c", "angle.c", "limbmap.c", "sma.c", "elapsed.c"], [], []),
    "test_ctl.c@r1-boost": ("r1-boost", ["ctl.c", "stall.c", "psi.c", "angle.c", "limbmap.c", "sma.c", "elapsed.c"], [], []),
    "test_ctl_given_up.c": ("r1-fast", ["ctl.c", "stall.c", "psi.c", "angle.c", "limbmap.c", "sma.c", "elapsed.c"], [], []),
    "test_ctl_given_up.c@r1-swapped": ("r1-swapped", ["ctl.c", "stall.c", "psi.c", "angle.c", "limbmap.c", "sma.c", "elapsed.c"],
                                       [], ["-DTEST_SWAPPED"]),
    "test_ctl_hold.c": ("r1-worn", ["ctl.c", "stall.c", "psi.c", "angle.c", "limbmap.c", "sma.c", "elapsed.c"], [], []),
    "test_ctl_stroke.c": ("r1-stroke", ["ctl.c", "stall.c", "psi.c", "angle.c", "limbmap.c", "sma.c", "elapsed.c"], [], []),
    "test_ctl_chain.c": ("inch-entry", ["ctl.c", "stall.c", "psi.c", "angle.c", "limbmap.c", "sma.c", "elapsed.c"], [], []),
    "test_stall.c": ("r1-fast", ["stall.c", "ctl.c", "psi.c", "angle.c", "limbmap.c", "sma.c", "elapsed.c"], [], []),
    "test_stall.c@r1-stroke": ("r1-stroke", ["stall.c", "ctl.c", "psi.c", "angle.c", "limbmap.c", "sma.c", "elapsed.c"], [], []),
    "test_seq.c": ("r1-fast", ["seq.c", "psi.c", "angle.c", "count.c"], ["gait_table.c"], []),
    "test_seq_transitions.c": ("r1-1act", ["seq.c", "psi.c", "angle.c", "count.c"], ["gait_table.c"], []),
    "test_seq_edges.c": ("big", ["seq.c", "psi.c", "angle.c", "count.c"], ["gait_table.c"], []),
    "test_seq_entry.c": ("inch-entry", ["seq.c", "psi.c", "angle.c", "count.c"], ["gait_table.c"], []),
    "test_sim_mpu6050.c": ("r1-fast", ["mpu6050.c", "imubus.c"], [SIM / "sim_mpu6050.c"], ["-DFAKE_HAL_SIM_MPU"]),
}


@pytest.fixture(scope="session")
def sanitizers(tmp_path_factory) -> list[str]:
    flags = ["-fsanitize=address,undefined", "-fno-omit-frame-pointer"]
    d_ = tmp_path_factory.mktemp("san")
    (d_ / "t.c").write_text("int main(void) { return 0; }\n")
    ok = subprocess.run([CC, *flags, str(d_ / "t.c"), "-o", str(d_ / "t")], capture_output=True).returncode == 0
    return flags if ok else []


@pytest.fixture(scope="session")
def rendered(tmp_path_factory):
    return renderer(tmp_path_factory)


@pytest.mark.parametrize("test_file", sorted(C_TESTS))
def test_c_unit(test_file, rendered, sanitizers, tmp_path):
    config, core, extra, defines = C_TESTS[test_file]
    gen = rendered(config)
    sources = [CDIR / test_file.split("@")[0], CDIR / "fake_hal.c"] + [CORE / c for c in core]
    sources += [gen / e if isinstance(e, str) else e for e in extra]
    exe = tmp_path / test_file.split("@")[0].removesuffix(".c")
    cmd = [CC, *CFLAGS, *sanitizers, *defines, f"-I{CORE}", f"-I{gen}", f"-I{SIM}", f"-I{CDIR}"]
    cmd += [str(s) for s in sources] + ["-o", str(exe), "-lm"]
    build = subprocess.run(cmd, capture_output=True, text=True)
    assert build.returncode == 0, build.stderr
    run = subprocess.run([str(exe)], capture_output=True, text=True, timeout=120)
    print(run.stdout)
    assert run.returncode == 0, run.stdout + run.stderr
    assert "FAIL" not in run.stdout


def test_render_is_deterministic_and_names_its_inputs():
    robot, gaits, board = r1_fast()
    a = render_config(robot, gaits, board)
    b = render_config(robot, gaits, board)
    assert a == b
    assert set(a) == {"robot_config.h", "gait_table.c"}
    head = a["robot_config.h"].splitlines()[:4]
    assert any("proleg.firmware.render" in line for line in head)
    assert any("sha256" in line for line in head)
    assert "#define CFG_GAIT_TABLE_HASH 0x" in a["robot_config.h"]


def test_entry_path_code_is_rendered_only_for_gaits_entered_off_their_step_0():
    """CFG_ENTRY_PATHS 0 (core/seq.c without its entry-path code) only where seq_entry_* would
    change nothing: no entry states and every join step 0 (R1: rest is on both gaits)."""
    from core_configs import inchworm_entry

    pick = lambda t: [line for line in t.splitlines() if line.startswith("#define CFG_ENTRY_PATHS")]  # noqa: E731
    assert pick(render_config(*r1_fast())["robot_config.h"]) == ["#define CFG_ENTRY_PATHS 0"]
    assert pick(render_config(*inchworm_entry())["robot_config.h"]) == ["#define CFG_ENTRY_PATHS 1"]


def test_gait_hash_changes_with_the_gaits_but_build_inputs_do_not_leak_time():
    robot, gaits, board = r1_fast()
    a = render_config(robot, gaits, board)["robot_config.h"]
    b = render_config(robot, {"+x": gaits["+x"][:1], "-x": []}, board)["robot_config.h"]
    pick = lambda t: [line for line in t.splitlines() if "CFG_GAIT_TABLE_HASH" in line]  # noqa: E731
    assert pick(a) != pick(b)


def test_render_refuses_a_channel_the_board_lacks():
    robot, gaits, board = r1_fast()
    with pytest.raises(BuildError, match="channel"):
        render_config(robot, gaits, dict(board, pwm_channels=["SIM0"]))


def test_render_refuses_a_pin_the_avr_hal_cannot_drive():
    robot, gaits, board = r1_fast()
    avr = dict(board, name="nano", family="avr", pwm_channels=["D9", "D7"])
    with pytest.raises(BuildError, match="D7"):
        render_config(robot, gaits, avr)


def test_render_refuses_a_band_reaching_90_degrees():
    """The loader refuses such a file (tests/test_robot_file.py); a Robot made otherwise is
    still refused by the renderer, whose C would otherwise wrap the band's edge."""
    from dataclasses import replace

    robot = robot_from_dict(robot_doc(), Path("tests/steep.toml"))
    steep = replace(robot, limbs=(replace(robot.limbs[0], psi_star_deg=(89.5,)), *robot.limbs[1:]))
    with pytest.raises(BuildError, match="90"):
        render_config(steep, {"+x": [], "-x": []}, SIM_BOARD)


def test_no_gait_in_either_direction_still_renders_valid_c(rendered, tmp_path):
    robot, _, board = r1_fast()
    files = render_config(robot, {"+x": [], "-x": []}, board)
    assert "#define CFG_N_GAITS_PX 0u" in files["robot_config.h"]
    for name, text in files.items():
        (tmp_path / name).write_text(text)
    r = subprocess.run(
        [CC, *CFLAGS, f"-I{CORE}", f"-I{tmp_path}", "-c", str(tmp_path / "gait_table.c"), "-o", str(tmp_path / "g.o")],
        capture_output=True,
        text=True,
    )
    assert r.returncode == 0, r.stderr
