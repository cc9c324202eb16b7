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
from build_checks import R1, assert_nothing_left, cli, empty_build_dir, exit_status_within
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


@pytest.fixture
def python_sigint():
    """SIGINT as a terminal's Ctrl-C gives it (a test worker started in the background ignores it)."""
    old = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, old)


def test_a_real_sigint_inside_an_mcap_chunk_write_waits_for_the_chunk(capsys, monkeypatch, tmp_path, python_sigint):
    """The signal itself, sent while the MCAP writer is writing its first chunk to the file:
    the chunk is written whole, then the run stops, and the recording reads back."""
    from proleg.record.mcap_format import McapWriter

    real_open, sent = McapWriter.open, []

    class Torn:  # the file, with Ctrl-C pressed during the first big write
        def __init__(self, f):
            self.f = f

        def write(self, data):
            if len(data) > 2048 and not sent:  # a chunk (16 KiB of messages, compressed), not its index
                sent.append(len(data))
                os.kill(os.getpid(), signal.SIGINT)  # handled at the next line, mid-chunk
                half = len(data) // 2
                return self.f.write(data[:half]) + self.f.write(data[half:])
            return self.f.write(data)

        def __getattr__(self, name):
            return getattr(self.f, name)

    def open_(self):
        real_open(self)
        self._w._Writer__stream = Torn(self._w._Writer__stream)  # the mcap library's own stream

    monkeypatch.setattr(McapWriter, "open", open_)
    record = tmp_path / "run.mcap"
    code, out, err = cli(capsys, "sim", R1, "--duration", "600", "--record", record)
    assert sent and code == 130 and out == "" and "Traceback" not in err, err
    assert err.rstrip().endswith(f"recording kept in {record} (complete up to there)")
    assert len(read_recording(record).time_s) > 40  # the chunk that was being written (16 KiB) is in it


def test_an_interrupted_sim_without_a_recording_says_nothing_was_recorded(capsys, monkeypatch):
    _ctrl_c_after(monkeypatch, 0.1)  # during the boot, before START
    code, out, err = cli(capsys, "sim", R1, "--duration", "60", "--json")
    assert code == 130 and out == ""
    assert err == "proleg: interrupted before the run started; nothing recorded\n"


@pytest.mark.parametrize("suffix", [".csv", ".mcap"])
def test_a_sim_interrupted_before_its_run_started_keeps_no_recording(capsys, monkeypatch, tmp_path, suffix):
    """Calibrating on the flat before START (--calibrated): a recording of no run is not kept,
    as proleg run does not keep one."""
    record = tmp_path / f"run{suffix}"
    _ctrl_c_after(monkeypatch, 1.0)
    code, out, err = cli(capsys, "sim", R1, "--calibrated", "--record", record)
    assert code == 130 and out == ""
    assert err == "proleg: interrupted before the run started; nothing recorded\n"
    assert list(tmp_path.iterdir()) == []


def test_a_real_sigint_between_opening_a_recording_and_keeping_it_loses_nothing(
        capsys, monkeypatch, tmp_path, python_sigint):
    """The signal lands after the writer opened its file and before the command holds it in
    its listeners: the command still closes it (here: removes it, no run had started) rather
    than leaving an MCAP without its footer and saying nothing was recorded."""
    from proleg.cli import sim_command

    real, opened = sim_command._recorder, []

    def recorder(*args):
        writer = real(*args)
        opened.append(writer.path)
        os.kill(os.getpid(), signal.SIGINT)  # handled at the next line: before the caller has it
        return writer

    monkeypatch.setattr(sim_command, "_recorder", recorder)
    record = tmp_path / "run.mcap"
    code, out, err = cli(capsys, "sim", R1, "--record", record)
    assert opened == [record] and code == 130 and out == ""
    assert err == "proleg: interrupted before the run started; nothing recorded\n"
    assert not record.exists()


def test_an_interrupted_build_leaves_nothing_and_says_so(capsys, monkeypatch, tmp_path):
    parent = empty_build_dir(tmp_path)

    def make(project, jobs, *rest):  # Ctrl-C while the compiler runs
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


#: ``python -c`` that gives SIGINT (and SIGTERM, SIGHUP) the disposition a shell's foreground
#: job has, then execs ``proleg ARGS``: a test run started in the background (``make test &``)
#: ignores SIGINT, under ``nohup`` SIGHUP, and an exec'd child would inherit that (a wrapper,
#: not ``preexec_fn``: this process has threads).
_AS_FROM_A_TERMINAL = ("import os, signal, sys; "
                       "[signal.signal(s, signal.SIG_DFL) for s in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)]; "
                       "signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT, signal.SIGTERM, signal.SIGHUP}); "
                       "os.execv(sys.executable, [sys.executable, '-m', 'proleg', *sys.argv[1:]])")


def _sigint_once_recording(args: list[str], record: Path, sig: int = signal.SIGINT) -> list[str]:
    """``proleg ARGS`` in a process of its own, sent ``sig`` once ``record`` holds 20 kB: it exits
    130 (SIGINT) or 128 + the signal with nothing on stdout and no traceback; its stderr lines
    besides warnings."""
    env = {**os.environ, "PYTHONPATH": str(ROOT / "host" / "src")}
    proc = subprocess.Popen([sys.executable, "-c", _AS_FROM_A_TERMINAL, *args], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, env=env)
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and (not record.exists() or record.stat().st_size < 20_000):
        time.sleep(0.2)
    proc.send_signal(sig)
    out, err = proc.communicate(timeout=60)
    assert proc.returncode == (130 if sig == signal.SIGINT else 128 + sig), (proc.returncode, err)
    assert out == "" and "Traceback" not in err, err
    return [x for x in err.splitlines() if "warning" not in x]


def test_ctrl_c_on_a_real_sim_process_ends_with_the_line_and_a_readable_mcap(tmp_path):
    """The signal itself, not a stand-in: SIGINT to ``proleg sim --record run.mcap``."""
    record = tmp_path / "run.mcap"
    lines = _sigint_once_recording(["sim", str(R1), "--duration", "3600", "--record", str(record)], record)
    assert len(lines) == 1 and lines[0].startswith("proleg: interrupted ")
    assert lines[0].endswith(f"recording kept in {record} (complete up to there)")
    assert len(read_recording(record).time_s) > 0


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGHUP])
def test_sigterm_and_sighup_end_a_sim_as_ctrl_c_does(tmp_path, sig):
    """``kill`` (a CI job's timeout) or a closed terminal killed the process mid-run: no STOP, no
    line, an MCAP without its footer. They now end it as Ctrl-C does, exit 128 + the signal."""
    record = tmp_path / "run.mcap"
    lines = _sigint_once_recording(["sim", str(R1), "--duration", "3600", "--record", str(record)], record, sig)
    assert len(lines) == 1 and lines[0].endswith(f"recording kept in {record} (complete up to there)")
    assert len(read_recording(record).time_s) > 0


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM, signal.SIGHUP])
def test_a_signal_ends_sim_pty_with_its_exit_status_and_one_line(sig):
    """``sim --pty`` took Ctrl-C (and SIGTERM, SIGHUP, delivered as one) for its way to stop
    and exited 0: a script or CI job could not tell it was stopped. Only console is exempt."""
    env = {**os.environ, "PYTHONPATH": str(ROOT / "host" / "src")}
    proc = subprocess.Popen([sys.executable, "-c", _AS_FROM_A_TERMINAL, "sim", str(R1), "--pty"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    try:
        first = proc.stdout.readline()  # serving once it names the pty
        assert first.startswith("simulated paper-r1 on /dev/"), first
        path = first.split(" on ")[1].split(" ")[0]
        time.sleep(0.5)
        proc.send_signal(sig)
        out, err = proc.communicate(timeout=30)
    finally:
        proc.kill()
    assert proc.returncode == (130 if sig == signal.SIGINT else 128 + sig), (proc.returncode, err)
    lines = [x for x in err.splitlines() if "warning" not in x]
    assert len(lines) == 1 and lines[0].startswith("proleg: interrupted after serving "), err
    assert lines[0].endswith(f" s (simulated) on {path}; nothing recorded")


def test_ctrl_c_before_the_command_begins_is_one_line(capsys, monkeypatch):
    """Ctrl-C while the parser is built (or Python still loads proleg) printed a traceback."""
    import importlib

    cli_main = importlib.import_module("proleg.cli.main")  # the module: proleg.cli.main is also the function

    def interrupted():
        raise KeyboardInterrupt

    monkeypatch.setattr(cli_main, "build_parser", interrupted)
    assert cli_main.main(["robots"]) == 130
    assert capsys.readouterr().err == "proleg: interrupted\n"


# --------------------------------------------------------------------------- proleg run
def _ctrl_c_while_a_coil_heats(monkeypatch, seconds: float) -> list[list[float]]:
    """Ctrl-C in ``proleg run --sim`` once the link's clock passes ``seconds`` at a moment a coil
    is on; returns the list that gets the coils' duties as the link closes."""
    from proleg.link.client import RobotClient

    real_recv, real_close = RobotClient.recv_received, RobotClient.close
    duties: list[list[float]] = []

    def board(client):
        return client.link.board.board  # the SimLink's SimulatedRobot's SimBoard

    def recv(self, *a, **k):
        if self.link.clock() > seconds and any(board(self).pwm(c) > 0 for c in (0, 1)):
            raise KeyboardInterrupt
        return real_recv(self, *a, **k)

    def close(self):
        if not self._closed:
            duties.append([board(self).pwm(c) for c in (0, 1)])
        real_close(self)

    monkeypatch.setattr(RobotClient, "recv_received", recv)
    monkeypatch.setattr(RobotClient, "close", close)
    return duties


def test_an_interrupted_run_stops_the_robot_says_how_far_it_got_and_keeps_a_whole_recording(
        capsys, monkeypatch, tmp_path):
    record = tmp_path / "run.mcap"
    duties = _ctrl_c_while_a_coil_heats(monkeypatch, 3.0)
    code, out, err = cli(capsys, "run", R1, "--sim", "--duration", "20", "--record", record, "-q")
    assert code == 130 and out == "" and "Traceback" not in err
    (line,) = err.splitlines()
    assert line.startswith("proleg: interrupted 3.") and " s into the 20 s run (simulated time), after " in line
    assert "; STOP acknowledged: the gait is stopped and the coils are off; " in line
    assert line.endswith(f"recording kept in {record} (complete up to there)")
    assert duties == [[0.0, 0.0]]  # a coil was heating at the Ctrl-C; none is once the link closes
    recording = read_recording(record)  # closed whole: the MCAP has its footer
    assert 2.5 < recording.time_s[-1] < 3.5
    # the stop the line reports is in the recording too: STOP's ACK and the firmware's GAIT_STOPPED
    stops = [e for e in recording.events if e["kind"] == "GAIT_STOPPED"]
    assert len(stops) == 1 and stops[0]["text"].startswith("gait stopped: COMMAND"), recording.events[-3:]
    assert 2.5 < stops[0]["t_s"] < 3.5
    assert any(e["msg"] == "ACK" and e["t_host_s"] >= stops[0]["t_host_s"] - 0.01 for e in recording.events)


def test_an_interrupted_jsonl_run_says_no_result_line_was_printed(capsys, monkeypatch):
    _ctrl_c_while_a_coil_heats(monkeypatch, 1.0)
    code, out, err = cli(capsys, "run", R1, "--sim", "--format", "jsonl", "-q")
    assert code == 130 and '"RESULT"' not in out
    assert err.endswith("; STOP acknowledged: the gait is stopped and the coils are off; nothing recorded; "
                        "no RESULT line printed\n")


def test_a_run_interrupted_while_connecting_started_nothing_and_wrote_no_recording(capsys, monkeypatch, tmp_path):
    from proleg.link.client import RobotClient

    def connect(self, *a, **k):
        raise KeyboardInterrupt

    monkeypatch.setattr(RobotClient, "connect", connect)
    code, out, err = cli(capsys, "run", R1, "--sim", "--record", tmp_path / "run.csv")
    assert code == 130 and out == ""
    assert err == ("proleg: interrupted while connecting, before the gait started: nothing was started on the "
                   "robot; nothing recorded\n")
    assert list(tmp_path.iterdir()) == []


def test_a_ctrl_c_whose_stop_goes_unanswered_sends_estop_and_says_what_is_left():
    from proleg.report.robot_run import _stop_after_ctrl_c, stop_text

    sent = []

    def command(name):
        sent.append(name)
        if name == "STOP":
            raise KeyboardInterrupt  # a second Ctrl-C while STOP waits: on to the ESTOP
        return True

    assert _stop_after_ctrl_c(command) == "ESTOP" and sent == ["STOP", "ESTOP"]
    assert _stop_after_ctrl_c(lambda name: False) is None
    assert "E-stop stays latched" in stop_text("ESTOP")
    assert "link watchdog stops the gait and turns the coils off within 2000 ms" in stop_text(None, 2000)
    assert "the coils may still be on, switch the robot's power off" in stop_text(None, 0)


# --------------------------------------------------------------------------- proleg calibrate
def _board_kept_across_commands(monkeypatch):
    """A simulated R1 board that outlives ``proleg calibrate --port …``, as a real one does:
    the command's link opens on it, and the test reconnects afterwards to see what it kept."""
    from proleg.cli import robot_link
    from proleg.link.client import RobotClient
    from proleg.link.sim_link import SimLink
    from proleg.sim.closed_loop import SimulatedRobot

    sim = SimulatedRobot(load_robot(R1), conditions=["imu_offset_deg=left:8", "imu_offset_deg=right:-8"])

    def connect(*args, **kwargs):
        client = RobotClient(SimLink(sim, step_s=sim.plant_dt_s))
        client.connect()
        return client

    monkeypatch.setattr(robot_link, "open_client", connect)  # where calibrate takes its link
    return connect


def test_an_interrupted_calibration_is_finished_by_the_board_whole_and_the_line_says_so(capsys, monkeypatch):
    from proleg.link import level
    from proleg.protocol.definition import LevelStatus

    connect = _board_kept_across_commands(monkeypatch)

    def ctrl_c(client, within_s=level.DONE_WITHIN_S):  # as CALIBRATE_LEVEL is acknowledged
        raise KeyboardInterrupt

    monkeypatch.setattr(level, "level_outcome", ctrl_c)
    code, out, err = cli(capsys, "calibrate", R1, "--port", "/dev/ttyUSB9")
    assert code == 130 and out == ""
    assert err.startswith("proleg: interrupted while the board was calibrating: it finishes on its own within a "
                          "second or so and either stores the new record whole or keeps the one it had")
    assert err.endswith(" --port /dev/ttyUSB9 --show\n") and "check which: proleg calibrate " in err
    client = connect()  # the board went on without the host: a whole record, the mounting tilts
    end = client.link.clock() + 1.0
    while client.link.clock() < end:
        client.recv(0.05)
    reading = level.get_level(client)
    left, right = reading.offsets_cdeg
    assert reading.status == LevelStatus.STORED and abs(left - 800) < 15 and abs(right + 800) < 15


def test_a_calibration_interrupted_while_connecting_asked_the_board_nothing(capsys, monkeypatch):
    from proleg.cli import robot_link
    from proleg.protocol.definition import LevelStatus

    connect = _board_kept_across_commands(monkeypatch)

    def ctrl_c(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(robot_link, "open_client", ctrl_c)
    code, out, err = cli(capsys, "calibrate", R1, "--port", "/dev/ttyUSB9")
    assert code == 130 and out == ""
    assert err == "proleg: interrupted before anything was asked of the board: its level calibration is unchanged\n"
    from proleg.link.level import get_level

    assert get_level(connect()).status == LevelStatus.NONE


def test_an_interrupted_calibration_of_a_sim_board_says_nothing_is_kept(capsys, monkeypatch):
    from proleg.link import level

    def ctrl_c(client, within_s=level.DONE_WITHIN_S):
        raise KeyboardInterrupt

    monkeypatch.setattr(level, "level_outcome", ctrl_c)
    code, out, err = cli(capsys, "calibrate", R1, "--sim")
    assert code == 130 and out == ""
    assert err == ("proleg: interrupted while the simulated board was calibrating; nothing kept: a --sim board "
                   "lives for this command only\n")


# --------------------------------------------------------------------------- proleg sim --measure-matrix
def _ctrl_c_at_drive(monkeypatch, call: int) -> None:
    """Ctrl-C in the idealised drive's ``call``-th run to a state (each transition measured is
    two: to its start, then to its end)."""
    from proleg.sim.physical import measure

    real, calls = measure._run_to, []

    def run_to(*a, **k):
        calls.append(1)
        if len(calls) == call:
            raise KeyboardInterrupt
        return real(*a, **k)

    monkeypatch.setattr(measure, "_run_to", run_to)


@pytest.mark.parametrize("json_flag", [[], ["--json"]], ids=["text", "json"])
def test_an_interrupted_matrix_measurement_says_how_many_transitions_and_prints_nothing(
        capsys, monkeypatch, json_flag):
    _ctrl_c_at_drive(monkeypatch, 7)  # in the 4th transition: 3 measured
    code, out, err = cli(capsys, "sim", R1, "--measure-matrix", *json_flag)
    assert code == 130 and out == ""
    assert err == ("proleg: interrupted after 3 of 24 trials (12 allowed transitions, 2 times each; 3 reached "
                   "their target); nothing printed: the matrix (text or --json) is printed only once every "
                   "transition is measured\n")


def test_an_interrupted_hold_range_counts_over_every_margin(capsys, monkeypatch):
    _ctrl_c_at_drive(monkeypatch, 48 + 5)  # the first margin's 24 transitions, then 2 of the second's
    # in this process (--jobs 1): the stand-in Ctrl-C is raised in the drive, which a worker would run
    code, out, err = cli(capsys, "sim", R1, "--measure-matrix", "--hold-range", "--json", "--jobs", "1")
    assert code == 130 and out == ""
    assert err.startswith("proleg: interrupted after 26 of 72 trials (12 allowed transitions, 2 times each at "
                          "each of 3 hold margins; 26 reached their target); nothing printed")


def test_ctrl_c_on_a_hold_range_measured_in_workers_ends_with_the_line_and_leaves_no_process():
    """The signal itself, as a terminal sends it: SIGINT to the whole process group of ``proleg
    sim caterpillar-4 --measure-matrix --hold-range --jobs 3`` (the parent, its three workers and
    the queue they count through): it exits 130 with the one line, counted over the margins, and
    nothing of the group goes on."""
    env = {**os.environ, "PYTHONPATH": str(ROOT / "host" / "src")}
    proc = subprocess.Popen([sys.executable, "-c", _AS_FROM_A_TERMINAL, "sim", str(ROOT / "robots" / "caterpillar-4.toml"),
                             "--measure-matrix", "--hold-range", "--jobs", "3", "--json"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env, start_new_session=True)
    time.sleep(4.0)  # started, the workers measuring (the whole takes about a minute of CPU)
    os.killpg(proc.pid, signal.SIGINT)
    out, err = proc.communicate(timeout=60)
    assert proc.returncode == 130 and out == "" and "Traceback" not in err, err
    line = err.strip().splitlines()[-1]
    assert line.startswith("proleg: interrupted after ") and " of 840 trials (140 allowed transitions, 2 times each at " \
        "each of 3 hold margins; " in line, line
    deadline = time.monotonic() + 10
    while True:
        try:
            os.killpg(proc.pid, 0)   # any process left in its group
        except ProcessLookupError:
            break
        assert time.monotonic() < deadline, "a worker outlived the interrupted measurement"
        time.sleep(0.1)


def test_a_matrix_measurement_interrupted_at_once_measured_nothing(capsys, monkeypatch):
    _ctrl_c_at_drive(monkeypatch, 1)
    code, out, err = cli(capsys, "sim", R1, "--measure-matrix")
    assert code == 130 and out == ""
    assert err.startswith("proleg: interrupted before the first transition was measured; nothing printed")


def test_ctrl_c_on_a_real_run_process_stops_the_robot_and_ends_with_the_line(tmp_path):
    """The signal itself: SIGINT to ``proleg run --sim --speed 1 --record run.jsonl``."""
    record = tmp_path / "run.jsonl"
    lines = _sigint_once_recording(["run", str(R1), "--sim", "--speed", "1", "--duration", "600", "--record",
                                    str(record), "-q"], record)
    assert len(lines) == 1 and lines[0].startswith("proleg: interrupted ") and " s into the 600 s run" in lines[0]
    assert "; STOP acknowledged: the gait is stopped and the coils are off; " in lines[0]
    assert lines[0].endswith(f"recording kept in {record} (complete up to there)")
    assert len(read_recording(record).time_s) > 0


def test_a_run_interrupted_while_checking_the_board_started_nothing(capsys, monkeypatch, tmp_path):
    import proleg.report

    def check_gait(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(proleg.report, "check_gait", check_gait)
    code, out, err = cli(capsys, "run", R1, "--sim", "--record", tmp_path / "run.mcap")
    assert code == 130 and out == ""
    assert err == ("proleg: interrupted before the gait started: nothing was started on the robot and no coil was "
                   "driven; nothing recorded\n")
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("suffix", [".csv", ".jsonl", ".mcap"])
def test_a_recording_opened_for_a_run_that_never_started_is_removed(capsys, monkeypatch, tmp_path, suffix):
    import proleg.report

    def run_gait_on(*args, **kwargs):  # Ctrl-C after the recording was opened, before START
        raise KeyboardInterrupt

    monkeypatch.setattr(proleg.report, "run_gait_on", run_gait_on)
    code, _, err = cli(capsys, "run", R1, "--sim", "--record", tmp_path / f"run{suffix}")
    assert code == 130 and err.endswith("; nothing recorded\n")
    assert list(tmp_path.iterdir()) == []


def test_a_console_interrupted_while_it_sets_up_closes_the_recording_it_opened(capsys, monkeypatch, tmp_path):
    """Ctrl-C after --record opened its file, before the session began (here while the UDP
    streamer is being made): the robot is stopped and the MCAP still gets its footer."""
    from proleg.record import udp

    def ctrl_c(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(udp.UdpStreamer, "__init__", ctrl_c)
    record = tmp_path / "session.mcap"
    code, _, err = cli(capsys, "console", "--sim", "paper-r1", "--plain", "--duration", "5",
                       "--record", record, "--udp", "127.0.0.1:9")
    assert code == 0 and "Traceback" not in err  # Ctrl-C is how a console session ends (README, "Exit status")
    assert "robot stopped" in err  # the robot was stopped all the same
    data = record.read_bytes()
    assert data.endswith(b"\x89MCAP0\r\n") and len(data) > 16  # the footer's closing magic: a whole file


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_sigterm_ends_a_console_with_143_where_ctrl_c_leaves_with_0(tmp_path, sig):
    """``proleg console`` took SIGTERM (a CI job's timeout, ``kill``) and SIGHUP for a ``q`` and
    exited 0: a script could not tell it was killed. Ctrl-C stays a way to leave (0); SIGTERM
    exits 143 as every other command does, after the robot is stopped and the recording closed."""
    record = tmp_path / "session.mcap"
    env = {**os.environ, "PYTHONPATH": str(ROOT / "host" / "src")}
    proc = subprocess.Popen([sys.executable, "-c", _AS_FROM_A_TERMINAL, "console", "--sim", "paper-r1", "--plain",
                             "--record", str(record)], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                            text=True, env=env)
    try:
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline and (not record.exists() or record.stat().st_size < 2_000):
            time.sleep(0.2)
        proc.send_signal(sig)
        _, err = proc.communicate(timeout=30)
    finally:
        proc.kill()
    assert "Traceback" not in err and "robot stopped on sim paper-r1" in err, err
    if sig == signal.SIGINT:
        assert proc.returncode == 0, err
    else:
        assert proc.returncode == 143, err
        assert err.splitlines()[-1] == f"proleg: ended by SIGTERM; recording kept in {record} (complete up to there)"
    assert len(read_recording(record).time_s) > 0


#: as ``_AS_FROM_A_TERMINAL`` but as a script's background job (``proleg run … &``): SIGINT ignored
_AS_A_BACKGROUND_JOB = _AS_FROM_A_TERMINAL.replace(
    "[signal.signal(s, signal.SIG_DFL) for s in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)]; ",
    "[signal.signal(s, signal.SIG_DFL) for s in (signal.SIGTERM, signal.SIGHUP)]; "
    "signal.signal(signal.SIGINT, signal.SIG_IGN); ")


def test_sigterm_ends_a_background_run_as_ctrl_c_does(tmp_path):
    """``proleg run … &`` in a script ignores Ctrl-C (the shell's doing), and SIGTERM then killed it
    outright: no STOP sent, no line, an MCAP without its footer. It now ends it as in the
    foreground: 143, the robot stopped, the recording whole."""
    assert "SIG_IGN" in _AS_A_BACKGROUND_JOB
    record = tmp_path / "run.mcap"
    env = {**os.environ, "PYTHONPATH": str(ROOT / "host" / "src")}
    proc = subprocess.Popen([sys.executable, "-c", _AS_A_BACKGROUND_JOB, "run", str(R1), "--sim", "--speed", "1",
                             "--duration", "600", "--record", str(record), "-q"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    try:
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline and (not record.exists() or record.stat().st_size < 20_000):
            time.sleep(0.2)
        proc.send_signal(signal.SIGTERM)
        _, err = proc.communicate(timeout=30)
    finally:
        proc.kill()
    assert proc.returncode == 143, (proc.returncode, err)
    lines = [x for x in err.splitlines() if "warning" not in x]
    assert len(lines) == 1 and "; STOP acknowledged: the gait is stopped and the coils are off; " in lines[0], err
    assert lines[0].endswith(f"recording kept in {record} (complete up to there)")
    assert record.read_bytes().endswith(b"\x89MCAP0\r\n")  # the footer: a whole file
    assert len(read_recording(record).time_s) > 0


def test_a_learn_ended_by_sigterm_says_sigterm_not_ctrl_c(tmp_path):
    """SIGTERM is delivered as a Ctrl-C: learn's last line said "paused by Ctrl-C" after a kill."""
    log = tmp_path / "trials.jsonl"
    env = {**os.environ, "PYTHONPATH": str(ROOT / "host" / "src")}
    proc = subprocess.Popen([sys.executable, "-c", _AS_FROM_A_TERMINAL, "learn", "caterpillar-4", "--sim", "--plant", "table", "--log",
                             str(log), "--repeats", "50"], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                            text=True, env=env)
    try:
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline and (not log.exists() or len(log.read_text().splitlines()) < 4):
            time.sleep(0.2)
        proc.send_signal(signal.SIGTERM)
        _, err = proc.communicate(timeout=30)
    finally:
        proc.kill()
    assert proc.returncode == 143, err
    last = err.replace("\r", "\n").strip().splitlines()[-1]
    assert last.startswith("proleg: learn: paused by SIGTERM (robot stopped): "), last


def test_a_run_whose_terminal_is_closed_exits_129_not_1(tmp_path):
    """SIGHUP from a closed terminal stopped the run (STOP acknowledged) but its last line then
    failed on the dead tty (EIO) and the command ended 1 with a traceback nobody saw."""
    import pty
    import select

    record = tmp_path / "run.csv"
    pid, fd = pty.fork()
    if pid == 0:  # pragma: no cover (the child)
        os.environ["PYTHONPATH"] = str(ROOT / "host" / "src")
        os.execv(sys.executable, [sys.executable, "-c", _AS_FROM_A_TERMINAL, "run", str(R1), "--sim", "--speed", "1",
                                  "--duration", "600", "--record", str(record)])
    try:
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline and (not record.exists() or record.stat().st_size < 5_000):
            if select.select([fd], [], [], 0.1)[0]:
                try:
                    os.read(fd, 65536)
                except OSError:
                    break
        os.close(fd)  # the terminal is closed
        status = exit_status_within(pid)
        if status is not None:
            pid = None  # reaped
    finally:
        if pid is not None:
            os.kill(pid, signal.SIGKILL)
            os.waitpid(pid, 0)
    assert status == 129
    assert len(read_recording(record).time_s) > 0
