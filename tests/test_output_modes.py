"""Outputs written through a temporary file and a rename (DBC, plots, the build directory)
get the mode a plain open/mkdir gives under the user's umask, not mkstemp's 0600/0700: a lab
shares its build/ and plots."""

from __future__ import annotations

import os
import stat
from pathlib import Path

import pytest
from proleg.firmware.boards import load_board
from proleg.firmware.build import build
from proleg.protocol.dbc import write_dbc
from proleg.robot import load_robot

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture
def umask_027():
    old = os.umask(0o027)
    yield
    os.umask(old)


def _mode(p: Path) -> int:
    return stat.S_IMODE(p.stat().st_mode)


def test_a_dbc_file_takes_the_umask(tmp_path, umask_027):
    out = write_dbc(tmp_path / "proleg.dbc")
    assert _mode(out) == 0o640


def test_a_build_directory_takes_the_umask(tmp_path, umask_027):
    result = build(load_robot(ROOT / "robots" / "paper-r1.toml"), load_board("host-sim"), tmp_path / "out")
    assert _mode(tmp_path / "out") == 0o750
    assert result.flash_used > 0
