"""Ctrl-C: exit 130 with one line saying what was kept, and nothing half-written.

The sweep's 3.7: ``sim`` and ``build`` interrupted with Ctrl-C printed nothing, not even
"recording kept in …"; ``learn`` already said what it kept (tests/test_learn_cli.py).
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from build_checks import R1, assert_nothing_left, cli, empty_build_dir
from proleg.firmware import build as build_mod
from proleg.firmware.boards import load_board
from proleg.firmware.build import MANIFEST, build
from proleg.record import read_recording
from proleg.report.gait_run import SimSession
from proleg.robot import load_robot

ROOT = Path(__file__).resolve().parents[1]


def _ctrl_c_after(monkeypatch, seconds: float) -> None:
    """Ctrl-C once the simulated board's clock passes ``seconds`` (boot included)."""
    real = SimSession._dispatch

    def dispatch(self, rx):
        real(self, rx)
        if self.sim.time_s > seconds:
            raise KeyboardInterrupt

    monkeypatch.setattr(SimSession, "_dispatch", dispatch)


@pytest.mark.parametrize("suffix", [".csv", ".jsonl", ".mcap"])
def test_an_interrupted_sim_says_how_far_it_got_and_keeps_a_whole_recording(capsys, monkeypatch, tmp_path, suffix):
    record = tmp_path / f"run{suffix}"
    _ctrl_c_after(monkeypatch, 3.0)
    code, out, err = cli(capsys, "sim", R1, "--duration", "60", "--record", record)
    assert code == 130 and out == "" and "Traceback" not in err
    (line,) = err.splitlines()
    assert line.startswith("proleg: interrupted 2.") and "s into the 60 s run (simulated time)" in line
    assert line.endswith(f"recording kept in {record} (complete up to there)")
    recording = read_recording(record)  # closed whole: no torn line, the MCAP has its footer
    assert 2.5 < recording.time_s[-1] < 3.5 and len(recording.time_s) > 50
    assert "torn" not in capsys.readouterr().err


def test_an_interrupted_sim_without_a_recording_says_nothing_was_recorded(capsys, monkeypatch):
    _ctrl_c_after(monkeypatch, 0.1)  # during the boot, before START
    code, out, err = cli(capsys, "sim", R1, "--duration", "60", "--json")
    assert code == 130 and out == ""
    assert err == "proleg: interrupted before the run started; nothing recorded\n"


def test_an_interrupted_build_leaves_nothing_and_says_so(capsys, monkeypatch, tmp_path):
    parent = empty_build_dir(tmp_path)

    def make(project, jobs):  # Ctrl-C while the compiler runs
        raise KeyboardInterrupt

    monkeypatch.setattr(build_mod, "_make", make)
    code, out, err = cli(capsys, "build", R1, "--board", "host-sim", "-o", parent / "fw")
    assert code == 130 and out == "" and err == "proleg: interrupted; nothing built\n"
    assert_nothing_left(parent)


def test_an_interrupted_rebuild_keeps_the_previous_build_and_says_so(capsys, monkeypatch, tmp_path):
    parent = empty_build_dir(tmp_path)
    out_dir = parent / "fw"
    build(load_robot(R1), load_board("host-sim"), out_dir)
    before = {p.relative_to(out_dir): p.read_bytes() for p in out_dir.rglob("*") if p.is_file()}
    real_rename = Path.rename
    hits = []

    def rename(self, target):  # Ctrl-C between moving the old build aside and the new one in
        if Path(target) == out_dir and not hits:
            hits.append(self)
            raise KeyboardInterrupt
        return real_rename(self, target)

    monkeypatch.setattr(Path, "rename", rename)
    code, out, err = cli(capsys, "build", R1, "--board", "host-sim", "-o", out_dir)
    assert code == 130 and out == ""
    assert err == f"proleg: interrupted; nothing built ({out_dir} keeps its previous build)\n"
    assert {p.relative_to(out_dir): p.read_bytes() for p in out_dir.rglob("*") if p.is_file()} == before
    assert sorted(p.name for p in parent.iterdir()) == ["fw"]
    assert (out_dir / MANIFEST).exists() and hits and hits[0].name.startswith(".fw.")  # the new one, refused


def test_ctrl_c_on_a_real_sim_process_ends_with_the_line_and_a_readable_mcap(tmp_path):
    """The signal itself, not a stand-in: SIGINT to ``proleg sim --record run.mcap``."""
    record = tmp_path / "run.mcap"
    env = {**os.environ, "PYTHONPATH": str(ROOT / "host" / "src")}
    proc = subprocess.Popen([sys.executable, "-m", "proleg", "sim", str(R1), "--duration", "3600", "--record",
                             str(record)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and (not record.exists() or record.stat().st_size < 20_000):
        time.sleep(0.2)
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=60)
    assert proc.returncode == 130 and out == "" and "Traceback" not in err, err
    lines = [x for x in err.splitlines() if "warning" not in x]
    assert len(lines) == 1 and lines[0].startswith("proleg: interrupted ")
    assert lines[0].endswith(f"recording kept in {record} (complete up to there)")
    assert len(read_recording(record).time_s) > 0
