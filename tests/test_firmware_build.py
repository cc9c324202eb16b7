"""Firmware builds: every example robot for every board, deterministic rendering, and
one clear error (with nothing left behind) for every way a build can fail. Flashing is in
test_flash_command.py, board-file mistakes in test_board_files.py.

Every build goes to its own ``tmp_path``; no test shares state with another, so the
file runs under pytest-xdist (``-n 2``) as well as serially. Size *targets* (R1 in
12 KB on the Nano, ...) are in bench/bench_firmware.py; here only the board limits.
"""

from __future__ import annotations

import hashlib
import json
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from build_checks import R1, ROOT, assert_nothing_left, board_variant, cli, empty_build_dir, one_line, robot_variant
from proleg.errors import BuildError
from proleg.firmware.boards import load_board
from proleg.firmware.build import MANIFEST, build, firmware_gaits, render_project
from proleg.robot import load_robot

ROBOT_FILES = sorted((ROOT / "robots").glob("*.toml"))
BOARD_FILES = sorted((ROOT / "boards").glob("*.toml"))
STRICT = "-std=c99 -Wall -Wextra -Werror"


@pytest.fixture
def parent(tmp_path: Path) -> Path:
    return empty_build_dir(tmp_path)


# ---------------------------------------------------------------------------------------
# every example robot for every board


#: (robot, board) pairs the board cannot host, and the reason the build must give. None
#: today: caterpillar-4 on the Nano (1,859 B of static RAM, too little left for the stack the
#: board file keeps) fits since its ψ progress edges left RAM (1,375 B).
CANNOT_HOST: dict[tuple[str, str], str] = {}


@pytest.mark.parametrize("board_file", BOARD_FILES, ids=lambda p: p.stem)
@pytest.mark.parametrize("robot_file", ROBOT_FILES, ids=lambda p: p.stem)
def test_every_robot_builds_for_every_board_within_its_limits(robot_file, board_file, parent):
    robot, board = load_robot(robot_file), load_board(board_file)
    out = parent / "fw"
    refused = CANNOT_HOST.get((robot.name, board.name))
    if refused is not None:  # the board cannot host it: the build says why, in one line, and writes nothing
        with pytest.raises(BuildError, match=refused):
            build(robot, board, out)
        assert not out.exists()
        return
    result = build(robot, board, out)
    print(f"\n{robot.name} on {board.name}: {result.size_report()}")

    # The generated Makefile compiles every object strict (C99, warnings are errors).
    makefile = (out / "Makefile").read_text()
    cflags = re.search(r"^CFLAGS\s*:=(.*)$", makefile, re.M)
    assert cflags and STRICT in cflags.group(1), cflags
    dry = subprocess.run(["make", "-C", str(out), "-B", "-n", "all"], capture_output=True, text=True, check=True)
    compiles = [line for line in dry.stdout.splitlines() if " -c " in line]
    n_sources = len(list(out.glob("core/*.c")) + list(out.glob("hal/*.c")) + list(out.glob("gen/*.c")))
    assert len(compiles) >= n_sources > 0
    for line in compiles:
        assert STRICT in line, line

    art = result.artifact
    assert art == out / board.artifact and art.is_file() and art.stat().st_size > 0
    data = art.read_bytes()
    if board.artifact.endswith(".so"):
        assert data[:4] == b"\x7fELF"
    elif board.artifact.endswith(".hex"):
        lines = data.decode("ascii").split()
        assert all(re.fullmatch(r":[0-9A-F]{10,}", ln) for ln in lines) and lines[-1] == ":00000001FF"
    elif board.artifact.endswith(".bin"):
        assert len(data) <= board.flash_bytes

    assert result.flash_used > 0 and result.ram_used > 0
    if board.flash_bytes:
        assert result.flash_used <= board.flash_bytes, result.size_report()
    if board.ram_bytes:
        assert result.ram_used <= board.ram_bytes, result.size_report()
    manifest = json.loads((out / MANIFEST).read_text())
    assert manifest["robot"] == robot.name and manifest["board"] == board.name
    assert (manifest["flash_used"], manifest["ram_used"]) == (result.flash_used, result.ram_used)
    assert sorted(p.name for p in parent.iterdir()) == ["fw"], "temporary directories left beside the build"


@pytest.fixture
def proleg_home(tmp_path, monkeypatch) -> Path:
    """A private copy of the data directories (boards, templates, robots) as PROLEG_HOME."""
    home = tmp_path / "home"
    for d in ("boards", "firmware_templates", "robots"):
        shutil.copytree(ROOT / d, home / d)
    monkeypatch.setenv("PROLEG_HOME", str(home))
    return home


# ---------------------------------------------------------------------------------------
# deterministic rendering, headers naming generator and inputs


def _digests(robot_file: Path, board: str, objective: str = "total") -> dict[str, str]:
    robot, b = load_robot(robot_file), load_board(board)
    files = render_project(robot, b, firmware_gaits(robot, objective))
    return {k: hashlib.sha256(v.encode()).hexdigest() for k, v in files.items()}


_RENDER_SCRIPT = """
import hashlib, json, sys
from proleg.robot import load_robot
from proleg.firmware.boards import load_board
from proleg.firmware.build import render_project, firmware_gaits
r = load_robot(sys.argv[1]); b = load_board(sys.argv[2])
files = render_project(r, b, firmware_gaits(r))
print(json.dumps({k: hashlib.sha256(v.encode()).hexdigest() for k, v in files.items()}))
"""


@pytest.mark.parametrize("board", ["host-sim", "arduino-nano", "bluepill-f103"])
def test_rendering_twice_gives_identical_bytes_even_across_processes(board, proleg_home):
    first = _digests(R1, board)
    assert _digests(R1, board) == first
    # A fresh interpreter with another hash seed (set/dict ordering of str keys) too.
    env = dict(os.environ, PYTHONHASHSEED="12345")
    proc = subprocess.run([sys.executable, "-c", _RENDER_SCRIPT, str(R1), board],
                          capture_output=True, text=True, env=env, check=True)
    assert json.loads(proc.stdout) == first


def test_two_builds_of_the_same_inputs_have_identical_project_files(parent, proleg_home):
    robot, board = load_robot(R1), load_board("host-sim")
    a = build(robot, board, parent / "a").out_dir
    b = build(robot, board, parent / "b").out_dir
    texts = sorted(p.relative_to(a) for p in a.rglob("*") if p.is_file() and p.suffix in (".c", ".h", ".json", "")
                   and "obj" not in p.parts and p.name != "libfirmware.so")
    assert Path("Makefile") in texts and Path(MANIFEST) in texts
    for rel in texts:
        assert (a / rel).read_bytes() == (b / rel).read_bytes(), rel


def _header(text: str) -> str:
    """The leading comment block of a C file or a Makefile."""
    if text.startswith("/*"):
        return text[: text.index("*/") + 2]
    lines = []
    for line in text.splitlines():
        if not line.startswith("#"):
            break
        lines.append(line)
    return "\n".join(lines)


@pytest.mark.parametrize("board", ["host-sim", "arduino-nano"])
def test_generated_files_start_with_a_comment_naming_generator_and_inputs(board):
    robot, b = load_robot(R1), load_board(board)
    files = render_project(robot, b, firmware_gaits(robot))
    generated = {k: v for k, v in files.items() if k.startswith("gen/") or k == "Makefile"}
    assert {"Makefile", "gen/robot_config.h", "gen/gait_table.c", "gen/proto_gen.h", "gen/proto_gen.c"} <= set(generated)
    for rel, text in generated.items():
        assert text.startswith(("/*", "#")), f"{rel} does not start with a comment"
        head = _header(text)
        assert re.search(r"generated", head, re.I) and "proleg" in head, f"{rel}: header does not say what generated it"
        if rel.startswith("gen/proto_gen"):
            assert "definition.py" in head and "max_limbs=2" in head and "max_channels=2" in head, head
        else:
            assert "robots/paper-r1.toml" in head, f"{rel}: header does not name the robot file"
    for rel in ("Makefile", "gen/robot_config.h"):
        assert f"{b.name}" in _header(generated[rel]), f"{rel}: header does not name the board"
    assert f"boards/{board}.toml" in _header(generated["Makefile"])
    sha = hashlib.sha256(R1.read_bytes()).hexdigest()
    assert sha in _header(generated["gen/robot_config.h"]) and sha in _header(generated["gen/gait_table.c"])


def test_a_robot_file_in_a_directory_with_a_line_break_leaves_the_makefile_header_a_comment(tmp_path):
    """The Makefile's header names the robot file; a line break in its path ended the comment,
    and the rest of the path's line became the first rule: `make` by hand failed."""
    odd = tmp_path / "lab\nrobots"
    odd.mkdir()
    path = odd / "r1.toml"
    path.write_text(R1.read_text(encoding="utf-8"), encoding="utf-8")
    robot, b = load_robot(path), load_board("host-sim")
    makefile = render_project(robot, b, firmware_gaits(robot))["Makefile"]
    head = makefile[: makefile.index("\n\n")]
    assert all(line.startswith("#") for line in head.splitlines()), head
    assert "lab\\nrobots" in head


def test_gait_selection_inputs_are_named_in_the_gait_table_header():
    robot, b = load_robot(R1), load_board("host-sim")
    total = render_project(robot, b, firmware_gaits(robot, "total"))["gen/gait_table.c"]
    short = render_project(robot, b, firmware_gaits(robot, "total", 2))["gen/gait_table.c"]
    assert total != short  # different inputs, different tables ...
    assert _header(total) != _header(short)  # ... so the headers must say which
    assert "objective total, max_transitions unbounded" in _header(total)
    assert "objective total, max_transitions 2" in _header(short)
    for head in (_header(total), _header(short)):
        assert "directions +x -x" in head and "ranked fewest opposing steps first" in head


def test_the_build_manifest_names_the_gait_selection(parent):
    robot, b = load_robot(R1), load_board("host-sim")
    result = build(robot, b, parent / "sel", max_transitions=2)
    manifest = json.loads((result.out_dir / MANIFEST).read_text())
    assert manifest["gait_selection"] == {
        "objective": "total", "max_transitions": 2, "directions": ["+x", "-x"],
        "rank": "fewest opposing steps first, then search order",
    }


# ---------------------------------------------------------------------------------------
# a failed build: one clear message, nothing left behind


def test_a_full_disk_while_writing_the_project_names_the_directory(capsys, parent, monkeypatch):
    def full(self, *a, **k):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(Path, "write_text", full)
    code, _, err = cli(capsys, "build", R1, "--board", "host-sim", "-o", parent / "fw")
    assert code == 1
    assert one_line(err) == f"proleg: error: cannot write build directory {parent / 'fw'}: No space left on device"
    assert_nothing_left(parent)


def test_unknown_board_is_one_error_line(capsys, parent):
    code, _, err = cli(capsys, "build", R1, "--board", "nope", "-o", parent / "fw")
    assert code == 2
    line = one_line(err)
    assert "unknown board 'nope'" in line and "arduino-nano" in line
    assert_nothing_left(parent)


def test_more_actuator_channels_than_the_board_has_names_the_channel(tmp_path, capsys, parent):
    robot = robot_variant(tmp_path, R1, (r'(name = "sma-right"\s*\nchannel = )1', r"\g<1>5"))
    with pytest.raises(BuildError, match=r"actuator 'sma-right' is on channel = 5, but board arduino-nano has 4 PWM channels: "
                       r"channel = 0 \(D9\), .*channel = 3 \(D3\)$"):
        build(load_robot(robot), load_board("arduino-nano"), parent / "fw")
    code, _, err = cli(capsys, "build", robot, "--board", "arduino-nano", "-o", parent / "fw")
    assert code == 2 and "channel = 5" in one_line(err)
    assert_nothing_left(parent)


def test_more_limbs_than_imu_addresses_is_a_clear_error(tmp_path, parent):
    third = '[[limb]]\nname = "middle"\npsi_star_deg = [20.0]\nactuator = "sma-left"\n\n[[actuator]]'
    robot = robot_variant(
        tmp_path, R1,
        (r"^\[\[actuator\]\]", third),
        (r'^states = \[.*?\]\nmatrix = \[.*?\n\]', "default_duration_s = 1.0\nmatrix = [\n"
         + "".join("  [" + ", ".join("1" if j == (i + 1) % 8 else "0" for j in range(8)) + "],\n" for i in range(8))
         + "]"),
    )
    one_bus = tmp_path / "one-bus.toml"
    text = (ROOT / "boards" / "host-sim.toml").read_text(encoding="utf-8")
    text = text[: text.index("[[i2c.bus]]")] + '[[i2c.bus]]\nname = "sim0"\nimu_addresses = [0x68, 0x69]\n' + text[text.index("[pwm]") - 1 :]
    one_bus.write_text(text, encoding="utf-8")
    with pytest.raises(BuildError, match=r"3 limbs, each with an IMU, but board host-sim can host at most 2 IMUs "
                                         r"\(bus sim0: 0x68/0x69, no multiplexer\)"):
        build(load_robot(robot), load_board(one_bus), parent / "fw")
    assert_nothing_left(parent)


def test_missing_toolchain_names_the_packages(tmp_path, capsys, parent):
    board = board_variant(tmp_path, "arduino-nano", (r'^cc = "avr-gcc"', 'cc = "avr-gcc-not-installed-xyz"'))
    with pytest.raises(BuildError, match=r"avr-gcc-not-installed-xyz not found.*gcc-avr avr-libc binutils-avr"):
        build(load_robot(R1), load_board(board), parent / "fw")
    code, _, err = cli(capsys, "build", R1, "--board", board, "-o", parent / "fw")
    assert code == 2 and "gcc-avr" in one_line(err)
    assert_nothing_left(parent)


def test_unknown_compiler_flag_fails_with_the_compilers_error_line(tmp_path, parent):
    board = board_variant(tmp_path, "host-sim", (r'^cflags = \["-O2"', 'cflags = ["-fno-such-flag-xyz", "-O2"'))
    with pytest.raises(BuildError) as e:
        build(load_robot(R1), load_board(board), parent / "fw")
    msg = str(e.value)
    assert msg.startswith("compilation failed")
    assert re.search(r"error: .*-fno-such-flag-xyz", msg), msg
    assert_nothing_left(parent)


def test_a_broken_source_fails_with_the_compilers_line(proleg_home, parent):
    src = proleg_home / "firmware_templates" / "core" / "crc16.c"
    lines = src.read_text().splitlines(keepends=True)
    lines.insert(2, "int broken(void) { return undeclared_thing_xyz; }\n")
    src.write_text("".join(lines))
    with pytest.raises(BuildError) as e:
        build(load_robot(proleg_home / "robots" / "paper-r1.toml"), load_board("host-sim"), parent / "fw")
    msg = str(e.value)
    assert re.search(r"core/crc16\.c:3:\d+: error: .*undeclared_thing_xyz", msg), msg
    assert str(parent) not in msg, "the message names the temporary directory instead of the project file"
    assert_nothing_left(parent)


def test_the_compile_failure_message_is_the_diagnostics_not_the_commands(proleg_home, parent):
    core = proleg_home / "firmware_templates" / "core"
    for i in range(3):  # a few more (valid) sources, as a bigger HAL would bring
        (core / f"zz_extra{i}.c").write_text(f"int zz_extra{i}(void);\n")
    hal = proleg_home / "firmware_templates" / "hal" / "sim" / "sim_mpu6050.c"
    hal.write_text(hal.read_text() + "\nint broken(void) { return undeclared_thing_xyz; }\n")
    with pytest.raises(BuildError) as e:
        build(load_robot(proleg_home / "robots" / "paper-r1.toml"), load_board("host-sim"), parent / "fw")
    msg = str(e.value)
    assert not [line for line in msg.splitlines() if " -c " in line], msg
    assert re.search(r"hal/sim_mpu6050\.c:\d+:\d+: error: .*undeclared_thing_xyz", msg), msg
    assert_nothing_left(parent)


def test_a_warning_is_an_error(proleg_home, parent):
    src = proleg_home / "firmware_templates" / "core" / "cobs.c"
    src.write_text(src.read_text() + "\nint proleg_unused_param_xyz(int a, int b) { return a; }\n")
    with pytest.raises(BuildError, match=r"cobs\.c:\d+:\d+: error: unused parameter .b. \[-Werror=unused-parameter\]"):
        build(load_robot(proleg_home / "robots" / "paper-r1.toml"), load_board("host-sim"), parent / "fw")
    assert_nothing_left(parent)


@pytest.mark.parametrize("board", ["host-sim", "arduino-nano"])
def test_over_the_flash_limit_says_needed_and_available(tmp_path, parent, board):
    variant = board_variant(tmp_path, board, (r"^flash_bytes = \d+", "flash_bytes = 1000"),
                            (r"^ram_bytes = \d+", "ram_bytes = 1000000"))
    with pytest.raises(BuildError) as e:
        build(load_robot(R1), load_board(variant), parent / "fw")
    m = re.search(r"needs ([\d,]+) bytes of flash, board \S+ has 1,000$", str(e.value))
    assert m, str(e.value)
    assert int(m.group(1).replace(",", "")) > 1000
    assert_nothing_left(parent)


@pytest.mark.parametrize("board", ["host-sim", "arduino-nano"])
def test_over_the_ram_limit_says_needed_and_available(tmp_path, parent, board):
    variant = board_variant(tmp_path, board, (r"^flash_bytes = \d+", "flash_bytes = 1000000"),
                            (r"^ram_bytes = \d+", "ram_bytes = 16"))
    with pytest.raises(BuildError, match=r"needs [\d,]+ bytes of static RAM( and [\d,]+ for its stack \(\[board\] stack_bytes\))?, board \S+ has 16$"):
        build(load_robot(R1), load_board(variant), parent / "fw")
    assert_nothing_left(parent)


# ---------------------------------------------------------------------------------------
# the output directory: never clobber a stranger's, always replace our own


def test_an_existing_non_proleg_directory_is_never_replaced(parent):
    out = parent / "fw"
    out.mkdir()
    (out / "thesis.tex").write_text("years of work")
    with pytest.raises(BuildError, match="not a proleg build directory"):
        build(load_robot(R1), load_board("host-sim"), out)
    assert sorted(p.name for p in out.iterdir()) == ["thesis.tex"]
    assert (out / "thesis.tex").read_text() == "years of work"
    assert sorted(p.name for p in parent.iterdir()) == ["fw"]


def test_an_existing_file_at_the_output_path_is_never_replaced(parent):
    out = parent / "fw"
    out.write_text("not a directory")
    with pytest.raises(BuildError, match="not a proleg build directory"):
        build(load_robot(R1), load_board("host-sim"), out)
    assert out.read_text() == "not a directory"
    assert sorted(p.name for p in parent.iterdir()) == ["fw"]


def test_a_rebuild_replaces_the_previous_build(parent):
    out = parent / "fw"
    build(load_robot(R1), load_board("host-sim"), out)
    (out / "stale-from-last-time.o").write_text("x")
    result = build(load_robot(ROOT / "robots" / "paper-r2.toml"), load_board("host-sim"), out)
    assert not (out / "stale-from-last-time.o").exists()
    assert json.loads((out / MANIFEST).read_text())["robot"] == "paper-r2"
    assert result.artifact.is_file()
    assert sorted(p.name for p in parent.iterdir()) == ["fw"]


def test_a_failed_rebuild_keeps_the_previous_build_intact(tmp_path, parent):
    out = parent / "fw"
    build(load_robot(R1), load_board("host-sim"), out)
    before = {p.relative_to(out): p.read_bytes() for p in out.rglob("*") if p.is_file()}
    broken = board_variant(tmp_path, "host-sim", (r'^cflags = \["-O2"', 'cflags = ["-fno-such-flag-xyz", "-O2"'))
    with pytest.raises(BuildError, match="compilation failed"):
        build(load_robot(R1), load_board(broken), out)
    after = {p.relative_to(out): p.read_bytes() for p in out.rglob("*") if p.is_file()}
    assert after == before
    assert sorted(p.name for p in parent.iterdir()) == ["fw"]


def test_a_limb_name_that_would_close_a_c_comment_builds(tmp_path, parent):
    """Limb names are "any printable text" (docs/robot-file.md), and they are written into
    the generated C's comments (the limb list, the IMU placement, the fallback gaits): a limb
    named 'left */ "x" \\ 1st' ended the comment, and the build failed with the compiler's
    "stray '\\' in program" instead of building."""
    path = robot_variant(tmp_path, R1, (r'^name = "left"', r'name = "left */ \"x\" \\\\ 1st"'))
    robot = load_robot(path)
    assert robot.limbs[0].name == 'left */ "x" \\ 1st'
    result = build(robot, load_board("host-sim"), parent / "fw")
    assert result.artifact.is_file()
    config = (parent / "fw" / "gen" / "robot_config.h").read_text()
    assert 'left *\\/ "x" \\ 1st' in config
    opens = robot_variant(tmp_path, R1, (r'^name = "left"', r'name = "left /* x"'))
    result = build(load_robot(opens), load_board("host-sim"), parent / "fw2")  # "/*" within comment: -Werror
    assert result.artifact.is_file()
    assert "left /\\* x" in (parent / "fw2" / "gen" / "robot_config.h").read_text()
