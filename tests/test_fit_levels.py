"""The Nano's static RAM and a robot of many levels: psi.c keeps a ψ band of 28 B per limb and
threshold, for every limb up to the robot's most thresholds. The estimate before compiling left
them out, so four limbs of 10, 2, 2, 2 levels passed it and failed to link ("compilation failed"
and four ld lines about .bss outside region data); now the estimate refuses it in one line, and a
link that still overflows (whatever the estimate missed) says the robot does not fit."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from proleg.errors import BuildError
from proleg.firmware import fit
from proleg.firmware.boards import load_board
from proleg.firmware.build import build
from proleg.firmware.gaits import firmware_gaits
from proleg.robot import load_robot


def _robot(tmp_path: Path, levels: list[int]) -> Path:
    """Limbs of ``levels`` on one coil each, ψ* 3° apart, three transitions in a CSV."""
    out = ['[robot]\nname = "many-levels"\n']
    for i, n in enumerate(levels):
        psi = [3.0 + 3.0 * k for k in range(n - 1)]
        out.append(f'[[limb]]\nname = "l{i}"\nlevels = {n}\npsi_star_deg = {psi}\nactuator = "a{i}"\n'
                   'hysteresis_deg = 1.0\n')
    out += [f'[[actuator]]\nname = "a{i}"\n' for i in range(len(levels))]
    out.append('[transitions]\nfile = "t.csv"\n[control]\ntick_hz = 500\nhold_margin_deg = 0.5\n')
    z, one, two = "0" * len(levels), "1" + "0" * (len(levels) - 1), "11" + "0" * (len(levels) - 2)
    (tmp_path / "t.csv").write_text(f"from,to,reward\n{z},{one},1\n{one},{two},1\n{two},{z},1\n")
    path = tmp_path / "many.toml"
    path.write_text("".join(out))
    return path


def test_the_ram_estimate_counts_each_limbs_bands_up_to_the_most_thresholds(tmp_path):
    nano = load_board("arduino-nano")
    robot = load_robot(_robot(tmp_path, [10, 2, 2, 2]))
    # the board's measured base (R1's image) plus the bands of 4 limbs up to 9 thresholds each
    needs = f"{nano.base_ram_bytes + 1206:,}"
    with pytest.raises(BuildError, match=r"^robot many-levels does not fit board arduino-nano \(estimated before "
                                         r"compiling, 4 limbs of up to 10 levels\): robot many-levels needs "
                                         + needs + r" bytes of static RAM and 320 for its stack"):
        fit.check_fit(robot, nano, firmware_gaits(robot))
    two = load_robot(_robot(tmp_path, [2, 2, 2, 2]))
    assert fit.check_fit(two, nano, firmware_gaits(two)).ram_estimate == nano.base_ram_bytes + 2 * 155


@pytest.mark.skipif(shutil.which("avr-gcc") is None, reason="no avr-gcc")
def test_a_link_past_the_boards_ram_is_one_line_saying_the_robot_does_not_fit(tmp_path, monkeypatch):
    monkeypatch.setattr(fit, "RAM_PER_BAND", 0)  # an estimate that misses something: the linker finds it
    robot = load_robot(_robot(tmp_path, [10, 2, 2, 2]))
    out = tmp_path / "out"
    with pytest.raises(BuildError) as e:
        build(robot, load_board("arduino-nano"), out)
    msg = str(e.value)
    assert msg.startswith("robot many-levels does not fit board arduino-nano: the linker puts the firmware past "
                          "the board's memory ("), msg
    assert "\n" not in msg and "compilation failed" not in msg, msg
    assert not out.exists()


def test_a_flash_dry_run_refuses_a_robot_the_ram_estimate_refuses(capsys, tmp_path):
    """flash --dry-run names what the build would refuse: it printed an avrdude command and exit 0
    for the robot above, which the build refuses for its static RAM."""
    from build_checks import cli, one_line

    path = _robot(tmp_path, [10, 2, 2, 2])
    code, out, err = cli(capsys, "flash", path, "--board", "arduino-nano", "--port", "/dev/ttyUSB0", "--dry-run",
                         "-o", tmp_path / "fw")
    assert code == 2 and out == "", out
    needs = f"{load_board('arduino-nano').base_ram_bytes + 1206:,}"
    assert "robot many-levels does not fit board arduino-nano" in one_line(err) and f"{needs} bytes of static RAM" in err
    assert not (tmp_path / "fw").exists()
    code, out, _ = cli(capsys, "flash", _robot(tmp_path, [3, 2]), "--board", "arduino-nano", "--port",
                       "/dev/ttyUSB0", "--dry-run", "-o", tmp_path / "fw")
    assert code == 0 and out.startswith("avrdude ")


def test_a_table_of_allowed_transitions_too_big_for_any_gaits_says_to_forbid_transitions(tmp_path):
    """Eight binary limbs allowing any transition: the sorted key list of 65,280 transitions
    takes 261,120 B, four times the bluepill's flash. The refusal advised fewer gaits
    (--max-transitions, another objective), which cannot make it fit; it now names the
    allowed transitions and how to forbid them. A robot whose gaits are what overflows keeps
    the advice about gaits."""
    out = ['[robot]\nname = "eight-any"\n']
    for i in range(8):
        out.append(f'[[limb]]\nname = "l{i}"\npsi_star_deg = [20.0]\nactuator = "a{i}"\nfriction = "D1"\n')
    out += [f'[[actuator]]\nname = "a{i}"\n' for i in range(8)]
    out.append('[transitions]\nmatrix = "unmeasured"\nallow = "any"\n[control]\ntick_hz = 200\n')
    path = tmp_path / "eight.toml"
    path.write_text("".join(out))
    robot = load_robot(path)
    no_gaits = {"+x": [], "-x": []}
    with pytest.raises(BuildError) as e:
        fit.check_fit(robot, load_board("bluepill-f103"), no_gaits)
    msg = str(e.value)
    assert "its 65,280 allowed transitions alone take 261,120 bytes" in msg and "allow = \"one-level\"" in msg, msg
    assert "fewer gaits" not in msg and "\n" not in msg, msg

    r1 = load_robot(Path(__file__).resolve().parents[1] / "robots" / "paper-r1.toml")
    from types import SimpleNamespace

    big = {"+x": [SimpleNamespace(states=tuple([0, 1] * 12000 + [0]))], "-x": []}
    with pytest.raises(BuildError, match=r"fewer gaits: --max-transitions or another objective"):
        fit.check_fit(r1, load_board("arduino-nano"), big)
