"""The firmware's build id (INFO's build_id, the console's "right firmware" check, and the seed of
the mark by which core/sma.c trusts the RAM a reset left: docs/safety.md, "A reset") covers the
firmware's own sources: an image another proleg of the same version number built for the same
robot file had the same id, so after flashing it over a running board the new image trusted the
old one's RAM, whatever its layout."""

from __future__ import annotations

import shutil
from pathlib import Path

from proleg.firmware import build_id as ids
from proleg.paths import templates_dir
from proleg.robot import load_robot

R1 = Path(__file__).resolve().parents[1] / "robots" / "paper-r1.toml"


def test_any_change_to_a_firmware_source_changes_the_sources_hash(tmp_path):
    copy = tmp_path / "t"
    shutil.copytree(templates_dir(), copy, ignore=shutil.ignore_patterns("__pycache__"))
    base = ids.firmware_sources_sha256(copy)
    assert base == ids.firmware_sources_sha256(templates_dir())  # the same files, wherever they are
    sma = copy / "core" / "sma.c"
    sma.write_bytes(sma.read_bytes().replace(b"uint8_t slot;", b"uint8_t slot; ", 1))
    assert ids.firmware_sources_sha256.__wrapped__(copy) != base
    (copy / "core" / "extra.h").write_text("")
    moved = ids.firmware_sources_sha256.__wrapped__(copy)
    (copy / "core" / "extra.h").rename(copy / "extra.h")  # the same bytes elsewhere: another tree
    assert ids.firmware_sources_sha256.__wrapped__(copy) != moved


def test_the_build_id_changes_with_the_firmware_sources(monkeypatch):
    """The console's check then tells a board flashed by another proleg from one this proleg
    would build for the same robot file (docs/safety.md, "The right firmware on the board")."""
    from proleg.console.identity import expected_identity

    robot = load_robot(R1)
    now = expected_identity(robot, "arduino-nano").build_id
    assert now == expected_identity(load_robot(R1), "arduino-nano").build_id  # deterministic
    monkeypatch.setattr(ids, "firmware_sources_sha256", lambda: "0" * 64)
    other = expected_identity(robot, "arduino-nano")
    assert other.build_id != now and other.gait_hash == expected_identity(robot, "host-sim").gait_hash
