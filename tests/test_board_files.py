"""Board files (boards/*.toml): every mistake in one is one line naming the file and the
field and what was expected, an unreadable one is one line and exit 2, and the build steps
it names are what the rendered Makefile runs."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from build_checks import R1, ROOT, assert_nothing_left, cli, empty_build_dir, one_line
from proleg.errors import BoardError
from proleg.firmware.boards import load_board
from proleg.firmware.build import firmware_gaits, render_project
from proleg.robot import load_robot


@pytest.fixture
def parent(tmp_path: Path) -> Path:
    return empty_build_dir(tmp_path)


def test_unknown_board_file_path_is_a_board_error(tmp_path):
    with pytest.raises(BoardError, match="no such board file"):
        load_board(tmp_path / "nope.toml")


def _board_variant(tmp_path: Path, old: str, new: str) -> Path:
    text = (ROOT / "boards" / "arduino-nano.toml").read_text()
    assert old in text
    p = tmp_path / "variant.toml"
    p.write_text(text.replace(old, new))
    return p


@pytest.mark.parametrize(("old", "new", "expected"), [
    ("[build]", "[built]", r"variant.toml: unknown table 'built'"),
    ("main_loop = true", "main_loop = 1", r"variant.toml: build.main_loop: expected true or false, got 1"),
    ('objcopy = ["avr-objcopy"', '# objcopy = ["avr-objcopy"',
     r"variant.toml: build.objcopy: missing, needed to make artifact 'firmware.hex' from 'firmware.elf'"),
    ('objcopy = ["avr-objcopy"', 'objcopy_off = ["avr-objcopy"',
     r"variant.toml: build.objcopy_off: unknown key \(did you mean 'objcopy'\?\)"),
    ("stack_bytes", "stack_byts", r"variant.toml: board.stack_byts: unknown key \(did you mean 'stack_bytes'\?\)"),
    ("baud", "baudrate", r"variant.toml: uart.baudrate: unknown key"),
    ('family = "avr"', 'family = "rp2040"',
     r"variant.toml: board.family: expected one of avr, sim, stm32f1, template \(a folder with a family.toml"),
    ("tx_buffer = 128", "tx_buffer = 100", r"variant.toml: uart.tx_buffer: expected a power of two"),
    # an empty artifact named the project directory itself: flash --dry-run printed it as the
    # file to write (exit 0), and the build made no artifact
    ('artifact = "firmware.hex"', 'artifact = ""',
     r"variant.toml: build.artifact: expected a file name in the project directory .*, got ''$"),
    ('link = "firmware.elf"', 'link = "../firmware.elf"',
     r"variant.toml: build.link: expected a file name in the project directory .*, got '../firmware.elf'$"),
    # an empty program was looked for on PATH: "proleg: error:  not found, needed for board …"
    ('cc = "avr-gcc"', 'cc = ""', r"variant.toml: toolchain.cc: expected the name of a program .*, got ''$"),
    ('size = ["avr-size"', 'size = [" avr-size"',
     r"variant.toml: build.size\[0\]: expected the name of a program .*, got ' avr-size'$"),
    # past 128 bytes the rings take 16-bit indices, not atomic on the ATmega328P: the file was
    # taken (flash --dry-run exit 0) and only hal_avr.c's #error refused it, in the compiler
    ("rx_buffer = 64", "rx_buffer = 256", r"variant.toml: uart.rx_buffer: expected a power of two from 16 to 128 "
                                          r"bytes \(the most the avr family's HAL takes: .*\), got 256$"),
    # a zero or negative number is refused, never replaced by a default or compiled in
    ("frequency_hz = 490", "frequency_hz = 0",
     r"variant.toml: pwm.frequency_hz: expected a PWM frequency in Hz in 1..1_000_000, got 0$"),
    ("frequency_hz = 490", "frequency_hz = -1000", r"variant.toml: pwm.frequency_hz: expected .*, got -1000$"),
    ("hz = 400000", "hz = 0", r"variant.toml: i2c.hz: expected an I2C clock in Hz in 1_000..3_400_000, got 0$"),
    ("hz = 400000", 'hz = "fast"', r"variant.toml: i2c.hz: expected an I2C clock in Hz .*, got 'fast'$"),
    ("clock_hz = 16000000", "clock_hz = -16000000",
     r"variant.toml: board.clock_hz: expected a clock in Hz in 0..1_000_000_000, got -16000000$"),
    ("baud = 115200", "baud = 0", r"variant.toml: uart.baud: expected a baud rate in 300..12_000_000, got 0$"),
    ("baud = 115200", "baud = -9600", r"variant.toml: uart.baud: expected a baud rate .*, got -9600$"),
    ("flash_bytes = 30720", "flash_bytes = -5", r"variant.toml: board.flash_bytes: expected a size in bytes in 0..4_294_967_295, got -5$"),
    ("ram_bytes = 2048", "ram_bytes = -1", r"variant.toml: board.ram_bytes: expected a size in bytes .*, got -1$"),
    ("base_flash_bytes = ", "base_flash_bytes = -100 # ", r"variant.toml: board.base_flash_bytes: expected a size in bytes .*, got -100$"),
    ('pins = ["D9", "D10"', 'pins = ["D9", "D9"',
     r"variant.toml: pwm.pins: expected each pin once \(one channel per pin\), got 'D9' twice$"),
    ('packages = ["avrdude"]', 'pakages = ["avrdude"]', r"variant.toml: flash\[0\].pakages: unknown key \(did you mean 'packages'\?\)$"),
    ('packages = ["avrdude"]', 'packages = "avrdude"', r"variant.toml: flash\[0\].packages: expected a list of strings, got 'avrdude'$"),
    ('description = "Arduino', 'description = 5 # "', r"variant.toml: board.description: expected a string, got 5$"),
    ('name = "arduino-nano"', 'name = "arduino\\"nano"', r"variant.toml: board.name: expected lowercase letters, digits .*, got 'arduino\"nano'$"),
    ('name = "arduino-nano"', 'name = "nano\\n"', r"variant.toml: board.name: expected lowercase letters, digits .*, got 'nano\\n'$"),
])
def test_a_board_file_mistake_is_one_line_naming_the_field(tmp_path, old, new, expected):
    with pytest.raises(BoardError, match=expected) as e:
        load_board(_board_variant(tmp_path, old, new))
    assert "\n" not in str(e.value)


def test_flash_dry_run_refuses_a_uart_ring_the_boards_hal_cannot_take(tmp_path, capsys):
    board = _board_variant(tmp_path, "rx_buffer = 64", "rx_buffer = 256")
    code, out, err = cli(capsys, "flash", R1, "--board", board, "--dry-run", "--port", "/dev/ttyUSB0")
    assert code == 2 and not out and "uart.rx_buffer: expected a power of two from 16 to 128 bytes" in one_line(err)


@pytest.mark.parametrize("table", ["pwm", "uart", "toolchain", "build"])
def test_a_board_table_given_as_a_value_is_one_line(tmp_path, table):
    text = (ROOT / "boards" / "host-sim.toml").read_text(encoding="utf-8")
    text, n = re.subn(rf"^\[{table}\]\n(?:[^\[].*\n|\n)*", "", text, flags=re.M)
    assert n == 1
    path = tmp_path / "variant.toml"
    path.write_text(f"{table} = 5\n{text}", encoding="utf-8")
    with pytest.raises(BoardError, match=rf"variant.toml: {table}: expected a table, got 5$"):
        load_board(path)


def test_a_board_file_that_cannot_be_read_is_one_line_and_exit_2(tmp_path, capsys, parent):
    latin1 = tmp_path / "latin1.toml"
    text = (ROOT / "boards" / "host-sim.toml").read_text(encoding="utf-8")
    latin1.write_bytes(text.replace("Simulated board", "Simulated b\u00f6ard").encode("latin-1"))
    line = text[: text.index("Simulated board")].count("\n") + 1
    code, _, err = cli(capsys, "build", R1, "--board", latin1, "-o", parent / "out")
    assert code == 2
    assert one_line(err) == f"proleg: error: {latin1}: expected UTF-8 text, got byte 0xf6 on line {line}"
    folder = tmp_path / "folder.toml"
    folder.mkdir()
    for board in (folder, tmp_path):  # a board file path, or any path with a '/'
        code, _, err = cli(capsys, "build", R1, "--board", board, "-o", parent / "out")
        assert code == 2
        assert one_line(err) == f"proleg: error: {board}: cannot read the board file: Is a directory"
    assert_nothing_left(parent)


def test_the_makefile_runs_the_board_files_build_steps(tmp_path):
    board = load_board(_board_variant(tmp_path, '"-R", ".eeprom", ', ""))
    robot = load_robot(R1)
    makefile = render_project(robot, board, firmware_gaits(robot))["Makefile"]
    assert "\tavr-objcopy -O ihex firmware.elf firmware.hex\n" in makefile
    assert "\tavr-size -B firmware.elf\n" in makefile
    assert "family" not in makefile.lower()


def _eight_mhz_nano(tmp_path: Path, baud: int) -> Path:
    text = (ROOT / "boards" / "arduino-nano.toml").read_text()
    text = text.replace("clock_hz = 16000000", "clock_hz = 8000000").replace("baud = 115200", f"baud = {baud}")
    p = tmp_path / "pro-mini-8.toml"
    p.write_text(text)
    return p


def test_a_baud_rate_the_boards_clock_cannot_make_is_refused_naming_the_rates_it_can(tmp_path, capsys):
    # an 8 MHz ATmega328P makes 115200 as 8e6 / (8 × 9) = 111,111 baud: 3.5 % slow, a garbled link
    board = _eight_mhz_nano(tmp_path, 115200)
    with pytest.raises(BoardError, match=r"pro-mini-8.toml: uart.baud: 115200 is made as 111,111 baud \(-3.5%\) "
                                         r"by the avr HAL on a 8,000,000 Hz clock .* 38400, 57600,") as e:
        load_board(board)
    assert "\n" not in str(e.value)
    code, out, err = cli(capsys, "build", R1, "--board", board)
    assert code == 2 and not out and "uart.baud: 115200 is made as 111,111 baud" in one_line(err)
    assert load_board(_eight_mhz_nano(tmp_path, 57600)).uart_baud == 57600  # 58,824: +2.1 %, as the Nano's 115200


@pytest.mark.parametrize("name", sorted(p.stem for p in (ROOT / "boards").glob("*.toml")))
def test_every_shipped_board_makes_its_baud_rate(name):
    load_board(ROOT / "boards" / f"{name}.toml")  # the Nano's 115200 is 117,647 (+2.1 %), within the 3 %


@pytest.mark.parametrize("board, baud, clock, rates", [
    # UBRR0 holds 12 bits: 300 baud on 16 MHz takes UBRR0 = 6666, which it cannot hold
    ("arduino-nano", 300, "16,000,000", "488 to 2,000,000 baud"),
    # BRR's mantissa would be 0 (BRR = 6): the STM32F1's USART makes at most clock / 16
    ("bluepill-f103", 12_000_000, "72,000,000", "1,099 to 4,500,000 baud"),
])
def test_a_baud_rate_the_uarts_register_cannot_hold_is_refused(tmp_path, board, baud, clock, rates):
    # the divider's rounding alone said these ran at exactly the rate named: the register truncates it
    text = (ROOT / "boards" / f"{board}.toml").read_text()
    p = tmp_path / f"{board}-odd.toml"
    p.write_text(re.sub(r"(?m)^baud = \d+", f"baud = {baud}", text))
    with pytest.raises(BoardError, match=rf"uart.baud: {baud} is beyond what the \w+ HAL's UART makes on a {clock} Hz "
                                         rf"clock \(board.clock_hz\): {rates}: the link would garble; rates within 3%: "):
        load_board(p)
