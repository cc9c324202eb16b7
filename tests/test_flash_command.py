"""``proleg flash``: the exact command each board's flash tool is given (--dry-run), and one
clear error, with nothing built or left behind, for every way a flash can fail before or
while the tool runs (no port, a board that is not flashed, a missing tool or port, no
artifact, a tool that fails)."""

from __future__ import annotations

from pathlib import Path

import pytest

from build_checks import R1, assert_nothing_left, board_variant, cli, empty_build_dir, one_line
from proleg.errors import BuildError, LinkError
from proleg.firmware.boards import load_board
from proleg.firmware.flash import choose_method, flash, flash_command


@pytest.fixture
def parent(tmp_path: Path) -> Path:
    return empty_build_dir(tmp_path)


def test_flash_dry_run_prints_the_exact_avrdude_command(capsys, parent):
    out = parent / "fw"
    code, stdout, err = cli(capsys, "flash", R1, "--board", "arduino-nano", "--port", "/dev/ttyUSB0",
                            "--dry-run", "-o", out)
    assert code == 0, err
    assert stdout.strip() == (f"avrdude -p atmega328p -c arduino -P /dev/ttyUSB0 -b 115200 -D "
                              f"-U flash:w:{out}/firmware.hex:i")
    assert_nothing_left(parent)  # a dry run builds nothing


def test_flash_dry_run_prints_the_exact_openocd_and_pyocd_commands(capsys, parent):
    out = parent / "fw"
    code, stdout, err = cli(capsys, "flash", R1, "--board", "bluepill-f103", "--dry-run", "-o", out)
    assert code == 0, err
    assert stdout.strip() == ("openocd -f interface/stlink.cfg -f target/stm32f1x.cfg "
                              f"-c 'program {out}/firmware.bin 0x08000000 verify reset exit'")
    code, stdout, err = cli(capsys, "flash", R1, "--board", "bluepill-f103", "--tool", "pyocd", "--dry-run", "-o", out)
    assert code == 0, err
    assert stdout.strip() == f"pyocd flash --target stm32f103c8 --base-address 0x08000000 {out}/firmware.bin"
    code, _, err = cli(capsys, "flash", R1, "--board", "bluepill-f103", "--tool", "stlink", "--dry-run")
    assert code == 2 and "no flash tool 'stlink'" in one_line(err) and "openocd, pyocd" in err


def test_a_port_given_to_a_tool_that_takes_none_is_refused_before_anything_is_built(capsys, parent):
    """It was dropped: the bluepill's default openocd flashed over the ST-Link whatever serial
    port --port named, and the dry run printed openocd's command, exit 0."""
    for dry in (("--dry-run",), ()):
        code, stdout, err = cli(capsys, "flash", R1, "--board", "bluepill-f103", "--port", "/dev/ttyUSB0", *dry,
                                "-o", parent / "fw")
        assert code == 2 and stdout == "", err
        assert one_line(err) == ("proleg: error: --port /dev/ttyUSB0: openocd takes no serial port; --tool "
                                 "stm32flash flashes through a serial port; or leave --port out")
    assert_nothing_left(parent)


def test_a_dry_run_refuses_what_the_build_would_refuse(capsys, parent, tmp_path):
    """With -o the dry run never read the robot file: a missing or broken one, or one the board
    cannot take, printed an avrdude command and exit 0."""
    out = parent / "fw"
    code, stdout, err = cli(capsys, "flash", tmp_path / "missing.toml", "--board", "arduino-nano",
                            "--port", "/dev/ttyUSB0", "--dry-run", "-o", out)
    assert code == 2 and stdout == "" and "no such robot file" in one_line(err)
    five = tmp_path / "five-channels.toml"  # an actuator on channel 4: the Nano has 0..3
    five.write_text(R1.read_text(encoding="utf-8").replace("channel = 1", "channel = 4"), encoding="utf-8")
    code, stdout, err = cli(capsys, "flash", five, "--board", "arduino-nano", "--port", "/dev/ttyUSB0",
                            "--dry-run", "-o", out)
    assert code == 2 and stdout == "" and "board arduino-nano has 4 PWM channels" in one_line(err)
    fast = tmp_path / "fast.toml"
    fast.write_text(R1.read_text(encoding="utf-8").replace("tick_hz = 1000", "tick_hz = 1500"), encoding="utf-8")
    code, stdout, err = cli(capsys, "flash", fast, "--board", "arduino-nano", "--port", "/dev/ttyUSB0",
                            "--dry-run", "-o", out)
    assert code == 2 and stdout == "" and "control.tick_hz = 1500 is too fast for board arduino-nano" in one_line(err)
    assert_nothing_left(parent)


def test_a_dry_run_refuses_a_tick_rate_the_imus_i2c_reads_do_not_fit(capsys, parent, tmp_path):
    """R1 at 3000 Hz passes the bluepill's [budget] (6666 Hz) but not its I2C reads (at most
    1785 Hz), which the build refuses before compiling (check_fit): the dry run said exit 0."""
    fast = tmp_path / "fast.toml"
    fast.write_text(R1.read_text(encoding="utf-8").replace("tick_hz = 1000", "tick_hz = 3000"), encoding="utf-8")
    code, stdout, err = cli(capsys, "flash", fast, "--board", "bluepill-f103", "--dry-run", "-o", parent / "fw")
    assert code == 2 and stdout == "" and "set control.tick_hz to at most 1785" in one_line(err)
    assert_nothing_left(parent)


def test_avrdude_without_a_port_is_a_clear_error(capsys, parent):
    code, _, err = cli(capsys, "flash", R1, "--board", "arduino-nano", "--dry-run", "-o", parent / "fw")
    assert code == 2
    assert "avrdude needs the board's serial port: give --port" in one_line(err)
    method = choose_method(load_board("arduino-nano"))
    with pytest.raises(BuildError, match="give --port"):
        flash_command(method, parent / "firmware.hex", None)
    assert_nothing_left(parent)


def test_flashing_host_sim_is_a_clear_error(capsys, parent):
    code, _, err = cli(capsys, "flash", R1, "--board", "host-sim", "--dry-run", "-o", parent / "fw")
    assert code == 2 and "host-sim is not flashed: the simulator loads it" in one_line(err)
    code, _, err = cli(capsys, "flash", R1, "--board", "host-sim", "-o", parent / "fw")
    assert code == 2 and "not flashed" in one_line(err)
    assert_nothing_left(parent)


@pytest.fixture
def fake_hex(tmp_path) -> Path:
    """An artifact to hand to flash(): the flash checks come before any tool reads it."""
    p = tmp_path / "firmware.hex"
    p.write_text(":00000001FF\n")
    return p


def test_missing_flash_tool_is_named(tmp_path, fake_hex):
    board = board_variant(tmp_path, "arduino-nano", (r'^command = \["avrdude"', 'command = ["avrdude-missing-xyz"'))
    method = choose_method(load_board(board))
    with pytest.raises(BuildError, match=r"^avrdude-missing-xyz not found: install it to flash \(Debian package: avrdude\)"):
        flash(method, fake_hex, "/dev/ttyUSB0")


def test_nonexistent_port_is_a_clear_error(tmp_path, fake_hex):
    # A stand-in tool that exists ("true"), so the port check is what stops the flash.
    board = board_variant(tmp_path, "arduino-nano", (r'^command = \["avrdude"', 'command = ["true"'))
    method = choose_method(load_board(board))
    with pytest.raises(BuildError, match=r"^/dev/ttyNOPE-proleg-test: no such serial port"):
        flash(method, fake_hex, "/dev/ttyNOPE-proleg-test")
    flash(method, fake_hex, "/dev/null")  # an existing port and a tool that succeeds: no error


def test_missing_artifact_and_failing_tool_are_clear_errors(tmp_path, fake_hex):
    board = board_variant(tmp_path, "arduino-nano", (r'^command = \["avrdude"', 'command = ["false"'))
    method = choose_method(load_board(board))
    with pytest.raises(BuildError, match=r"no firmware to flash \(build it first\)"):
        flash(method, tmp_path / "missing.hex", "/dev/null")
    # the tool ran and failed (no sync, a verify error): a failure (exit 1), not a usage error (2)
    with pytest.raises(LinkError, match=r"^false failed with exit status 1 \(its messages are above\)$"):
        flash(method, fake_hex, "/dev/null")


@pytest.mark.parametrize("name", ["my robots", "lab {x} [1] $HOME; \"q\"", "tab\there"])
def test_openocd_gets_the_artifact_as_one_tcl_word(tmp_path, name):
    """openocd's ``-c 'program {artifact} ...'`` is a Tcl script: a build directory with a space
    in its path ('program my robots/firmware.bin 0x08000000 ...') handed ``program`` the file
    'my' and the address 'robots/firmware.bin', and the flash failed. Tcl itself reads the
    command back: one file name, the whole path, then the address and the options."""
    tkinter = pytest.importorskip("tkinter")
    try:
        tcl = tkinter.Tcl()
    except tkinter.TclError:
        pytest.skip("no Tcl library")
    artifact = tmp_path / name / "firmware.bin"
    method = choose_method(load_board("bluepill-f103"), "openocd")
    script = flash_command(method, artifact, None)[-1]
    tcl.eval("proc program {args} {return $args}")
    words = tcl.splitlist(tcl.eval(script))
    assert list(words) == [str(artifact), "0x08000000", "verify", "reset", "exit"]
    # a tool given the path as a whole argument gets it unchanged
    pyocd = choose_method(load_board("bluepill-f103"), "pyocd")
    assert str(artifact) in flash_command(pyocd, artifact, None)
    nano = choose_method(load_board("arduino-nano"))
    assert f"flash:w:{artifact}:i" in flash_command(nano, artifact, "/dev/ttyUSB0")


def _tool_script(tmp_path: Path, body: str) -> Path:
    tool = tmp_path / "fake-avrdude"
    tool.write_text("#!/bin/sh\n" + body + "\n")
    tool.chmod(0o755)
    return tool


def test_a_flash_tool_killed_by_a_signal_is_named_so(tmp_path, fake_hex):
    """A tool killed mid-write (the OOM killer, a kill -9) was reported as 'exit status -9'."""
    tool = _tool_script(tmp_path, "kill -9 $$")
    board = board_variant(tmp_path, "arduino-nano", (r'^command = \["avrdude"', f'command = ["{tool}"'))
    method = choose_method(load_board(board))
    with pytest.raises(LinkError) as e:
        flash(method, fake_hex, "/dev/null")
    assert str(e.value) == (f"{tool} was killed by SIGKILL (its messages are above); the board's flash may hold part "
                            "of the firmware: flash it again")


def test_a_flash_interrupted_while_the_tool_writes_says_the_board_may_hold_half_a_firmware(tmp_path, fake_hex,
                                                                                           monkeypatch):
    """Ctrl-C or SIGTERM while avrdude wrote said only 'proleg: interrupted', nothing about the board."""
    import subprocess

    from proleg.errors import Interrupted

    def ctrl_c(*args, **kwargs):
        raise KeyboardInterrupt

    board = board_variant(tmp_path, "arduino-nano", (r'^command = \["avrdude"', 'command = ["true"'))
    method = choose_method(load_board(board))
    monkeypatch.setattr(subprocess, "run", ctrl_c)
    with pytest.raises(Interrupted) as e:
        flash(method, fake_hex, "/dev/null")
    assert str(e.value) == (f"interrupted while true was flashing {fake_hex}: the board's flash may hold part of it "
                            "(flash it again before using the board)")


def test_a_missing_flash_tool_or_port_is_said_before_anything_is_built(tmp_path, capsys, monkeypatch):
    """proleg flash built the firmware (seconds, a build directory) and only then said the tool
    was not installed or the port not there."""
    from proleg.firmware import build as build_module

    def build(*args, **kwargs):  # pragma: no cover (must not be reached)
        raise AssertionError("built before checking the tool")

    monkeypatch.setattr(build_module, "build", build)
    monkeypatch.setenv("PATH", str(tmp_path))  # no openocd, no avrdude
    out = tmp_path / "fw"
    code, _, err = cli(capsys, "flash", R1, "--board", "bluepill-f103", "-o", out)
    assert code == 2 and err == "proleg: error: openocd not found: install it to flash (Debian package: openocd)\n"
    code, _, err = cli(capsys, "flash", R1, "--board", "arduino-nano", "--port", "/dev/ttyNOPE-proleg", "-o", out)
    assert code == 2 and "avrdude not found" in err
    assert not out.exists()


def test_a_dry_run_refuses_what_the_build_refuses_before_compiling(capsys, parent, tmp_path):
    """The dry run checked the board and the robot file but not the rest of what the build
    refuses before compiling: it printed a command and exit 0 for tables four times the
    bluepill's flash, --objective speed on a file without durations, a --library heading the
    file has no dy for, and an -o the build will not replace or whose folder does not exist."""
    eight = ['[robot]\nname = "eight-any"\n']
    for i in range(8):
        eight.append(f'[[limb]]\nname = "l{i}"\npsi_star_deg = [20.0]\nactuator = "a{i}"\nfriction = "D1"\n')
    eight += [f'[[actuator]]\nname = "a{i}"\n' for i in range(8)]
    eight.append('[transitions]\nmatrix = "unmeasured"\nallow = "any"\n[control]\ntick_hz = 200\n')
    big = tmp_path / "eight.toml"
    big.write_text("".join(eight), encoding="utf-8")
    out = parent / "fw"
    foreign = tmp_path / "not-a-build"
    foreign.mkdir()
    cases = [
        ((big, "--board", "bluepill-f103"), "robot eight-any does not fit board bluepill-f103"),
        ((R1, "--board", "bluepill-f103", "--objective", "speed"), "gives no transition durations"),
        ((R1, "--board", "bluepill-f103", "--library", "0,90"), "heading 90° (off the x axis) needs [transitions].dy"),
    ]
    for argv, expected in cases:
        code, stdout, err = cli(capsys, "flash", *argv, "--dry-run", "-o", out)
        assert code == 2 and stdout == "" and expected in one_line(err), (argv, err)
        build_code, _, build_err = cli(capsys, "build", *argv, "-o", out)
        assert build_code == 2 and expected in one_line(build_err), (argv, build_err)
    code, stdout, err = cli(capsys, "flash", R1, "--board", "bluepill-f103", "--dry-run", "-o", foreign)
    assert code == 2 and stdout == "" and "is not a proleg build directory" in one_line(err)
    code, stdout, err = cli(capsys, "flash", R1, "--board", "bluepill-f103", "--dry-run", "-o", tmp_path / "no" / "fw")
    assert code == 2 and stdout == "" and "does not exist" in one_line(err)
    assert_nothing_left(parent)
