"""Scripting a robot from the command line on the simulated board (``--sim``): proleg run,
load-gait, set-param, robots; exit codes, --version, -v/-q, JSON lines, live UDP output,
and no traceback on a closed pipe, a full disk or an ASCII terminal."""

from __future__ import annotations

import json
import os
import re
import socket
import subprocess
import sys
from pathlib import Path

import pytest
from build_checks import cli as run

from proleg import __version__
from proleg.cli import main

PROLEG = str(Path(sys.executable).with_name("proleg"))
ROBOTS = Path(__file__).resolve().parents[1] / "robots"


def shell(cmd: str, cwd: Path, **env: str) -> subprocess.CompletedProcess:
    return subprocess.run(["bash", "-c", cmd], cwd=cwd, capture_output=True, text=True, timeout=120,
                          env={**os.environ, **env})


# --------------------------------------------------------------------------- hygiene
def test_version_and_exit_codes_in_help(capsys):
    with pytest.raises(SystemExit) as e:
        main(["--version"])
    assert e.value.code == 0 and capsys.readouterr().out.strip() == f"proleg {__version__}"
    with pytest.raises(SystemExit):
        main(["--help"])
    out = capsys.readouterr().out
    assert "exit status:" in out
    assert re.search(r"0\s+ok", out) and re.search(r"1\s+failed", out) and re.search(r"2\s+usage", out)
    # and the signals' statuses, as the README gives them (help listed 0, 1 and 2 only)
    assert re.search(r"130\s+interrupted: Ctrl-C", out) and re.search(r"143\s+ended by SIGTERM", out)
    assert re.search(r"129\s+ended by SIGHUP", out)


@pytest.mark.parametrize("argv", [
    ("learn", "paper-r3", "--port", "sim://paper-r1", "--source", "tracker", "--repeats", "1"),
    ("load-gait", "paper-r3", "--port", "sim://paper-r1", "00,10,11,01"),
    ("calibrate", "paper-r3", "--port", "sim://paper-r1"),
])
def test_learn_load_gait_and_calibrate_refuse_a_board_of_another_robot_as_run_does(capsys, tmp_path, argv):
    """They checked at most the limb count: learn recorded paper-r1's body into a paper-r3 log,
    load-gait advised the way paper-r3's matrix walks, calibrate stored the level."""
    extra = ("--log", str(tmp_path / "l.jsonl")) if argv[0] == "learn" else ()
    code, out, err = run(capsys, *argv, *extra)
    assert code == 1 and "Traceback" not in err, err
    assert "runs robot 'paper-r1', not 'paper-r3'" in err and "give the robot file it was built from" in err
    assert "loaded" not in out and "calibrat" not in out
    assert not (tmp_path / "l.jsonl").exists()  # learn opens its log only once the board answered as it should


def test_a_board_built_from_another_robot_exits_1_as_the_documented_rule_says(capsys):
    """The sweep's 3.7: run on a board of another robot exits 1, and the README listed "a bad
    robot file" under 2. The file loads; what does not match is the board, found over the
    link, like the console's identity check and a library's gait hash (both 1): the README
    and --help now say so."""
    code, out, err = run(capsys, "run", "paper-r3", "--port", "sim://paper-r1", "--duration", "1")
    assert code == 1 and out == "" and "Traceback" not in err
    assert err.startswith("proleg: error: ") and err.count("\n") == 1
    assert "runs robot 'paper-r1', not 'paper-r3'" in err and "give the robot file it was built from" in err
    readme = " ".join((Path(__file__).resolve().parents[1] / "README.md").read_text(encoding="utf-8").split())
    assert ("the board does not run the firmware of the robot file given); **2** usage (a bad argument, "
            "an output directory that does not exist, a robot or board file or a recording (`proleg plot`) that does "
            "not load, a bad gait)") in readme
    with pytest.raises(SystemExit):
        main(["--help"])
    assert "the board does not run the firmware of the robot file given" in " ".join(capsys.readouterr().out.split())


def test_a_usage_error_exits_2(capsys):
    with pytest.raises(SystemExit) as e:
        main(["run", "paper-r1"])  # no --port/--can/--sim
    assert e.value.code == 2


def test_robots_lists_the_bundled_examples_and_robot_accepts_their_names(capsys, tmp_path, monkeypatch):
    code, out, _ = run(capsys, "robots")
    assert code == 0
    names = [line.split()[0] for line in out.splitlines()]
    assert {"paper-r1", "paper-r2", "paper-r3"} <= set(names)
    monkeypatch.chdir(tmp_path)  # no robots/ here: the name means the bundled file
    code, out, _ = run(capsys, "gait", "paper-r2", "--json")
    assert code == 0 and json.loads(out)["robot"] == "paper-r2"


def test_build_accepts_a_bundled_robot_name(capsys, tmp_path, monkeypatch):
    import shutil

    if shutil.which("avr-gcc") is None:
        pytest.skip("no avr-gcc")
    monkeypatch.chdir(tmp_path)
    code, out, err = run(capsys, "build", "paper-r1", "--board", "arduino-nano", "-o", str(tmp_path / "fw"))
    assert code == 0, err
    assert "built paper-r1 for arduino-nano" in out


def test_progress_lines_come_once_a_period_of_the_run_and_end_with_it(capsys):
    """--progress 0.1 over a 1 s run: the start line and one line a period, none from the
    STOP's tail after it (a "0.2 s" line followed a 0.1 s run)."""
    code, _, err = run(capsys, "run", "paper-r1", "--sim", "--duration", "1", "--progress", "0.1")
    times = [float(line.split("proleg: ")[1].split(" s:")[0]) for line in err.splitlines() if " s: " in line]
    assert code == 0 and "started gait 0" in err
    assert len(times) == 10 and times == sorted(times) and max(times) <= 1.0 + 1e-6, err


def test_a_stalled_loop_says_one_progress_line_and_the_stop_tail_none():
    """run_gait_on's own progress (the library has no 0.1 s floor): a host loop held up for a
    second (a slow disk, a loaded machine) printed one line per period it missed, one after
    the other with the same time; and the 0.1 s after STOP printed lines of their own, past
    the run's duration."""
    from proleg.link import RobotClient, open_link
    from proleg.link.listeners import Listener
    from proleg.report import run_gait_on

    def progress_times(period: float, stall_s: float) -> list[float]:
        link = open_link("sim://paper-r1")
        real, stalled = link.clock, []
        link.clock = lambda: real() + (stall_s if stalled else 0.0)

        class Stall(Listener):
            def on_message(self, rx) -> None:
                if stall_s and not stalled and real() >= 0.5:
                    stalled.append(real())

        lines: list[str] = []
        with RobotClient(link) as client:
            client.connect()
            run_gait_on(client, 0, "+x", 1.0 + stall_s, listeners=[Stall()], progress=lines.append,
                        progress_every_s=period)
        return [float(s.split(" s:")[0]) for s in lines if " s: " in s]

    times = progress_times(0.1, 1.0)
    # one line at the stall, the next on the period's grid (0.06 s on here: both read 1.5 s); it
    # was a line per period missed, one each receive pass (ten lines reading 1.5 s)
    assert times == sorted(times) and max(times.count(t) for t in times) <= 2, times
    times = progress_times(0.02, 0.0)
    assert len(times) <= round(1.0 / 0.02), times  # none from the STOP's tail


def test_verbosity_flags_control_progress_on_stderr(capsys):
    code, out, err = run(capsys, "run", "paper-r1", "--sim", "--duration", "2")
    assert code == 0, err
    assert "started gait 0 in +x" in err and re.search(r"1\.0 s: \d+ frames", err)
    assert out.startswith("paper-r1 on sim paper-r1: gait 0 in +x for 2 s")
    code, out, err = run(capsys, "run", "paper-r1", "--sim", "--duration", "2", "-q")
    assert code == 0 and err == ""
    code, _, err = run(capsys, "-v", "run", "paper-r1", "--sim", "--duration", "1")
    assert code == 0 and "connected to paper-r1" in err


def test_broken_pipe_ends_quietly(tmp_path):
    p = shell(f"'{PROLEG}' run paper-r1 --sim --duration 30 --format jsonl -q | head -1", tmp_path)
    assert json.loads(p.stdout.splitlines()[0])["msg"] in ("INFO", "EVENT", "TELEMETRY", "ACK")
    assert p.stderr == ""


def test_learn_out_writes_its_file_also_when_the_reader_goes_away(tmp_path):
    """The table was printed first: with | head -1 the command ended quietly (exit 0) before
    it wrote --out."""
    p = shell(f"'{PROLEG}' learn paper-r1 --sim --repeats 1 --log r1.jsonl -q", tmp_path)
    assert p.returncode == 0, p.stderr
    p = shell(f"'{PROLEG}' learn paper-r1 --log r1.jsonl --out learned.toml | head -1", tmp_path)
    assert p.stdout.startswith("paper-r1: 12 trials") and "Traceback" not in p.stderr
    assert "[transitions]" in (tmp_path / "learned.toml").read_text()


def test_a_full_disk_is_one_line_and_exit_1(tmp_path):
    if not Path("/dev/full").exists():
        pytest.skip("no /dev/full")
    p = shell(f"'{PROLEG}' gait paper-r1 --json > /dev/full", tmp_path)
    assert p.returncode == 1
    assert p.stderr.count("\n") == 1 and "No space left on device" in p.stderr
    (tmp_path / "run.jsonl").symlink_to("/dev/full")
    p = shell(f"'{PROLEG}' run paper-r1 --sim --duration 1 -q --record run.jsonl", tmp_path)
    assert p.returncode == 1
    assert p.stderr.count("\n") == 1 and "No space left on device" in p.stderr and "Traceback" not in p.stderr


@pytest.mark.parametrize(("error", "line"), [
    (IsADirectoryError(21, "Is a directory", "some/dir"), "cannot access some/dir: Is a directory"),
    (PermissionError(13, "Permission denied", "x.toml"), "cannot access x.toml: Permission denied"),
    (OSError(28, "No space left on device", "out/gen"), "cannot write out/gen: No space left on device"),
])
def test_an_os_error_no_command_caught_names_the_file_and_claims_no_write_it_cannot_know(
        capsys, monkeypatch, error, line):
    import proleg.firmware.boards
    # imported before the patch: a module imported first under it (build pulls in the
    # simulator's closed_loop, which binds load_board at import) would keep `fail` for good
    import proleg.firmware.build  # noqa: F401
    import proleg.sim.closed_loop  # noqa: F401

    def fail(*_):
        raise error

    monkeypatch.setattr(proleg.firmware.boards, "load_board", fail)
    code, _, err = run(capsys, "build", "paper-r1", "--board", "host-sim")
    assert code == 1 and err == f"proleg: error: {line}\n"


@pytest.mark.parametrize("env", [{"PYTHONIOENCODING": "ascii"}, {"LANG": "C", "LC_ALL": "C", "PYTHONUTF8": "0"}])
def test_a_terminal_without_utf8_gets_replacement_characters(tmp_path, env):
    p = shell(f"'{PROLEG}' gait paper-r1", tmp_path, **env)
    assert p.returncode == 0, p.stderr
    assert p.stderr == ""
    assert "00 ? 10" in p.stdout or "00 → 10" in p.stdout  # LANG=C may still be UTF-8 on Python ≥ 3.7
    if env.get("PYTHONIOENCODING") == "ascii":
        assert "?" in p.stdout and "→" not in p.stdout


# --------------------------------------------------------------------------- run
def test_run_a_gait_that_does_not_exist_is_a_usage_error(capsys):
    code, out, err = run(capsys, "run", "paper-r1", "--sim", "--gait", "7", "--duration", "1")
    assert code == 2 and out == ""
    assert err.count("\n") == 1 and "--gait 7: paper-r1 has gait 0 only in +x" in err  # not INFO's 2 (both ways)
    code, _, err = run(capsys, "run", "paper-r1", "--sim", "--gait", "1", "--duration", "1")
    assert code == 2 and "--gait 1: paper-r1 has gait 0 only in +x" in err
    code, _, err = run(capsys, "run", "paper-r1-one-actuator", "--sim", "--direction", "-x", "--duration", "1")
    assert code == 2 and "no gait in -x" in err
    code, _, err = run(capsys, "sim", "paper-r1", "--gait", "3", "--duration", "1")
    assert code == 2 and "--gait 3" in err


def test_run_jsonl_prints_every_message_then_a_result_line(capsys):
    code, out, _ = run(capsys, "run", "paper-r1", "--sim", "--duration", "3", "--format", "jsonl", "-q")
    assert code == 0
    lines = [json.loads(x) for x in out.splitlines()]
    tel = [x for x in lines if x["msg"] == "TELEMETRY"]
    assert len(tel) >= 140
    assert isinstance(tel[0]["seq"], int) and isinstance(tel[0]["psi_left_deg"], float)
    assert "duty_sma_right_pct" in tel[0] and "displacement_mm" in tel[0]
    result = lines[-1]
    assert result["msg"] == "RESULT" and result["ok"] is True and result["faults"] == []
    assert result["telemetry_frames"] == len(tel)


def test_states_reached_is_the_same_list_of_labels_in_run_and_sim(capsys):
    """The sweep's 6: ``states_reached`` was a list of labels in sim --json and a count in run's
    RESULT line. Both are now the labels, in order; on the same simulated board the same ones."""
    code, out, _ = run(capsys, "run", "paper-r1", "--sim", "--duration", "8", "--format", "jsonl", "-q")
    result = json.loads(out.splitlines()[-1])
    code_sim, out_sim, _ = run(capsys, "sim", "paper-r1", "--duration", "8", "--plant", "table", "--json")
    sim = json.loads(out_sim)
    assert code == code_sim == 0 and result["msg"] == "RESULT"
    assert isinstance(result["states_reached"], list) and isinstance(sim["states_reached"], list)
    assert set(result["states_reached"]) <= {"00", "01", "10", "11"} and len(result["states_reached"]) >= 4
    assert result["states_reached"][:4] == sim["states_reached"][:4]  # gait 0 of +x, from rest
    events = [json.loads(x) for x in out.splitlines()[:-1]]
    assert len(result["states_reached"]) == sum(e["msg"] == "EVENT" and e["kind"] == "STATE_REACHED"
                                                 for e in events)


def test_run_exits_1_when_the_robot_refuses_to_start(capsys):
    code, out, err = run(capsys, "run", "paper-r1", "--sim", "--gait", "user", "--duration", "1", "-q")
    assert code == 1
    assert "START failed" in err and "robot refused START" in err
    assert "did not start" in out and "for 1 s" not in out  # it never ran
    # a --sim board is this command's alone: the NACK's "load one first" cannot be followed, so
    # the way that can is named (a board that stays, on a pty)
    assert "warning: --gait user --sim: the simulated board lives for this command only" in err
    assert "give the sequence to run itself: --states SEQ" in err
    code, out, _ = run(capsys, "run", "paper-r1", "--sim", "--gait", "user", "--duration", "1", "--format", "jsonl")
    result = json.loads(out.strip().splitlines()[-1])
    assert code == 1 and result["ok"] is False and result["duration_s"] == 0.0


def test_run_states_loads_and_runs_a_sequence_in_its_own_session(capsys):
    """run --states SEQ: the sequence is loaded in run's own session (a Nano resets when its port
    opens, and a --sim board is new to each command, so load-gait then run --gait user cannot
    work there) and the board runs it: R1's paper sequence C_T1, cycle after cycle."""
    code, out, err = run(capsys, "run", "paper-r1", "--sim", "--states", "00,10,01", "--direction", "+x",
                         "--duration", "20", "--format", "jsonl")
    result = json.loads(out.strip().splitlines()[-1])
    assert code == 0 and result["ok"], err
    reached = result["states_reached"]
    cycle = ["00", "10", "01"]
    k = reached.index("00")
    assert reached[k:k + 7] == (cycle * 3)[:7]
    assert result["cycles"] >= 2 and result["gait"] == 255 and result["direction"] == "+x"
    for argv, says in ((("--states", "00,10,01", "--gait", "0"), "--states: the gait to run; leave out --gait"),
                       (("--states", "00,10,10"), "--states: 10 follows itself"),
                       (("--states", "00,1x"), "--states:")):
        code, out, err = run(capsys, "run", "paper-r1", "--sim", "--duration", "1", *argv)
        assert code == 2 and says in err and out == "", (argv, err)
    # a way stated against the matrix's is warned of (the climb guard checks the way stated), as
    # load-gait says the matrix's way; C_T2 walks -x
    code, _, err = run(capsys, "run", "paper-r1", "--sim", "--states", "00,01,10", "--direction", "+x",
                       "--duration", "1")
    assert code == 0 and "matrix says this sequence walks -x, and --direction states +x" in err
    code, _, err = run(capsys, "run", "paper-r1", "--sim", "--states", "00,01,10", "--direction", "-x",
                       "--duration", "1")
    assert code == 0 and "warning" not in err
    # a step the robot file forbids is refused before anything is sent, as load-gait refuses it
    code, out, err = run(capsys, "run", "paper-r1-one-actuator", "--sim", "--duration", "1", "--states", "00,01,11")
    assert code == 2 and "--states: 00 → 01 is forbidden" in err, err


def test_run_states_with_a_heading_or_rotation_is_refused_before_a_gait_is_computed(capsys):
    """--states with --heading computed the heading's gait first and said it was "loaded with
    LOAD_GAIT" (nothing was: no link was open) before refusing the pair; with --rotate the
    error was the rotation's (no dtheta_deg), not the pair's."""
    for argv in (("--heading", "0"), ("--rotate", "cw"), ("--heading", "90", "--exact-heading")):
        code, out, err = run(capsys, "run", "paper-r1", "--sim", "--duration", "1", "--states", "00,10,01", *argv)
        assert code == 2 and out == "", (argv, err)
        assert err.strip().splitlines() == ["proleg: error: --states: the gait to run; leave out --gait, --heading "
                                            "and --rotate"], (argv, err)


def test_run_on_a_faulting_robot_reports_the_fault(tmp_path):
    from proleg.link import RobotClient, open_link
    from proleg.report import run_gait_on

    link = open_link("sim://paper-r1")
    link.board.inject("dead-actuator:sma-left")
    with RobotClient(link) as client:
        client.connect()
        result = run_gait_on(client, 0, "+x", 12.0)
    assert not result.ok
    assert "STATE_TIMEOUT" in [f.code for f in result.faults]


def test_run_records_mcap_that_the_mcap_reader_reads(capsys, tmp_path):
    from mcap.reader import make_reader

    path = tmp_path / "run.mcap"
    code, _, err = run(capsys, "run", "paper-r1", "--sim", "--duration", "2", "-q", "--record", str(path))
    assert code == 0, err
    with path.open("rb") as f:
        topics = [ch.topic for _, ch, _ in make_reader(f).iter_messages()]
    assert topics.count("/proleg/telemetry") >= 95 and "/proleg/events" in topics


# --------------------------------------------------------------------------- live UDP
def _udp_socket() -> socket.socket:
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 1 << 21)
    sock.bind(("127.0.0.1", 0))
    sock.settimeout(0.5)
    return sock


def _datagrams(sock: socket.socket) -> list[bytes]:
    out = []
    while True:
        try:
            out.append(sock.recv(65536))
        except TimeoutError:
            return out


TELEPLOT_LINE = re.compile(r"^>(?P<name>[A-Za-z0-9_]+):(?P<ts>\d+):(?P<value>-?\d+(\.\d+)?([eE][-+]?\d+)?)$")


def test_teleplot_lines_over_udp(capsys):
    with _udp_socket() as sock:
        port = sock.getsockname()[1]
        code, _, err = run(capsys, "run", "paper-r1", "--sim", "--duration", "2", "-q",
                           "--udp", f"127.0.0.1:{port}", "--udp-format", "teleplot")
        assert code == 0, err
        grams = _datagrams(sock)
    assert len(grams) >= 95
    series: dict[str, list[tuple[int, float]]] = {}
    for g in grams:
        for line in g.decode("ascii").split("\n"):
            m = TELEPLOT_LINE.match(line)  # Teleplot: >name:timestamp_ms:value
            assert m, line
            series.setdefault(m["name"], []).append((int(m["ts"]), float(m["value"])))
    assert {"psi_left_deg", "psi_right_deg", "duty_sma_left_pct", "seq", "measured"} <= set(series)
    ts = [t for t, _ in series["seq"]]
    assert ts == sorted(ts) and ts[-1] - ts[0] >= 1900
    assert [v for _, v in series["seq"]][:3] == sorted([v for _, v in series["seq"]][:3])


def test_a_live_plot_gets_no_placeholder_state_while_the_board_does_not_know_it(capsys):
    """At boot the measured state is 65535 (STATE_UNKNOWN): Teleplot drew a spike to it."""
    with _udp_socket() as sock:
        port = sock.getsockname()[1]
        code, _, err = run(capsys, "sim", "paper-r1", "--duration", "2",
                           "--udp", f"127.0.0.1:{port}", "--udp-format", "teleplot")
        assert code == 0, err
        grams = _datagrams(sock)
    measured = [float(ln.split(":")[2]) for g in grams for ln in g.decode("ascii").split("\n")
                if ln.startswith(">measured:")]
    seq = [ln for g in grams for ln in g.decode("ascii").split("\n") if ln.startswith(">seq:")]
    assert measured and max(measured) <= 3 and len(measured) < len(seq)  # the boot frames carry no state


def test_plotjuggler_json_over_udp(capsys):
    with _udp_socket() as sock:
        port = sock.getsockname()[1]
        code, _, err = run(capsys, "run", "paper-r1", "--sim", "--duration", "2", "-q",
                           "--udp", f"127.0.0.1:{port}")
        assert code == 0, err
        grams = _datagrams(sock)
    docs = [json.loads(g) for g in grams]  # PlotJuggler's JSON parser: one object per datagram
    assert len(docs) >= 95
    assert all(isinstance(d["timestamp"], float) for d in docs)
    assert [d["timestamp"] for d in docs] == sorted(d["timestamp"] for d in docs)
    assert isinstance(docs[0]["psi_left_deg"], float) and isinstance(docs[0]["seq"], int)


def test_a_bad_udp_endpoint_is_one_line(capsys):
    code, _, err = run(capsys, "run", "paper-r1", "--sim", "--duration", "1", "--udp", "nowhere")
    assert code == 2 and "expected HOST:PORT" in err and err.count("\n") == 1


def test_a_udp_host_that_does_not_resolve_is_a_usage_error(capsys, monkeypatch):
    # --udp 999.1.1.1:5 exited 1 as if a link had failed
    def no_such_host(*_a, **_k):
        raise socket.gaierror(socket.EAI_NONAME, "Name or service not known")

    monkeypatch.setattr(socket, "getaddrinfo", no_such_host)
    code, _, err = run(capsys, "run", "paper-r1", "--sim", "--duration", "1", "--udp", "999.1.1.1:5")
    assert code == 2 and err.count("\n") == 1
    assert "--udp 999.1.1.1:5: no host '999.1.1.1' (Name or service not known); expected HOST:PORT" in err


@pytest.mark.parametrize("argv, words", [
    (("run", "paper-r1", "--sim", "--duration", "1", "--udp-format", "teleplot"),
     "--udp-format: only with --udp HOST:PORT"),
    (("sim", "paper-r1", "--duration", "1", "--udp-format", "teleplot"), "--udp-format: only with --udp HOST:PORT"),
    (("console", "--sim", "paper-r1", "--plain", "--duration", "1", "--udp-format", "teleplot"),
     "--udp-format: only with --udp HOST:PORT"),
    (("calibrate", "paper-r1", "--sim", "--baudrate", "9600"), "--baudrate: only with --port"),
    (("calibrate", "paper-r1", "--sim", "--node", "3"), "--node: only with --can"),
    (("run", "paper-r1", "--sim", "--bitrate", "500000"), "--bitrate: only with --can"),
    (("run", "paper-r1", "--port", "loop://", "--interface", "virtual"), "--interface: only with --can"),
    (("console", "--sim", "paper-r1", "--plain", "--baudrate", "9600"), "--baudrate: only with --port"),
    (("learn", "paper-r1", "--sim", "--plant", "table", "--log", "LOG", "--node", "1"), "--node: only with --can"),
    (("run", "paper-r1", "--can", "x", "--interface", "nosuch"), "unknown CAN interface 'nosuch'; python-can knows:"),
    (("run", "paper-r1", "--port", "sim://paper-r1", "--speed", "2"), "--speed: only with --sim"),
])
def test_an_option_the_command_would_ignore_or_cannot_take_is_exit_2(capsys, tmp_path, argv, words):
    # each ran with exit 0 (the option ignored) or exited 1 as if a link had failed
    argv = tuple(str(tmp_path / "t.jsonl") if a == "LOG" else a for a in argv)
    code, _, err = run(capsys, *argv)
    assert code == 2 and words in err and err.count("\n") == 1, err
    assert not (tmp_path / "t.jsonl").exists()


@pytest.mark.parametrize("argv, words", [
    # each was taken and ignored (exit 0): the score printed was not the one asked for
    (("--evaluate", "00,10,11,01,00", "--heading", "90"), "--heading: not with --evaluate"),
    (("--evaluate", "00,10,11,01,00", "--max-transitions", "2"), "--max-transitions: not with --evaluate"),
    (("--evaluate", "00,10,11,01,00", "--direction", "-x"), "--direction: not with --evaluate"),
    (("--direction", "-x", "--heading", "90"), "--direction -x: not with a planar option"),
])
def test_gait_options_that_would_be_ignored_are_refused(capsys, argv, words):
    code, out, err = run(capsys, "gait", "paper-r1", *argv)
    assert code == 2 and out == "" and words in err, err


def test_direction_still_picks_the_way_of_a_weighted_answer(capsys):
    code, out, err = run(capsys, "gait", "paper-r1", "--direction", "-x", "--transition-cost", "0.1")
    assert code == 0 and "-x" in out and "+x" not in out, (out, err)


def test_a_negative_transition_cost_is_refused_like_every_other_weight(capsys):
    with pytest.raises(SystemExit) as e:
        main(["gait", "paper-r1", "--transition-cost", "-1"])
    assert e.value.code == 2
    assert "argument --transition-cost: expected a number >= 0, got '-1'" in capsys.readouterr().err


# --------------------------------------------------------------------------- load-gait, set-param
def test_load_gait_on_the_simulated_board(capsys):
    code, out, err = run(capsys, "load-gait", "paper-r1", "--sim", "00,10,11,01,00")
    assert code == 0, err
    assert "loaded 00 → 10 → 11 → 01 → 00 as the user gait" in out
    assert "matrix says it walks +x: run it with --gait user --direction +x" in out  # J = +3
    code, out, err = run(capsys, "load-gait", "paper-r1", "--sim", "00,01,11,10")
    assert code == 0 and "matrix says it walks -x" in out, err
    code, _, err = run(capsys, "load-gait", "paper-r1-one-actuator", "--sim", "00,01,11")
    assert code == 2 and "STATES: 00 → 01 is forbidden" in err and err.count("\n") == 1  # refused before sending
    code, _, err = run(capsys, "load-gait", "paper-r1", "--sim", "00,12")
    assert code == 2 and "STATES" in err
    code, _, err = run(capsys, "load-gait", "paper-r1", "--sim", "00,,10")  # not read as 00,10
    assert code == 2 and "STATES: entry 2 of '00,,10' is empty" in err
    code, _, err = run(capsys, "load-gait", "paper-r1", "--sim", "11,11,10")  # the board NACKed it: exit 1
    assert code == 2 and "STATES: 11 follows itself" in err and err.count("\n") == 1


def test_load_gait_says_what_the_gait_check_finds_as_proleg_build_does(capsys, tmp_path):
    """load-gait sent any sequence the matrix allows without a word: R1 whose durations (0.9 s a
    step) outlast its state_timeout_ms (500) loaded 00 10 11 01 silently, and the board then
    stopped it at once (STATE_TIMEOUT), where proleg build says 'expect a fault' of the same
    gait. It still loads (the robot file's body is a model); the warning names the step."""
    text = (ROBOTS / "paper-r1.toml").read_text()
    path = tmp_path / "slow.toml"
    path.write_text(text.replace("state_timeout_ms = 8000", "state_timeout_ms = 500")
                    .replace("[transitions]\n", "[transitions]\ndefault_duration_s = 0.9\n"))
    code, out, err = run(capsys, "load-gait", str(path), "--sim", "00,10,11,01")
    assert code == 0 and "loaded 00 → 10 → 11 → 01 → 00 as the user gait" in out, err
    assert "proleg: warning: STATES: expect a fault: gait 00 10 11 01 00: step 1 (00 -> 10) takes 0.9 s" in err, err
    assert "STATE_TIMEOUT" in err and err.count("STATES:") == 1, err
    code, out, err = run(capsys, "load-gait", "paper-r1", "--sim", "00,10,11,01")
    assert code == 0 and "warning" not in err, err
    # a loaded gait has no entry path from rest: a slow step into it from 00 is no step of it
    path.write_text(text.replace("  [ 0,  0,  0,  0],\n]\n", "  [ 0,  0,  0,  0],\n]\n"
                                 "durations_s = [[0, 1, 9, 1], [1, 0, 1, 1], [1, 1, 0, 1], [1, 1, 1, 0]]\n"))
    code, out, err = run(capsys, "load-gait", str(path), "--sim", "10,11,01")
    assert code == 0 and "STATE_TIMEOUT" not in err, err


def test_set_param_on_a_port_says_a_nano_forgets_it_at_the_next_open(capsys, monkeypatch):
    """`set-param max_on_ms 1000 --port ...` printed only `set max_on_ms[0] = 1000`; a Nano
    resets whenever its port opens, so the `proleg run` after it ran with the robot file's
    3000 ms, the narrowing a lab made for a fragile coil gone without a word."""
    from proleg.cli import robot_commands
    from proleg.link.client import RobotClient
    from proleg.link.sim_link import SimLink
    from proleg.sim.closed_loop import SimulatedRobot
    from proleg.robot import load_robot
    from proleg.paths import robots_dir

    sim = SimulatedRobot(load_robot(robots_dir() / "paper-r1.toml"))

    class _Open:
        def __init__(self, *a, **k):
            self.client = RobotClient(SimLink(sim, step_s=sim.plant_dt_s))

        def __enter__(self):
            self.client.connect()
            return self.client

        def __exit__(self, *exc):
            self.client.close()

    monkeypatch.setattr(robot_commands, "open_client", _Open)
    code, out, err = run(capsys, "set-param", "--port", "/dev/ttyUSB0", "max_on_ms", "1000")
    assert code == 0, err
    assert out.startswith("set max_on_ms[0] = 1000")
    assert "a Nano resets whenever its port is opened: on a Nano the next" in out and "robot file's value again" in out


def test_set_param_by_name_on_the_simulated_board(capsys):
    code, out, err = run(capsys, "set-param", "--sim", "paper-r1", "drive_duty", "3000")
    assert code == 0, err
    assert out.startswith("set drive_duty[0] = 3000")
    assert "a --sim board lives for this command only" in out  # as load-gait and calibrate say
    # a watchdog under the robot files' floor is refused; a short one is set, with what it means later
    code, _, err = run(capsys, "set-param", "--sim", "paper-r1", "link_watchdog_ms", "50")
    assert code == 2 and "link_watchdog_ms: expected at least 100 ms" in err
    code, out, err = run(capsys, "set-param", "--sim", "paper-r1", "link_watchdog_ms", "300")
    assert code == 0 and "the board keeps 300 ms until it resets" in out and "stops with LINK_WATCHDOG" in out
    code, _, err = run(capsys, "set-param", "--sim", "paper-r1", "DRIVE-DUTY", "9900")
    assert code == 1 and "SAFETY_LIMIT" in err
    with pytest.raises(SystemExit) as e:
        main(["set-param", "--sim", "paper-r1", "warp_factor", "9"])
    assert e.value.code == 2
    assert "known: drive_duty" in capsys.readouterr().err


@pytest.mark.parametrize("argv, message", [
    (("drive_duty", "5000", "--index", "5"),
     "--index 5: drive_duty has no index (only psi_star_cdeg and hysteresis_cdeg take one; docs/control.md)"),
    (("hold_ms", "100", "--index", "0"), "--index 0: hold_ms has no index"),
    (("hysteresis_cdeg", "100", "--index", "2"),
     "--index 2: hysteresis_cdeg's index is the limb; paper-r1 has 2 limbs, expected 0..1"),
    (("psi_star_cdeg", "1500", "--index", "2"), "paper-r1 has 2 thresholds, expected 0..1"),
])
def test_set_param_refuses_an_index_the_parameter_does_not_have_before_sending(capsys, monkeypatch, argv, message):
    """`set-param drive_duty 5000 --index 5` sent it and printed `set drive_duty[5] = 5000`:
    drive_duty has no index (docs/control.md)."""
    from proleg.link.client import RobotClient

    sent = []
    monkeypatch.setattr(RobotClient, "set_param", lambda self, *a: sent.append(a))
    code, out, err = run(capsys, "set-param", "--sim", "paper-r1", *argv)
    assert code == 2 and out == "" and err.startswith("proleg: error: ") and message in err, err
    assert err.count("\n") == 1 and sent == []  # one line, and nothing was sent
    code, out, _ = run(capsys, "set-param", "--sim", "caterpillar-4", "psi_star_cdeg", "1500", "--index", "5")
    assert code == 0 and out.startswith("set psi_star_cdeg[5] = 1500") and sent == [("psi_star_cdeg", 5, 1500)]


def test_sim_recording_marks_injections_and_faults_for_the_plot(capsys, tmp_path):
    pd = pytest.importorskip("pandas")
    from proleg.plot import _markers
    from proleg.record import read_recording

    path = tmp_path / "run.csv"
    code, _, _ = run(capsys, "sim", "paper-r1", "--duration", "12", "--inject", "dead-actuator:sma-right+2",
                     "--record", str(path))
    assert code == 1  # faulted
    events = pd.read_csv(tmp_path / "run.events.csv")
    injected = events[events["msg"] == "INJECT"]
    assert list(injected["text"]) == ["dead-actuator:sma-right"]
    assert injected["t_s"].iloc[0] == pytest.approx(2.2, abs=0.01)  # boot 0.2 s + 2 s
    assert "FAULT" in set(events["kind"].dropna())
    labels = [m[2] for m in _markers(read_recording(path))]
    assert labels[0] == "injected dead-actuator:sma-right" and any(x.startswith("FAULT ") for x in labels)
    code, out, _ = run(capsys, "plot", str(path), "-o", str(tmp_path / "run.png"))
    assert code == 0 and (tmp_path / "run.png").read_bytes()[:4] == b"\x89PNG"


def test_plot_of_a_sim_recording_leaves_the_unknown_boot_state_out_of_the_state_panel(capsys, tmp_path,
                                                                                      monkeypatch):
    """The first frames of every simulator recording have measured=65535 (state unknown): the
    state panel's axis ran 0..65535, the real states a flat line at the bottom."""
    import proleg.plot

    path = tmp_path / "run.csv"
    code, _, err = run(capsys, "sim", "paper-r1", "--duration", "2", "--record", str(path))
    assert code == 0, err
    assert "65535" in path.read_text().splitlines()[1]  # the recording keeps it (docs/data.md)
    drawn = []
    real_write = proleg.plot.write_figure
    monkeypatch.setattr(proleg.plot, "write_figure", lambda fig, out, dpi=None: (drawn.append(fig),
                                                                                  real_write(fig, out, dpi)))
    code, _, err = run(capsys, "plot", str(path), "-o", str(tmp_path / "run.png"))
    assert code == 0, err
    state_panel = drawn[0].axes[1]
    measured = next(line for line in state_panel.get_lines() if line.get_label() == "measured")
    ys = [y for y in measured.get_ydata() if y == y]  # NaN: not drawn
    assert ys and max(ys) <= 3 and len(ys) < len(measured.get_ydata())
    assert state_panel.get_ylim()[1] < 10


def test_console_plain_jsonl_prints_named_rows_for_scripts(capsys):
    code, out, err = run(capsys, "console", "--sim", "paper-r1", "--plain", "--format", "jsonl", "--duration", "1")
    assert code == 0, err
    rows = [json.loads(x) for x in out.splitlines()]
    tel = [r for r in rows if r["msg"] == "TELEMETRY"]
    assert len(tel) >= 20 and isinstance(tel[0]["seq"], int) and "psi_right_deg" in tel[0]
    assert any(r["msg"] == "EVENT" and r["kind"] == "BOOT" for r in rows)


@pytest.mark.parametrize("inject", ["imu-silent:left", "imu-stuck:right+0.5"])
def test_console_exits_1_when_the_robot_faulted_during_the_session(capsys, inject):
    """The README's exit status: 1 when the robot faulted. An IMU that is silent from the start
    latches its fault before the console listens (the telemetry's fault flag says so); one
    that sticks later sends a FAULT event."""
    code, _, err = run(capsys, "console", "--sim", "paper-r1", "--plain", "--duration", "2", "--inject", inject)
    assert code == 1 and "the robot faulted during the console session" in err, err


def test_console_refuses_an_injection_after_its_duration(capsys):
    """It used to run for the duration and never inject the fault, without a word."""
    code, _, err = run(capsys, "console", "--sim", "paper-r1", "--plain", "--duration", "2", "--inject",
                       "dead-actuator:sma-right+5")
    assert code == 2 and "5 s is after the run ends (--duration 2 s)" in err, err


def test_console_reads_a_limb_named_leg_plus_2_whole_whatever_its_duration(capsys, tmp_path):
    """The console parsed --inject once without the robot's names before opening the simulator:
    with --duration 1, `dead-actuator:leg+2` (a limb called leg+2) was refused as '2 s is after
    the run ends', where proleg sim injects it at once."""
    robot = tmp_path / "plus.toml"
    robot.write_text((ROBOTS / "paper-r1.toml").read_text().replace('name = "left"', 'name = "leg+2"'))
    code, _, err = run(capsys, "console", "--sim", str(robot), "--plain", "--duration", "1", "--inject",
                       "dead-actuator:leg+2")
    assert code == 0 and "injected dead-actuator:leg+2 at 0.0 s" in err, err


def test_load_gait_refuses_a_transition_the_robot_file_forbids_before_sending(capsys):
    """The board would answer FORBIDDEN_TRANSITION (detail 0), exit 1; the host knows which."""
    code, out, err = run(capsys, "load-gait", "--sim", "paper-r1-one-actuator", "00,10,11,01")
    assert code == 2 and out == "" and "STATES: 11 → 01 is forbidden" in err
    code, out, err = run(capsys, "load-gait", "--sim", "paper-r1-one-actuator", "00,10,11,10,00")
    assert code == 0, err


def test_load_gait_refuses_a_gait_longer_than_the_firmware_holds_in_steps_not_protocol_fields(capsys):
    """It said "LOAD_GAIT.states: 48 elements, at most 24" (the codec's words)."""
    long = ",".join(["00", "10", "11", "01"] * 12)
    code, out, err = run(capsys, "load-gait", "--sim", "paper-r1", long)
    assert code == 2 and out == ""
    assert "STATES: a gait of 48 steps; the firmware holds a user gait of at most 24" in err and "LOAD_GAIT" not in err
    code, _, err = run(capsys, "load-gait", "--sim", "paper-r1", ",".join(["00", "10", "11", "01"] * 6))
    assert code == 0, err  # 24 steps


@pytest.mark.parametrize("argv, text", [
    (("set-param", "--sim", "paper-r1", "drive_duty", "9000"), "SAFETY_LIMIT (above the build's duty ceiling, "
                                                               "the robot file's [safety] max_duty"),
    # the refusal names the limit it met (it said only "e.g. max_duty for a duty")
    (("set-param", "--sim", "paper-r1", "state_timeout_ms", "9000"), "longer than the build's [safety] "
                                                                     "state_timeout_ms (it may only be shortened)"),
    (("set-param", "--sim", "paper-r1", "min_cooldown_ms", "100"), "shorter than the build's [safety] "
                                                                   "min_cooldown_ms"),
    (("set-param", "--sim", "paper-r1", "drive_duty", "-1"), "OUT_OF_RANGE (outside the parameter's range"),
    (("run", "--sim", "paper-r1", "--gait", "user", "--duration", "1"), "NO_GAIT (no gait is loaded"),
])
def test_a_refusal_says_what_it_means_not_a_bare_detail(capsys, argv, text):
    code, _, err = run(capsys, *argv)
    assert code == 1 and text in err and "(detail" not in err


@pytest.mark.parametrize("argv, text", [
    (("run", "--sim", "planar-4", "--exact-heading", "--duration", "1"), "--exact-heading: only with --heading"),
    (("run", "--sim", "planar-4", "--library", "0,90", "--duration", "1"), "--library: only with --heading or --rotate"),
])
def test_run_refuses_a_steering_option_without_the_heading_it_serves(capsys, argv, text):
    code, _, err = run(capsys, *argv)
    assert code == 2 and text in err


def test_run_says_a_nearest_heading_once(capsys):
    """It was a warning before the run and again on stdout after it."""
    code, out, err = run(capsys, "run", "planar-4", "--sim", "--heading", "45", "--duration", "1")
    assert code == 0, err
    assert (out + err).count("the library's nearest heading") == 1


def test_a_robot_named_longer_than_info_carries_runs_and_is_watched(capsys, tmp_path):
    """INFO carries a robot name's first 15 characters; run and console compared the whole
    name with them and refused every robot with a longer one, even on --sim."""
    text = (ROBOTS / "paper-r1.toml").read_text(encoding="utf-8")
    path = tmp_path / "long.toml"
    path.write_text(text.replace('name = "paper-r1"', 'name = "paper-r1-with-a-long-name"', 1), encoding="utf-8")
    code, out, err = run(capsys, "run", str(path), "--sim", "--duration", "1", "-q")
    assert code == 0, err
    code, out, err = run(capsys, "console", "--sim", str(path), "--plain", "--duration", "0.3")
    assert code == 0 and "does not run firmware built from" not in err, err


def test_run_starts_once_the_board_knows_where_the_robot_is_so_a_gait_off_rest_takes_its_entry_path(capsys):
    """run STARTed a millisecond after the (simulated) board booted, before it had read an IMU:
    the firmware matched no step and took no entry path, so planar-4's +x gait 3, which starts
    at 0101, raised both limbs at once (first STATE_REACHED: step 1 at 0101). run now waits for
    a telemetry frame with a known state (at most 2 s), and the entry path from rest comes first."""
    code, out, _ = run(capsys, "run", "planar-4", "--sim", "--gait", "3", "--duration", "4", "--format", "jsonl", "-q")
    assert code == 0
    lines = [json.loads(x) for x in out.splitlines()]
    reached = [e for e in lines if e["msg"] == "EVENT" and e["kind"] == "STATE_REACHED"]
    assert reached and reached[0]["code"] == 255, reached[:2]  # the entry path's, not step 1's
    assert reached[0]["text"].startswith("entry path reached state 0") and reached[0]["text"].count("1") == 1
    start = next(e for e in lines if e["msg"] == "EVENT" and e["kind"] == "GAIT_STARTED")
    tel = [x for x in lines if x["msg"] == "TELEMETRY" and x["t_s"] <= start["t_s"]]
    assert tel and not tel[-1]["flags"] & 512  # Flag.STATE_UNKNOWN: the last frame before START knew the state


def test_run_names_a_long_named_robot_as_its_file_does(capsys, tmp_path):
    """INFO carries the first 15 characters of the robot's name (checked against the file when
    run connects); run's RESULT and summary line gave that truncation ("a-very-long-rob") as
    the robot, where proleg sim --json gives the file's name."""
    long_name = "a-robot-name-of-more-than-fifteen-characters"
    path = tmp_path / "long.toml"
    path.write_text((Path(__file__).resolve().parents[1] / "robots" / "paper-r1.toml").read_text()
                    .replace('name = "paper-r1"', f'name = "{long_name}"'))
    code, out, _ = run(capsys, "run", str(path), "--sim", "--duration", "1", "--format", "jsonl", "-q")
    assert code == 0 and json.loads(out.splitlines()[-1])["robot"] == long_name
    code, out, _ = run(capsys, "run", str(path), "--sim", "--duration", "1", "-q")
    assert code == 0 and out.startswith(f"{long_name} on sim ")


@pytest.mark.parametrize("command", [["sim", "--duration", "1"], ["check", "--rows", "1"],
                                     ["run", "--sim", "--duration", "1"]])
def test_a_robot_that_walks_only_minus_x_is_told_to_ask_for_minus_x(capsys, command):
    robot = str(Path(__file__).parent / "fixtures" / "ratchet-minus-x.toml")
    code, out, err = run(capsys, command[0], robot, *command[1:])  # the default direction, +x
    assert code == 2 and out == ""
    assert err.strip().splitlines()[-1] == ("proleg: error: --gait 0: ratchet-minus-x has no gait in +x "
                                            "(it has gait 0 only in -x: --direction -x)")
    code, _, err = run(capsys, command[0], robot, *command[1:], "--direction", "-x", "--gait", "5")
    assert code == 2 and err.strip().splitlines()[-1] == "proleg: error: --gait 5: ratchet-minus-x has gait 0 only in -x"
    # a gait number past -x's too: +x has none at all, which alone says nothing of -x
    code, _, err = run(capsys, command[0], robot, *command[1:], "--gait", "3")
    assert code == 2 and err.strip().splitlines()[-1] == ("proleg: error: --gait 3: ratchet-minus-x has no gait in +x "
                                                          "(it has gait 0 only in -x: --direction -x)")


@pytest.mark.parametrize("suffix", [".csv", ".mcap"])
def test_console_recording_and_jsonl_mark_an_injection_as_sim_does(capsys, tmp_path, suffix):
    """console --sim --inject said 'injected …' on stderr but its recording (and --format jsonl)
    had no INJECT row: the plot drew the FAULT without the orange marker of its cause."""
    from proleg.plot import _markers
    from proleg.record import read_recording

    path = tmp_path / f"run{suffix}"
    code, out, err = run(capsys, "console", "--sim", "inchworm-3", "--plain", "--format", "jsonl", "--duration", "3",
                         "--record", str(path), "--inject", "imu-stuck:middle+1")
    assert code == 1 and "injected imu-stuck:middle at 1.0 s" in err, err
    printed = [r for r in map(json.loads, out.splitlines()) if r["msg"] == "INJECT"]
    recorded = [e for e in read_recording(path).events if e["msg"] == "INJECT"]
    for rows in (printed, recorded):
        assert [r["text"] for r in rows] == ["imu-stuck:middle"]
        assert rows[0]["t_s"] == pytest.approx(1.0, abs=0.05)
    labels = [m[2] for m in _markers(read_recording(path))]
    assert labels[0] == "injected imu-stuck:middle" and any(x.startswith("FAULT ") for x in labels)


def test_console_leaving_a_running_gait_records_its_stop(capsys, tmp_path, monkeypatch):
    """Leaving sends STOP after the Notifier stopped: its ACK and the firmware's GAIT_STOPPED were
    never handed to the recorder, whose recording ended on a running gait."""
    import proleg.console

    real = proleg.console.run_plain

    def with_a_gait(client, **kw):
        client.wait_known_state(2.0)
        client.request("START", gait=0, direction=0)  # as the UI's key does
        real(client, **kw)

    monkeypatch.setattr(proleg.console, "run_plain", with_a_gait)
    path = tmp_path / "run.jsonl"
    code, out, err = run(capsys, "console", "--sim", "paper-r1", "--plain", "--format", "jsonl", "--duration", "1",
                         "--record", str(path))
    assert code == 0 and "robot stopped" in err, err
    from proleg.record import read_recording

    events = read_recording(path).events
    assert [e["text"] for e in events if e["kind"] == "GAIT_STOPPED"] == ["gait stopped: COMMAND after 0 cycles"], [(e["msg"], e["kind"], e["text"]) for e in events][-4:]
    assert events[-1]["kind"] == "GAIT_STOPPED" or events[-2]["kind"] == "GAIT_STOPPED"
