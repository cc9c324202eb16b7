"""What the build and flash tests share: run the CLI and capture its output (``cli``), a
board or robot file with a few lines changed (``board_variant``, ``robot_variant``), an
empty output directory and the check that a failure left nothing in it, and the check that
an error is one ``proleg: error:`` line (``one_line``), a forked child's exit status
(``exit_status_within``), and the smallest two-limb robot file up to its ``[transitions]``
(``TWO_LIMBS``) for the robot-file tests to finish. No test lives here.
"""

from __future__ import annotations

import os
import re
import time
from pathlib import Path

from proleg.cli import main

ROOT = Path(__file__).resolve().parents[1]
R1 = ROOT / "robots" / "paper-r1.toml"

#: R1's two limbs (ψ* 20°) on coils a and b, channels 0 and 1: a robot file but for its
#: [transitions] table, which the tests append (and what they are about after it).
TWO_LIMBS = """
[robot]
name = "t"

[[limb]]
name = "left"
psi_star_deg = [20.0]
actuator = "a"

[[limb]]
name = "right"
psi_star_deg = [20.0]
actuator = "b"

[[actuator]]
name = "a"
channel = 0

[[actuator]]
name = "b"
channel = 1

"""
#: R1's matrix in the paper's steps, as a [transitions] table line.
R1_MATRIX = "matrix = [[0, -1, 1, 0], [1, 0, 0, -1], [-1, 0, 0, 1], [0, 0, 0, 0]]"


def cli(capsys, *argv: str) -> tuple[int, str, str]:
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def board_variant(tmp_path: Path, name: str, *subs: tuple[str, str]) -> Path:
    """A copy of boards/NAME.toml in tmp_path with each (regex, replacement) applied once."""
    text = (ROOT / "boards" / f"{name}.toml").read_text(encoding="utf-8")
    for pattern, repl in subs:
        text, n = re.subn(pattern, repl, text, count=1, flags=re.M)
        assert n == 1, f"{pattern!r} not found in boards/{name}.toml"
    path = tmp_path / "boardfiles" / f"{name}-variant.toml"
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text, encoding="utf-8")
    return path


def robot_variant(tmp_path: Path, src: Path, *subs: tuple[str, str]) -> Path:
    text = src.read_text(encoding="utf-8")
    for pattern, repl in subs:
        text, n = re.subn(pattern, repl, text, count=1, flags=re.M | re.S)
        assert n == 1, f"{pattern!r} not found in {src.name}"
    path = tmp_path / "robotfiles" / src.name
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text, encoding="utf-8")
    return path


def empty_build_dir(tmp_path: Path) -> Path:
    """An empty directory the build's output goes into: after a failure it must stay empty
    (the ``parent`` fixture of the tests that build)."""
    p = tmp_path / "builds"
    p.mkdir()
    return p


def assert_nothing_left(parent: Path) -> None:
    left = sorted(p.name for p in parent.iterdir())
    assert left == [], f"a failed build left {left} in {parent}"


def one_line(err: str) -> str:
    lines = err.strip().splitlines()
    assert len(lines) == 1, f"expected one error line, got:\n{err}"
    assert lines[0].startswith("proleg: error: ")
    assert "Traceback" not in err
    return lines[0]


def exit_status_within(pid: int, timeout_s: float = 30.0) -> int | None:
    """The exit status of the child ``pid`` (``os.waitstatus_to_exitcode``) once it ends within
    ``timeout_s``, else None: it still runs, and is the caller's to kill."""
    for _ in range(int(timeout_s / 0.1)):
        done, st = os.waitpid(pid, os.WNOHANG)
        if done:
            return os.waitstatus_to_exitcode(st)
        time.sleep(0.1)
    return None
