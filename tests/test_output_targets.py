"""Outputs written through a temporary file renamed into place (``dbc -o``, ``learn --out``,
``plot -o``, ``gait --plot``) land on what the path means: a symlink is written through to
its target (the link stays a link), a FIFO or device is written in place, never replaced by
a regular file. (``proleg dbc -o /dev/stdout`` as root replaced the /dev/stdout symlink.)

Device nodes are exercised with FIFOs made here, never with a real /dev entry: a wrong
rename would destroy it."""

from __future__ import annotations

import os
import select
import stat
import threading
import time
from pathlib import Path

import pytest
from proleg.cli.main import main
from proleg.outputs import write_text_atomic
from proleg.plot import new_figure, save_figure

ROOT = Path(__file__).resolve().parents[1]
ROBOT = ROOT / "robots" / "paper-r1.toml"


class FifoReader:
    """A FIFO at ``path`` with its read end open (non-blocking, so a writer's open does not
    wait and a wrong rename cannot hang the test), drained by a thread."""

    def __init__(self, path: Path):
        os.mkfifo(path)
        self.fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK)
        self.chunks: list[bytes] = []
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._drain, daemon=True)
        self._thread.start()

    def _read(self) -> bool:
        try:
            b = os.read(self.fd, 1 << 16)
        except BlockingIOError:
            return False
        if b:
            self.chunks.append(b)
        return bool(b)

    def _drain(self) -> None:
        while not self._stop.is_set():
            if select.select([self.fd], [], [], 0.05)[0] and not self._read():
                time.sleep(0.01)  # readable with no data: no writer at the moment

    def data(self) -> bytes:
        self._stop.set()
        self._thread.join(5)
        while self._read():
            pass
        os.close(self.fd)
        return b"".join(self.chunks)


def _is_fifo(p: Path) -> bool:
    return stat.S_ISFIFO(os.lstat(p).st_mode)


def test_dbc_through_a_symlink_replaces_the_target_and_keeps_the_link(tmp_path, capsys):
    target = tmp_path / "target.dbc"
    target.write_text("old\n")
    link = tmp_path / "link.dbc"
    link.symlink_to("target.dbc")
    assert main(["dbc", "-o", str(link), "--robot", str(ROBOT)]) == 0
    assert link.is_symlink() and os.readlink(link) == "target.dbc"
    assert target.read_text().startswith("VERSION")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["link.dbc", "target.dbc"]  # no temp left


def test_a_dangling_symlink_output_creates_its_target(tmp_path):
    link = tmp_path / "link.txt"
    link.symlink_to("made.txt")
    write_text_atomic(link, "hello\n", "test")
    assert link.is_symlink()
    assert (tmp_path / "made.txt").read_text() == "hello\n"


def test_dbc_to_a_fifo_writes_into_the_fifo(tmp_path):
    fifo = tmp_path / "f.dbc"
    reader = FifoReader(fifo)
    assert main(["dbc", "-o", str(fifo), "--robot", str(ROBOT)]) == 0
    got = reader.data()
    assert _is_fifo(fifo)
    assert got.startswith(b"VERSION") and b"BO_ " in got
    assert [p.name for p in tmp_path.iterdir()] == ["f.dbc"]


def test_a_symlink_to_a_fifo_is_written_through_and_both_stay(tmp_path):
    fifo = tmp_path / "f"
    reader = FifoReader(fifo)
    link = tmp_path / "out.txt"
    link.symlink_to(fifo)
    write_text_atomic(link, "through the link\n", "test")
    assert reader.data() == b"through the link\n"
    assert link.is_symlink() and _is_fifo(fifo)


def test_a_figure_to_a_fifo_and_through_a_symlink(tmp_path):
    fig = new_figure(2, 2)
    fig.subplots().plot([0, 1], [0, 1])
    fifo = tmp_path / "p.svg"
    reader = FifoReader(fifo)
    save_figure(fig, fifo)
    assert _is_fifo(fifo) and b"<svg" in reader.data()

    (tmp_path / "real.svg").write_text("old")
    link = tmp_path / "lnk.svg"
    link.symlink_to("real.svg")
    save_figure(fig, link)
    assert link.is_symlink() and "<svg" in (tmp_path / "real.svg").read_text()


def test_plot_and_gait_plot_write_through_a_symlink(tmp_path, capsys):
    rec = tmp_path / "r.csv"
    assert main(["sim", str(ROBOT), "--duration", "2", "--record", str(rec)]) == 0
    for argv, name in ((["plot", str(rec), "-o"], "plot"), (["gait", str(ROBOT), "--plot"], "gait")):
        (tmp_path / f"{name}-real.png").write_bytes(b"old")
        link = tmp_path / f"{name}.png"
        link.symlink_to(f"{name}-real.png")
        assert main(argv + [str(link)]) == 0
        assert link.is_symlink()
        assert (tmp_path / f"{name}-real.png").read_bytes().startswith(b"\x89PNG")


def test_learn_out_through_a_symlink_keeps_the_link(tmp_path):
    from proleg.learn.estimate import estimate
    from proleg.learn.robotfile import write_learned_robot
    from proleg.robot import load_robot

    robot = load_robot(ROBOT)
    est = estimate(robot.transitions, [])  # nothing measured: the file's values kept
    (tmp_path / "real.toml").write_text("old")
    link = tmp_path / "learned.toml"
    link.symlink_to("real.toml")
    write_learned_robot(robot, est, link)
    assert link.is_symlink()
    assert "[transitions]" in (tmp_path / "real.toml").read_text()


@pytest.mark.parametrize("path", ["/dev/null"])
def test_a_device_is_a_target_written_in_place(path):
    from proleg.outputs import output_target

    # stat only: nothing is opened or renamed here
    assert output_target(path) == (Path(path), True)


@pytest.mark.parametrize("stdout_is", ["a pipe", "a file"])
def test_dbc_to_standard_output_writes_it_there_and_notes_on_stderr(tmp_path, stdout_is):
    # /proc/self/fd/1, not /dev/stdout: a wrong rename there could only fail, never replace a
    # system entry
    import subprocess
    import sys

    env = {**os.environ, "PYTHONPATH": str(ROOT / "host" / "src")}
    argv = [sys.executable, "-m", "proleg", "dbc", "-o", "/proc/self/fd/1", "--robot", str(ROBOT)]
    if stdout_is == "a pipe":
        p = subprocess.run(argv, check=False, capture_output=True, env=env, timeout=120)
        got = p.stdout
    else:
        out = tmp_path / "piped.dbc"
        with open(out, "wb") as fh:
            p = subprocess.run(argv, check=False, stdout=fh, stderr=subprocess.PIPE, env=env, timeout=120)
        got = out.read_bytes()
        assert [x.name for x in tmp_path.iterdir()] == ["piped.dbc"]
    assert p.returncode == 0, p.stderr
    assert got.startswith(b"VERSION") and b"wrote" not in got
    assert b"wrote /proc/self/fd/1" in p.stderr
