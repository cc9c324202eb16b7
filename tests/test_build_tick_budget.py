"""``proleg build`` refuses a tick rate the board's measured per-tick work cannot fit
(``[budget]`` in boards/*.toml, measured by bench/bench_mcu.py on the emulated MCU)."""

from __future__ import annotations

import dataclasses
import re
from pathlib import Path

import pytest
from hypothesis import given
from hypothesis import strategies as st

from proleg.cli import main
from proleg.errors import BoardError, BuildError
from proleg.firmware.boards import TickBudget, load_board
from proleg.firmware.build import check_tick_budget, firmware_gaits
from proleg.firmware.fit import check_fit
from proleg.paths import boards_dir, robots_dir
from proleg.robot import load_robot

R1 = robots_dir() / "paper-r1.toml"


def at_rate(robot, hz: int):
    return dataclasses.replace(robot, control=dataclasses.replace(robot.control, tick_hz=hz))


def board_with(tmp_path: Path, budget: str, name: str = "bluepill-f103") -> Path:
    text = (boards_dir() / f"{name}.toml").read_text(encoding="utf-8")
    text = re.sub(r"\n\[budget\]\n(?:[^\[]*\n)*?(?=\n\[|\Z)", "\n", text)  # drop the board's own
    path = tmp_path / f"{name}.toml"
    path.write_text(text + "\n[budget]\n" + budget, encoding="utf-8")
    return path


def test_every_mcu_board_with_a_budget_says_when_and_how_it_was_measured():
    for name in ("arduino-nano", "bluepill-f103"):
        budget = load_board(name).budget
        if budget is not None:
            assert "bench/bench_mcu.py" in budget.measured and re.search(r"\d{4}-\d\d-\d\d", budget.measured)
    assert load_board("host-sim").budget is None  # virtual time: nothing to measure


def test_the_bluepill_takes_paper_r1_at_1_khz_and_refuses_a_rate_beyond_both_limits_naming_the_one_that_binds():
    board = load_board("bluepill-f103")
    assert board.budget is not None
    r1 = load_robot(R1)
    check_tick_budget(r1, board)  # 1 kHz: fits
    hz = 20_000  # 50 µs: beyond the two-limb budget (105 µs) and the two IMUs' I2C reads (420 µs)
    with pytest.raises(BuildError) as e:
        check_tick_budget(at_rate(r1, hz), board)
    msg = str(e.value)
    assert "\n" not in msg
    assert msg == (f"{r1.path}: reading 2 IMUs (0 channel switches) takes about 420 us of I2C at 400 kHz per tick "
                   "on board bluepill-f103, more than 75% of the 50 us tick: set control.tick_hz to at most 1785")


@pytest.mark.parametrize("board", ["host-sim", "bluepill-f103"])
def test_a_one_limb_robot_at_10_khz_is_refused_for_its_i2c_reads_on_host_sim_and_the_bluepill_alike(board):
    """Both boards read the IMU at 400 kHz; only the Blue Pill has a [budget], which takes one limb
    up to 9,589 Hz. It refused for that budget (73 µs of work), host-sim for the I2C reads:
    two reasons for one robot, and the Blue Pill's not the limit (it said "at most 3571 Hz")."""
    one = at_rate(load_robot(R1), 10_000)
    one = dataclasses.replace(one, limbs=one.limbs[:1])
    b = load_board(board)
    with pytest.raises(BuildError) as e:
        check_tick_budget(one, b)
        check_fit(one, b, {})
    assert str(e.value).endswith(
        f"reading 1 IMU (0 channel switches) takes about 210 us of I2C at 400 kHz per tick on board {board}, "
        "more than 75% of the 100 us tick: set control.tick_hz to at most 3571")
    check_tick_budget(at_rate(one, 3571), b)
    check_fit(at_rate(one, 3571), b, {})


def test_the_nano_refuses_a_one_limb_robot_at_10_khz_for_its_budget_the_lower_limit():
    one = at_rate(load_robot(R1), 10_000)
    one = dataclasses.replace(one, limbs=one.limbs[:1])
    with pytest.raises(BuildError) as e:
        check_tick_budget(one, load_board("arduino-nano"))
    assert "1 limb needs 541 µs per tick (391 + 1 × 150 µs, [budget] of arduino-nano.toml)" in str(e.value)
    assert str(e.value).endswith("at most 1293 Hz")  # the I2C reads would take 3,571


def test_the_rate_a_refused_tick_names_builds_where_the_i2c_reads_allow_less_than_the_budget(tmp_path, capsys):
    """The bluepill's [budget] takes R1 up to 6,666 Hz, its two IMUs' I2C reads up to 1,785: the
    budget's refusal said 'at most 6666 Hz', and at 6,666 Hz the build refused again, naming 1,785."""
    fast, named = tmp_path / "fast-r1.toml", tmp_path / "named-r1.toml"
    fast.write_text(R1.read_text(encoding="utf-8").replace("tick_hz = 1000", "tick_hz = 10000"), encoding="utf-8")
    assert main(["build", str(fast), "--board", "bluepill-f103", "-o", str(tmp_path / "a")]) == 2
    err = capsys.readouterr().err
    most = int(re.search(r"at most (\d+)", err).group(1))
    assert most < load_board("bluepill-f103").budget.max_tick_hz(2)
    named.write_text(R1.read_text(encoding="utf-8").replace("tick_hz = 1000", f"tick_hz = {most}"), encoding="utf-8")
    board = load_board("bluepill-f103")
    check_tick_budget(load_robot(named), board)
    check_fit(load_robot(named), board, firmware_gaits(load_robot(named)))


def test_proleg_build_refuses_the_rate_in_one_line_before_compiling(tmp_path, capsys):
    robot = tmp_path / "fast-r1.toml"
    robot.write_text(R1.read_text(encoding="utf-8").replace("tick_hz = 1000", "tick_hz = 5000"), encoding="utf-8")
    board = board_with(tmp_path, 'tick_us_base = 300\ntick_us_per_limb = 100\nmeasured = "test"\n')
    code = main(["build", str(robot), "--board", str(board), "-o", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert code == 2
    assert err.count("\n") == 1 and "control.tick_hz = 5000 is too fast" in err
    assert "2 limbs need 500 µs per tick (300 + 2 × 100 µs, [budget] of bluepill-f103.toml)" in err
    assert "at most 1400 Hz" in err
    assert not (tmp_path / "out").exists()


def test_a_one_limb_robot_is_told_what_its_one_limb_needs():
    """On the Nano, whose [budget] binds before its I2C reads (on the Blue Pill these bind first)."""
    r1 = load_robot(R1)
    one = dataclasses.replace(r1, limbs=r1.limbs[:1])
    with pytest.raises(BuildError) as e:
        check_tick_budget(at_rate(one, 20_000), load_board("arduino-nano"))
    assert " 1 limb needs " in str(e.value) and "limbs need" not in str(e.value)


@given(base=st.integers(0, 5000), per_limb=st.integers(0, 3000), limbs=st.integers(1, 8))
def test_max_tick_hz_is_exactly_the_highest_rate_the_check_accepts(base, per_limb, limbs):
    budget = TickBudget(float(base), float(per_limb), "test")
    if budget.busy_us(limbs) <= 0:
        return
    hz = budget.max_tick_hz(limbs)
    # brute force: the same rule, in integers (busy ≤ 0.7 × 1e6 / hz  ⇔  10 × busy × hz ≤ 7e6)
    busy = base + per_limb * limbs
    assert 10 * busy * hz <= 7_000_000 < 10 * busy * (hz + 1)


@pytest.mark.parametrize("budget,expected", [
    ('tick_us_per_limb = 100\nmeasured = "x"\n', "budget.tick_us_base: missing"),
    ('tick_us_base = -1\ntick_us_per_limb = 100\nmeasured = "x"\n', "budget.tick_us_base: expected µs ≥ 0, got -1"),
    ('tick_us_base = 100\ntick_us_per_limb = "fast"\nmeasured = "x"\n', "budget.tick_us_per_limb: expected"),
    ('tick_us_base = 100\ntick_us_per_limb = 100\n', "budget.measured: missing"),
    ('tick_us_base = 0\ntick_us_per_limb = 0\nmeasured = "x"\n', "must be above 0 µs"),
    ('tick_us_base = 1\ntick_us_per_limb = 1\nmeasured = "x"\nenforce = "no"\n', "budget.enforce: expected true or false"),
])
def test_a_malformed_budget_is_one_line_naming_the_field(tmp_path, budget, expected):
    with pytest.raises(BoardError, match=re.escape(expected)):
        load_board(board_with(tmp_path, budget))


def test_a_budget_not_enforced_yet_warns_with_the_same_numbers_and_builds(tmp_path, caplog):
    board = load_board(board_with(tmp_path, 'tick_us_base = 900\ntick_us_per_limb = 250\n'
                                            'measured = "test"\nenforce = false\n'))
    with caplog.at_level("WARNING", logger="proleg"):
        check_tick_budget(load_robot(R1), board)
    assert [r.getMessage() for r in caplog.records] == [
        f"{R1}: control.tick_hz = 1000 is too fast for board bluepill-f103: 2 limbs need 1400 µs per tick "
        "(900 + 2 × 250 µs, [budget] of bluepill-f103.toml), more than 70 % of the 1000 µs period; at most 500 Hz "
        "(building anyway: [budget] enforce = false)"
    ]


def test_the_nano_enforces_its_budget_takes_every_example_robot_it_hosts_and_refuses_r1_one_hz_too_fast():
    """arduino-nano's [budget] is measured (bench/bench_mcu.py on avr-emu) and enforced:
    every example robot builds at its configured rate, and R1 one Hz above the highest
    rate the budget fits is refused in one line before anything is compiled."""
    board = load_board("arduino-nano")
    b = board.budget
    assert b is not None and b.enforce
    for path in sorted(robots_dir().glob("*.toml")):
        check_tick_budget(load_robot(path), board)  # the rate each robot file configures fits
    r1 = load_robot(R1)
    fastest = b.max_tick_hz(len(r1.limbs))
    assert 1000 <= fastest < 2000
    check_tick_budget(at_rate(r1, fastest), board)
    with pytest.raises(BuildError) as e:
        check_tick_budget(at_rate(r1, fastest + 1), board)
    msg = str(e.value)
    assert "\n" not in msg and msg.startswith(
        f"{r1.path}: control.tick_hz = {fastest + 1} is too fast for board arduino-nano: 2 limbs need ")
    assert "[budget] of arduino-nano.toml), more than 70 % of the" in msg and f"at most {fastest} Hz" in msg


def test_proleg_build_refuses_r1_on_the_nano_at_a_rate_its_budget_cannot_meet(tmp_path, capsys):
    board = load_board("arduino-nano")
    hz = board.budget.max_tick_hz(2) + 1
    robot = tmp_path / "fast-r1.toml"
    robot.write_text(R1.read_text(encoding="utf-8").replace("tick_hz = 1000", f"tick_hz = {hz}"), encoding="utf-8")
    code = main(["build", str(robot), "--board", "arduino-nano", "-o", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert code == 2
    assert err.count("\n") == 1 and f"control.tick_hz = {hz} is too fast for board arduino-nano" in err
    assert not (tmp_path / "out").exists()


def test_robot_file_md_gives_the_default_tick_rate_and_the_highest_rate_each_board_takes():
    """docs/robot-file.md named `tick_hz` but neither its default (1000) nor that robots of four
    limbs or more must lower it: the build's refusal was the first anyone heard of it. Each rate
    in its table passes both checks (I2C reads, [budget]) and one more Hz fails one of them."""
    from types import SimpleNamespace

    from proleg.firmware import placement
    from proleg.firmware.fit import DEFAULT_I2C_HZ
    from proleg.robot import Control

    doc = (Path(__file__).resolve().parents[1] / "docs" / "robot-file.md").read_text(encoding="utf-8")
    assert Control().tick_hz == 1000
    assert "`tick_hz` (200–10000, default 1000)" in doc and "a robot of four limbs\nor more must set `tick_hz` lower" in doc
    rows = {}
    for line in doc.splitlines():
        cells = [c.strip() for c in line.strip("|").split("|")]
        if len(cells) == 9 and cells[0] != "limbs" and all(c.isdigit() for c in cells[1:]):
            for name in cells[0].split(", "):
                rows[name] = [int(c) for c in cells[1:]]
    assert set(rows) == {p.stem for p in boards_dir().glob("*.toml")}

    def fits(board, limbs: int, hz: int) -> bool:
        robot = SimpleNamespace(name="toy", where="toy.toml", limbs=tuple(
            SimpleNamespace(name=f"l{i}", imu=None) for i in range(limbs)), control=SimpleNamespace(tick_hz=hz))
        i2c_hz = int((board.i2c or {}).get("hz", DEFAULT_I2C_HZ))  # as check_fit reads it
        try:  # the I2C reads, as check_fit checks them
            placement.check_tick_budget(robot, board.name, placement.place_imus(robot, board), i2c_hz)
            check_tick_budget(robot, board)  # the board's [budget]
        except BuildError:
            return False
        return True

    for name, most in rows.items():
        board = load_board(name)
        for limbs, hz in enumerate(most, start=1):
            assert fits(board, limbs, hz) and not fits(board, limbs, hz + 1), (name, limbs, hz)
        assert [limbs for limbs, hz in enumerate(most, start=1) if hz < 1000] == list(
            range(3 if name == "arduino-nano" else 4, 9))
