"""Render a robot's firmware project for a board and compile it.

The project directory is self-contained: ``core/`` (the hand-written portable C, copied
unchanged; ``main.c`` only when the board file's ``build.main_loop`` is true), ``hal/``
(the board family's port), ``gen/`` (the rendered configuration, gait tables and
protocol tables), a ``Makefile`` a user can run by hand (its link, objcopy and size steps
are the board file's ``[build]`` table), and ``proleg-build.json`` (what was built from
which inputs, the gait selection, and its size). The project is
written and compiled in a temporary sibling directory and moved into place only when
the build succeeded and fits the board: a failed build leaves nothing half-written.
"""

from __future__ import annotations

import hashlib
import json
import logging
import os
import re
import shutil
import subprocess
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import jinja2

from .. import __version__
from ..errors import BuildError, Interrupted, LinkError
from ..paths import as_if_created, display_path, templates_dir
from ..robot import Robot
from .boards import Board, pwm_channel_error
from .fit import Fit, check_fit, check_i2c_ticks, i2c_hz
from .gaits import firmware_gaits, gait_warnings
from .placement import max_tick_hz, place_imus

__all__ = ["MANIFEST", "BuildResult", "build", "check_board_takes", "check_buildable", "firmware_gaits", "plan_build",
           "render_project"]

MANIFEST = "proleg-build.json"
#: The core file that holds main() and the tick loop: in the image only when build.main_loop.
CORE_MAIN = "main.c"


@dataclass(frozen=True)
class BuildResult:
    out_dir: Path
    artifact: Path
    board: Board
    flash_used: int
    ram_used: int
    gait_table_hash: str
    gaits: dict  # {"+x": (Gait, ...), "-x": (...)}
    fit: Fit | None = None  # IMU placement, I2C time and size estimates checked before compiling
    warnings: tuple[str, ...] = ()  # feasibility problems of gaits other than gait 0 (gait_warnings)

    def size_report(self) -> str:
        b = self.board
        if not b.flash_bytes:
            return f"{b.name}: code {self.flash_used:,} bytes, static data {self.ram_used:,} bytes (host, no limit)"
        return (
            f"{b.name}: flash {self.flash_used:,} / {b.flash_bytes:,} bytes ({100 * self.flash_used / b.flash_bytes:.1f}%), "
            f"static RAM {self.ram_used:,} / {b.ram_bytes:,} bytes ({100 * self.ram_used / b.ram_bytes:.1f}%)"
        )


def default_out_dir(robot: Robot, board: Board) -> Path:
    return Path("build") / f"{robot.name}-{board.name}"


def check_buildable(robot: Robot, board: Board) -> None:
    check_board_takes(robot, board)
    for tool in board.tools():
        if shutil.which(tool) is None:
            pkgs = " ".join(board.packages) or "its toolchain"
            raise BuildError(
                f"{tool} not found, needed for board {board.name}: install the Debian packages {pkgs} "
                f"(`make toolchains` does it)"
            )
    if shutil.which("make") is None:
        raise BuildError("make not found: install the Debian package make")
    check_tick_budget(robot, board)  # last: with enforce = false it only warns


def check_board_takes(robot: Robot, board: Board) -> None:
    """What the board must offer the robot, checked without a toolchain (``flash --dry-run``
    too): PWM channels, IMU placement and the link's telemetry rate."""
    channels = len(board.pwm_pins)
    for a in robot.actuators:
        if a.channel >= channels:
            raise BuildError(pwm_channel_error(robot, a, board.name, board.pwm_pins))
    place_imus(robot, board)  # BuildError when the board cannot carry the robot's IMUs
    check_can_link(robot, board)
    # Telemetry may use at most half the UART (the firmware's TELEMETRY_MAX_HZ rule).
    frame = 24 + 2 * len(robot.limbs) + 2 * len(robot.actuators)
    link_hz = board.uart_baud // 10 // frame // 2
    if robot.control.telemetry_hz > link_hz:
        raise BuildError(
            f"{robot.where}: control.telemetry_hz = {robot.control.telemetry_hz} needs more than half of "
            f"board {board.name}'s {board.uart_baud} baud link (at most {link_hz} Hz for {frame}-byte frames)"
        )


def check_can_link(robot: Robot, board: Board) -> None:
    """On a CAN link, telemetry may use at most half the bus (worst-case stuffed frames)."""
    from .can_config import FRAME_BITS, telemetry_frames

    if getattr(board, "transport", "uart") != "can" or board.can is None:
        return
    bits = telemetry_frames(len(robot.limbs), len(robot.actuators)) * FRAME_BITS
    bus_hz = board.can.bitrate // bits // 2
    if robot.control.telemetry_hz > bus_hz:
        raise BuildError(
            f"{robot.where}: control.telemetry_hz = {robot.control.telemetry_hz} needs more than half of "
            f"board {board.name}'s {board.can.bitrate} bit/s CAN bus (at most {bus_hz} Hz for {bits}-bit telemetry)"
        )


def check_tick_budget(robot: Robot, board: Board) -> None:
    """Refuse a tick rate whose period the board's measured per-tick work (``[budget]``)
    does not fit within 70 %: its ticks would overrun, and its timers run late.

    A tick has two limits, this one and the IMUs' I2C reads (``fit.check_i2c_ticks``, every
    board, host-sim too); a rate past both is refused naming the lower, the one that binds.
    Naming the work first, the Blue Pill refused a one-limb robot at 10 kHz for its 73 µs of
    work (it takes 9,589 Hz) and host-sim for its 210 µs of I2C (3,571 Hz), the same robot
    for two reasons, the Blue Pill's not the one that limits it."""
    budget = board.budget
    if budget is None:
        return
    limbs = len(robot.limbs)
    hz = robot.control.tick_hz
    period_us = 1e6 / hz
    need_us = budget.busy_us(limbs)
    if need_us * hz > budget.BUSY_LIMIT * 1e6:  # need > 70 % of the period, without dividing
        most = budget.max_tick_hz(limbs)
        if max_tick_hz(place_imus(robot, board), i2c_hz(board)) < most:
            check_i2c_ticks(robot, board)  # the I2C reads bind (and fail at this rate): refused naming them
        message = (
            f"{robot.where}: control.tick_hz = {hz} is too fast for board {board.name}: "
            f"{limbs} {'limb needs' if limbs == 1 else 'limbs need'} {need_us:.0f} µs per tick ({budget.tick_us_base:g} + {limbs} × "
            f"{budget.tick_us_per_limb:g} µs, [budget] of {board.path.name}), more than "
            f"{100 * budget.BUSY_LIMIT:.0f} % of the {period_us:.0f} µs period; at most {most} Hz"
        )
        if budget.enforce:
            raise BuildError(message)
        logging.getLogger(__name__).warning("%s (building anyway: [budget] enforce = false)", message)


def render_project(robot: Robot, board: Board, gaits: dict) -> dict[str, str]:
    """Every file of the project directory, by relative path; same inputs, same bytes."""
    from ..protocol.render import render_c
    from .render import render_config

    tdir = templates_dir()
    files: dict[str, str] = {}
    for src in sorted((tdir / "core").iterdir()):
        if src.suffix in (".c", ".h") and (board.main_loop or src.name != CORE_MAIN) and _in_image(board, src.name):
            files[f"core/{src.name}"] = src.read_text(encoding="utf-8")
    hal_dir = tdir / "hal" / board.family
    if not hal_dir.is_dir():
        raise BuildError(f"no HAL for board family {board.family!r} in {hal_dir}")
    for src in sorted(hal_dir.iterdir()):
        if src.suffix in (".c", ".h", ".S", ".ld") and _in_image(board, src.name):  # not family.toml: data
            files[f"hal/{src.name}"] = src.read_text(encoding="utf-8")
    for name, text in render_config(robot, gaits, board).items():
        files[f"gen/{name}"] = text
    for name, text in render_c(len(robot.limbs), len(robot.actuators)).items():
        files[f"gen/{name}"] = text
    env = jinja2.Environment(
        loader=jinja2.FileSystemLoader(str(tdir)),
        undefined=jinja2.StrictUndefined,
        keep_trailing_newline=True,
    )
    files["Makefile"] = env.get_template("Makefile.j2").render(
        version=__version__,
        robot=robot,
        board=board,
        robot_file=_make_comment(display_path(robot.path)),
        board_file=_make_comment(display_path(board.path)),
    )
    return files


def _make_comment(text: str) -> str:
    """A path as the Makefile's header comment shows it: a line break in it (a directory named
    so) ended the comment, and the rest of the line became the Makefile's first rule, so `make`
    by hand failed ("No rule to make target 're-run'")."""
    return text.replace("\n", "\\n").replace("\r", "\\r")


def _in_image(board: Board, name: str) -> bool:
    """The CAN link's sources (``can*`` in core/ and hal/<family>/) are in the image only when
    the board's host link is CAN (``[link] transport = "can"``): other boards pay nothing for it."""
    return not name.startswith("can") or getattr(board, "transport", "uart") == "can"


def gait_table_hash(files: dict[str, str]) -> str:
    """The hash the firmware reports, as rendered into robot_config.h by render_config."""
    m = re.search(r"#define\s+CFG_GAIT_TABLE_HASH\s+(0x[0-9A-Fa-f]+)", files.get("gen/robot_config.h", ""))
    return m.group(1).lower() if m else ""


def build(
    robot: Robot,
    board: Board,
    out_dir: Path | None = None,
    *,
    objective: str = "total",
    max_transitions: int | None = None,
    jobs: int = 2,
    library: Any = None,
) -> BuildResult:
    """Render and compile; on success the project is at ``out_dir``, on failure nothing is (an
    older build there is kept). Ctrl-C is an ``Interrupted`` saying which of the two happened."""
    check_buildable(robot, board)
    out_dir = Path(out_dir) if out_dir is not None else default_out_dir(robot, board)
    had = (out_dir / MANIFEST).exists()
    written: list[Path] = []  # the project, once it is in place
    try:
        return _build_into(robot, board, out_dir, objective, max_transitions, jobs, library, written)
    except KeyboardInterrupt:
        if written:
            raise Interrupted(f"interrupted after the build was written: {out_dir} is complete") from None
        kept = f" ({out_dir} keeps its previous build)" if had else ""
        raise Interrupted(f"interrupted; nothing built{kept}") from None


def plan_build(robot: Robot, board: Board, out_dir: Path, objective: str = "total", max_transitions: int | None = None,
               library: Any = None) -> tuple[Any, Fit]:
    """What the build decides before it renders anything: the project directory it may
    replace, the gaits the firmware carries and whether their tables fit the board
    (BuildError otherwise). ``flash --dry-run`` asks it too: it printed a command and exit 0
    for robots whose tables are four times the board's flash, or whose directory the build
    refuses to replace."""
    if out_dir.exists() and not (out_dir / MANIFEST).exists():
        raise BuildError(f"{out_dir} exists and is not a proleg build directory: refusing to replace it")
    gaits = firmware_gaits(robot, objective, max_transitions, library)  # library: default the robot file's
    return gaits, check_fit(robot, board, gaits)


def _build_into(robot: Robot, board: Board, out_dir: Path, objective: str, max_transitions: int | None, jobs: int,
           library: Any, written: list[Path]) -> BuildResult:
    gaits, fit = plan_build(robot, board, out_dir, objective, max_transitions, library)
    warnings = tuple(gait_warnings(robot, gaits))
    files = render_project(robot, board, gaits)

    with _writing(out_dir):
        out_dir.parent.mkdir(parents=True, exist_ok=True)
        tmp = Path(tempfile.mkdtemp(prefix=f".{out_dir.name}.", dir=out_dir.parent))
        as_if_created(tmp, directory=True)
    try:
        with _writing(out_dir):
            for rel, text in files.items():
                p = tmp / rel
                p.parent.mkdir(parents=True, exist_ok=True)
                p.write_text(text, encoding="utf-8")
        _make(tmp, jobs, f"robot {robot.name} does not fit board {board.name}")
        flash_used, ram_used = _sizes(board, tmp)
        _check_limits(robot, board, flash_used, ram_used)
        digest = gait_table_hash(files)
        manifest = {
            "generator": f"proleg {__version__}",
            "robot": robot.name,
            "robot_file": display_path(robot.path),
            "robot_sha256": _sha256(robot.path),
            "board": board.name,
            "board_file": display_path(board.path),
            "artifact": board.artifact,
            "flash_used": flash_used,
            "ram_used": ram_used,
            "flash_bytes": board.flash_bytes,
            "ram_bytes": board.ram_bytes,
            "gait_table_hash": digest,
            "imu_placement": [
                {"limb": p.limb, "bus": p.bus_name, "mux": p.mux, "channel": p.channel, "address": p.address,
                 "automatic": p.automatic}
                for p in fit.placements
            ],
            "gait_objective": objective,
            "gait_max_transitions": max_transitions,
            "gait_selection": gaits.selection.as_json(),
            "gaits": {d: [list(g.states) for g in gs] for d, gs in gaits.items()},
        }
        if gaits.left_out:  # a direction whose optimal gaits the hardware cannot make: none carried, and why
            manifest["gaits_left_out"] = gaits.left_out
        if gaits.library_spec is not None:  # issue 17: the gait library, heading → (direction, gait)
            manifest["gait_library_selection"] = gaits.library_spec.as_json()
            manifest["gait_library"] = [lg.as_json(robot.transitions.label) for lg in gaits.library]
        with _writing(out_dir):
            (tmp / MANIFEST).write_text(json.dumps(manifest, indent=2) + "\n", encoding="utf-8")
            _replace_dir(tmp, out_dir)
            written.append(out_dir)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return BuildResult(out_dir, out_dir / board.artifact, board, flash_used, ram_used, digest, gaits, fit, warnings)


@contextmanager
def _writing(out_dir: Path) -> Iterator[None]:
    """A failed write (a full disk...) as one line naming the project directory (exit 1)."""
    try:
        yield
    except OSError as e:
        raise LinkError(f"cannot write build directory {out_dir}: {e.strerror or e}") from None


#: What a linker says when the image outgrows the board's flash or RAM (GNU ld, avr and arm).
_OVERFLOW = re.compile(r"is not within region|region `?[\w.]+'? overflowed|will not fit in region")


def _make(project: Path, jobs: int, overflow: str = "the firmware does not fit the board") -> None:
    """Compile and link; a link that overflows the board's memory is one line starting with
    ``overflow`` (the estimate before compiling lets past what it cannot foresee: four limbs of
    10, 2, 2, 2 levels on the Nano linked .bss past its RAM, "compilation failed" with four ld lines)."""
    proc = subprocess.run(
        ["make", "-C", str(project), f"-j{jobs}", "all"],
        capture_output=True,
        text=True,
    )
    if proc.returncode != 0:
        out = (proc.stdout + proc.stderr).replace(str(project) + "/", "")
        full = [line.split(": ", 1)[-1].strip() for line in out.splitlines() if _OVERFLOW.search(line)]
        if full:
            raise BuildError(f"{overflow}: the linker puts the firmware past the board's memory ({full[0]}); "
                             "fewer or shorter gaits (--max-transitions, another objective), fewer levels, "
                             "or a larger board")
        diagnostic = re.compile(r":\d+(:\d+)?: (fatal )?error:|: undefined reference|ld(\.bfd)?: ")
        errors = [line for line in out.splitlines() if diagnostic.search(line)] or out.splitlines()[-15:]
        raise BuildError("compilation failed:\n  " + "\n  ".join(errors[:15]))


def _sizes(board: Board, cwd: Path) -> tuple[int, int]:
    """(flash, static RAM) from the board's size command (Berkeley format: flash = text+data,
    RAM = data+bss)."""
    cmd = board.size_command()
    proc = subprocess.run(cmd, capture_output=True, text=True, cwd=cwd)
    lines = proc.stdout.strip().splitlines()
    if proc.returncode != 0 or len(lines) < 2:
        raise BuildError(f"{cmd[0]} could not read {board.link}: {proc.stderr.strip()}")
    text, data, bss = (int(x) for x in lines[1].split()[:3])
    return text + data, data + bss


def _check_limits(robot: Robot, board: Board, flash_used: int, ram_used: int) -> None:
    if board.flash_bytes and flash_used > board.flash_bytes:
        raise BuildError(
            f"robot {robot.name} needs {flash_used:,} bytes of flash, board {board.name} has {board.flash_bytes:,}"
        )
    if board.ram_bytes and ram_used + board.stack_bytes > board.ram_bytes:
        stack = f" and {board.stack_bytes:,} for its stack ([board] stack_bytes)" if board.stack_bytes else ""
        raise BuildError(
            f"robot {robot.name} needs {ram_used:,} bytes of static RAM{stack}, board {board.name} has "
            f"{board.ram_bytes:,}"
        )


def _replace_dir(new: Path, target: Path) -> None:
    """Move ``new`` to ``target``; an older build there is removed only after the move."""
    old = None
    if target.exists():
        old = target.with_name(f".{target.name}.old-{os.getpid()}")
        target.rename(old)
    try:
        new.rename(target)
    except BaseException:  # Ctrl-C or a failed rename between the two: the older build goes back
        if old is not None and not target.exists():
            old.rename(target)
        raise
    if old is not None:
        shutil.rmtree(old, ignore_errors=True)


def _sha256(path: Path) -> str:
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


