"""Recording (CSV / JSON Lines / MCAP, chosen by suffix), plots, DBC output; a bad recording read back → one RecordingError line (exit 2)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from proleg.errors import LinkError, RecordingError, UsageError
from proleg.link import RobotClient
from proleg.cli.link_commands import console_main, dbc_main, plot_main
from fake_board import FakeBoard
from proleg.plot import plot_recording
from proleg.record import Logger, RecordingMeta, read_recording
from proleg.robot import load_robot
from proleg.link.sim_link import SimLink


ROBOT = load_robot(Path(__file__).resolve().parents[1] / "robots" / "paper-r1.toml")
ROBOT_FILE = Path(__file__).resolve().parents[1] / "robots" / "paper-r1.toml"


def _recording(path: Path) -> tuple[FakeBoard, RobotClient, Logger]:
    """A fake board's gait 0 started, with a Logger recording it to ``path``."""
    board = FakeBoard()
    link = SimLink(board)
    client = RobotClient(link)
    info = client.connect()
    rec = Logger(path, RecordingMeta.for_robot(info=info, robot=ROBOT, link=link))
    client.start(0, "+x")
    return board, client, rec


def record(path: Path, frames: int = 120, inject_at: int | None = None) -> FakeBoard:
    board, client, rec = _recording(path)
    n = 0
    while n < frames:
        rx = client.recv_received(1.0)
        assert rx is not None
        rec.on_message(rx)
        n += rx.message.name == "TELEMETRY"
        if n == inject_at and rx.message.name == "TELEMETRY":
            rec.mark(rx.time, rx.message.time_ms / 1000, "dead-actuator:sma-left")
        if n == frames // 2 and rx.message.name == "TELEMETRY" and path.suffix != ".mcap":
            # flushed per line: everything so far is already in the file(s)
            files = [path, path.with_name(f"{path.stem}.events.csv")] if path.suffix == ".csv" else [path]
            lines = sum(p.read_text().count("\n") for p in files)
            assert lines == rec.records + (2 if path.suffix == ".csv" else 1)
    rec.stop()
    assert rec.error is None
    return board


def test_pandas_reads_the_csv_plainly_with_integer_columns_si_units_and_limb_names(tmp_path):
    pd = pytest.importorskip("pandas")
    path = tmp_path / "run.csv"
    board = record(path)
    df = pd.read_csv(path)
    assert len(df) == 120
    assert list(df.columns[:3]) == ["t_host_s", "t_s", "seq"]
    assert {"psi_left_deg", "psi_right_deg", "duty_sma_left_pct", "duty_sma_right_pct", "displacement_mm"} <= set(df)
    for c in ("seq", "measured", "target", "gait", "direction", "step", "flags"):
        assert df[c].dtype == "int64", c
    assert (df["seq"].diff().dropna() == 1).all()
    assert df["displacement_mm"].iloc[-1] == pytest.approx(board.displacement_mm, abs=10)
    events = pd.read_csv(tmp_path / "run.events.csv")
    assert "ACK" in set(events["msg"])
    assert events["code"].dtype == "int64"


def test_the_csv_metadata_sidecar_has_the_robot_firmware_ids_and_a_utc_start_time(tmp_path):
    from datetime import datetime, timezone

    before = datetime.now(timezone.utc)
    record(tmp_path / "run.csv", 10)
    meta = json.loads((tmp_path / "run.meta.json").read_text())
    start = datetime.fromisoformat(meta["start_utc"].replace("Z", "+00:00"))
    assert start.tzinfo is not None and start.utcoffset().total_seconds() == 0
    assert abs((start - before).total_seconds()) < 5
    assert meta["robot"] == "paper-r1" and meta["board"] == "fake"
    assert meta["info"]["firmware_build_id"] == "00c0ffee" and meta["info"]["gait_table_hash"] == "1234abcd"
    assert meta["limb_names"] == ["left", "right"] and meta["psi_star_deg"] == [[20.0], [20.0]]
    rec = read_recording(tmp_path / "run.csv")
    assert rec.psi_deg.shape == (10, 2) and rec.meta.board == "fake"


def test_jsonl_uses_the_csv_field_names_in_physical_units(tmp_path):
    record(tmp_path / "run.csv")
    record(tmp_path / "run.jsonl")
    lines = (tmp_path / "run.jsonl").read_text().splitlines()
    meta = json.loads(lines[0])
    assert meta["msg"] == "META" and meta["robot"] == "paper-r1" and meta["start_utc"].endswith("Z")
    tel = [json.loads(x) for x in lines[1:] if '"TELEMETRY"' in x]
    header = (tmp_path / "run.csv").read_text().splitlines()[0].split(",")
    assert len(tel) == 120 and set(tel[0]) == {"msg", *header}
    assert isinstance(tel[5]["psi_left_deg"], float) and isinstance(tel[5]["seq"], int)
    rec = read_recording(tmp_path / "run.jsonl")
    assert rec.psi_deg[5, 0] == pytest.approx(tel[5]["psi_left_deg"])


def test_mcap_recording_reads_back_with_the_mcap_reader(tmp_path):
    from mcap.reader import make_reader

    path = tmp_path / "run.mcap"
    record(path, 50, inject_at=20)
    with path.open("rb") as f:
        reader = make_reader(f)
        summary = reader.get_summary()
        topics = {c.topic: c for c in summary.channels.values()}
        assert set(topics) == {"/proleg/telemetry", "/proleg/events"}
        schema = summary.schemas[topics["/proleg/telemetry"].schema_id]
        assert schema.encoding == "jsonschema"
        assert json.loads(schema.data)["properties"]["seq"]["type"] == "integer"
        msgs = [(ch.topic, m) for _, ch, m in reader.iter_messages()]
        meta = {r.name: r.metadata for r in reader.iter_metadata()}
    tel = [json.loads(m.data) for topic, m in msgs if topic == "/proleg/telemetry"]
    assert len(tel) == 50 and "psi_left_deg" in tel[0]
    times = [m.log_time for topic, m in msgs]
    assert times == sorted(times) and times[0] > 1.7e18  # wall-clock nanoseconds
    assert meta["proleg"]["robot"] == "paper-r1"
    rec = read_recording(path)
    assert rec.time_s.size == 50
    assert [e["text"] for e in rec.events if e["msg"] == "INJECT"] == ["dead-actuator:sma-left"]


def test_a_killed_mcap_recorder_keeps_every_chunk_it_completed(tmp_path, capsys):
    """A console killed by SIGKILL (a CI job's hard timeout, a crash) writes no MCAP footer. The
    library's 1 MiB chunks (an hour of telemetry at 50 Hz) stayed in memory and the reader
    needed the footer, so the file read back as nothing: every whole chunk is now on disk (at
    most CHUNK_BYTES are lost) and a file without a footer reads up to its last whole record,
    with a warning. What is on disk while the recorder runs is what SIGKILL leaves."""
    pytest.importorskip("mcap")
    from proleg.cli.main import main
    from proleg.record.mcap_format import CHUNK_BYTES

    path = tmp_path / "run.mcap"
    _, client, rec = _recording(path)
    frames = 0
    while frames < 300:
        rx = client.recv_received(1.0)
        assert rx is not None
        rec.on_message(rx)
        frames += rx.message.name == "TELEMETRY"
    killed = tmp_path / "killed.mcap"
    killed.write_bytes(path.read_bytes())  # the recorder is still open: no footer yet
    kept = read_recording(killed)
    assert 0 < 300 - kept.time_s.size < CHUNK_BYTES / 200  # a telemetry message is over 200 bytes of JSON
    assert np.all(np.diff(kept.seq) == 1) and kept.seq[0] == 0
    assert main(["plot", str(killed), "-o", str(tmp_path / "out.png")]) == 0
    assert f"warning: {killed}: no MCAP footer: read up to message" in capsys.readouterr().err
    rec.stop()
    assert read_recording(path).time_s.size == 300  # finished: every message, and no warning
    assert "footer" not in capsys.readouterr().err


def test_an_mcap_recorder_killed_before_its_first_chunk_says_so(tmp_path, capsys):
    """SIGKILL in the recording's first second (a few frames, all in the unwritten first chunk)
    left the header and the metadata: read back, that was 'not a readable MCAP recording
    (unknown (opcode 34) record has length 7310018830345052218 …)', the metadata's last bytes
    taken for a footer, as if the file were garbage."""
    pytest.importorskip("mcap")
    from proleg.cli.main import main

    path = tmp_path / "run.mcap"
    _, client, rec = _recording(path)
    for _ in range(10):
        rx = client.recv_received(1.0)
        assert rx is not None
        rec.on_message(rx)
    killed = tmp_path / "killed.mcap"
    killed.write_bytes(path.read_bytes())  # what SIGKILL leaves now: the first chunk is not written yet
    rec.stop()
    with pytest.raises(RecordingError) as e:
        read_recording(killed)
    assert str(e.value) == (f"{killed}: not a readable MCAP recording (no telemetry in it: it ends, without a "
                            "footer, before its first chunk was written whole: a recorder killed in its first "
                            "second or so)")
    assert main(["plot", str(killed), "-o", str(tmp_path / "out.png")]) == 2
    assert "opcode" not in capsys.readouterr().err


def test_an_mcap_chunk_with_damaged_compressed_bytes_is_read_up_to_it_not_a_traceback(tmp_path, capsys):
    """A chunk whose zstd bytes were damaged (a disk or copy error): the decompressor's
    ZstdError is no McapError, and proleg plot printed a traceback. Now the messages before the
    damaged chunk are read, with a warning that says so (the file has its footer: it was not
    cut short); a damaged first chunk is the one-line error of any unreadable recording."""
    pytest.importorskip("mcap")
    pytest.importorskip("zstandard")
    from proleg.cli.main import main

    path = tmp_path / "run.mcap"
    record(path, frames=300)
    data = path.read_bytes()
    frames = [i for i in range(len(data)) if data[i:i + 4] == b"\x28\xb5\x2f\xfd"]  # zstd frames: chunks
    assert len(frames) >= 3, "300 frames make several 16 KiB chunks"
    for which, rc in ((1, 0), (0, 2)):
        spoiled = tmp_path / f"spoiled{which}.mcap"
        spoiled.write_bytes(data[:frames[which]] + b"\0\0\0\0" + data[frames[which] + 4:])
        assert main(["plot", str(spoiled), "-o", str(tmp_path / f"out{which}.png")]) == rc
        err = capsys.readouterr().err
        assert "Traceback" not in err and "ZstdError" not in err, err
        if rc == 0:
            kept = read_recording(spoiled)
            assert 0 < kept.time_s.size < 300 and np.all(np.diff(kept.seq) == 1)
            assert f"warning: {spoiled}: not readable past message" in err and "footer" not in err
        else:
            assert f"{spoiled}: not a readable MCAP recording (a damaged chunk" in err


def test_every_writer_has_a_reader_and_the_suffix_picks_them():
    from proleg.record import READERS, WRITERS

    assert set(WRITERS) == set(READERS) == {".csv", ".jsonl", ".ndjson", ".mcap"}
    for suffix, writer in WRITERS.items():
        assert suffix in writer.suffixes and suffix in READERS[suffix].suffixes


def test_a_full_disk_stops_the_writer_with_one_error_line_and_no_exception(tmp_path):
    if not Path("/dev/full").exists():
        pytest.skip("no /dev/full")
    full = tmp_path / "full.jsonl"
    full.symlink_to("/dev/full")
    board = FakeBoard()
    client = RobotClient(SimLink(board))
    info = client.connect()
    meta = RecordingMeta.for_robot(info=info, robot=ROBOT)
    with pytest.raises(LinkError, match="cannot write record file .*full.jsonl: No space left on device"):
        Logger(full, meta)  # the metadata line already fails
    rec = Logger(tmp_path / "run.jsonl", meta)
    rec._f.close()
    rec._f = open("/dev/full", "w")  # the disk fills up during the run
    for _ in range(5):
        rec.on_message(client.recv_received(1.0))  # must not raise into the Notifier thread
    assert rec.error is not None and "No space left on device" in str(rec.error)
    assert "\n" not in str(rec.error)


def test_a_killed_recorders_half_line_is_ignored(tmp_path):
    path = tmp_path / "run.jsonl"
    record(path, 20)
    with path.open("a") as f:
        f.write('{"t_host_s": 1.0, "msg": "TELEM')
    assert read_recording(path).time_s.size == 20


def test_plot_has_fault_and_injection_markers_and_limb_names(tmp_path):
    from proleg.plot import _markers

    record(tmp_path / "run.jsonl", 60, inject_at=30)
    rec = read_recording(tmp_path / "run.jsonl")
    marks = _markers(rec)
    assert [m[2] for m in marks] == ["injected dead-actuator:sma-left"]
    assert rec.meta.limb_names == ("left", "right") and rec.meta.channel_names == ("sma-left", "sma-right")
    out = plot_recording(tmp_path / "run.jsonl", tmp_path / "run.svg")
    svg = out.read_text()
    assert "injected dead-actuator:sma-left" in svg or "injected" in svg


def test_plot_labels_the_states_a_large_robot_visits(capsys, tmp_path):
    """caterpillar-4 has 36 states: its state panel counted indices 0..35, where a lab reads
    labels (0220). The states the run visits are labelled when they are 16 or fewer."""
    from proleg.cli.main import main
    from proleg.plot import MAX_STATE_TICKS, state_ticks

    assert state_ticks([0, 3], [np.nan, 1.0], 4) == [0, 1, 2, 3]  # a small robot: every state
    assert state_ticks([0, 9, 27], [np.nan, 65535.0, 9.0, 11.0], 36) == [0, 9, 11, 27]
    assert state_ticks(list(range(MAX_STATE_TICKS + 1)), [], 36) == []  # too many: indices
    run_path = tmp_path / "cat.jsonl"
    assert main(["sim", "caterpillar-4", "--duration", "20", "--record", str(run_path)]) == 0
    capsys.readouterr()
    assert plot_recording(run_path, tmp_path / "cat.svg").stat().st_size > 0
    rec = read_recording(run_path)
    ticks = state_ticks(rec.target, rec.measured, 36)
    assert 0 in ticks and 2 <= len(ticks) <= MAX_STATE_TICKS  # rest and the gait's states, by label


def test_plot_writes_the_image_atomically(tmp_path):
    src = tmp_path / "run.csv"
    record(src)
    out = plot_recording(src, tmp_path / "run.png")
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.csv", "run.events.csv", "run.meta.json", "run.png"]


@pytest.mark.parametrize("content, match", [
    (None, "does not exist"),
    ("hello\n", "not a proleg CSV recording"),
])
def test_unreadable_record_file_is_one_recording_error_and_no_output(tmp_path, content, match):
    src = tmp_path / "bad.csv"
    if content is not None:
        src.write_text(content)
    with pytest.raises(RecordingError, match=match) as e:
        plot_main(record_file=str(src), out=str(tmp_path / "out.png"))
    assert "\n" not in str(e.value)
    assert not (tmp_path / "out.png").exists()
    assert [p.name for p in tmp_path.iterdir() if p.name != "bad.csv"] == []


def test_unknown_record_extension_is_refused_before_connecting(tmp_path):
    with pytest.raises(UsageError, match="use .csv, .jsonl, .mcap"):
        console_main(port="/dev/ttyNOPE", record=str(tmp_path / "run.txt"), plain=True)


def test_console_on_a_missing_port_is_one_clear_line(tmp_path):
    with pytest.raises(LinkError, match="^cannot open serial port /dev/ttyNOPE-proleg:"):
        console_main(port="/dev/ttyNOPE-proleg", record=str(tmp_path / "run.csv"), plain=True)
    assert not (tmp_path / "run.csv").exists()


def test_console_on_an_unknown_can_interface_is_one_clear_line():
    with pytest.raises(UsageError, match="unknown CAN interface 'bogus'; python-can knows: "):  # a typo: exit 2
        console_main(can_channel="can0", interface="bogus", plain=True)


def test_dbc_command_writes_a_file_cantools_loads(tmp_path, capsys, monkeypatch):
    import cantools

    out = tmp_path / "robot.dbc"
    assert dbc_main(out=str(out), nodes=[1]) == 0
    assert len(cantools.database.load_file(str(out)).messages) == 9  # 8 protocol frames + EVENT
    assert "wrote" in capsys.readouterr().out
    with pytest.raises(UsageError, match="does not exist"):  # exit 2 as plot and learn --out (it was 1)
        dbc_main(out=str(tmp_path / "no" / "robot.dbc"))
    # -o -: the DBC on standard output, not a file named "-"
    cwd = tmp_path / "cwd"
    cwd.mkdir()
    monkeypatch.chdir(cwd)
    assert dbc_main(out="-", nodes=[1]) == 0
    text = capsys.readouterr().out
    assert list(cwd.iterdir()) == []
    assert len(cantools.database.load_string(text, "dbc").messages) == 9 and "wrote" not in text


@pytest.mark.parametrize("suffix", [".csv", ".jsonl", ".mcap"])
def test_recorded_events_name_the_actuator_and_states_as_the_console_does(tmp_path, suffix):
    from proleg.console.names import RobotNames, event_text
    from proleg.link.received import Received
    from proleg.protocol.codec import Message
    from proleg.protocol.definition import EventKind, FaultCode

    if suffix == ".mcap":
        pytest.importorskip("mcap")
    meta = RecordingMeta.for_robot(robot=ROBOT, board="fake")
    assert meta.actuator_names == ("sma-left", "sma-right")
    events = [
        {"time_ms": 20000, "kind": int(EventKind.SUSPECT), "code": 1, "detail": 11},
        {"time_ms": 20001, "kind": int(EventKind.FALLBACK), "code": 1, "detail": 2},
        {"time_ms": 20002, "kind": int(EventKind.FAULT), "code": int(FaultCode.SMA_ON_LIMIT), "detail": 0},
        {"time_ms": 20003, "kind": int(EventKind.GAIT_STOPPED), "code": 1, "detail": 3},
        {"time_ms": 20004, "kind": int(EventKind.STATE_REACHED), "code": 0, "detail": 2},
    ]
    rec = Logger(tmp_path / f"run{suffix}", meta)
    telemetry = {"seq": 0, "time_ms": 19999, "measured": 0, "target": 1, "gait": 0, "direction": 0, "step": 0,
                 "flags": 1, "psi": (0, 0), "duty": (0, 0)}
    rec.on_message(Received(Message("TELEMETRY", telemetry), 19.9))  # a recording holds telemetry
    for i, f in enumerate(events):
        rec.on_message(Received(Message("EVENT", f), 20.0 + i))
    rec.stop()
    texts = [e["text"] for e in read_recording(tmp_path / f"run{suffix}").events]
    assert texts == [
        "suspects sma-right (transition 10→11 failed)",
        "FALLBACK: gave up sma-right, runs its 2-step fallback gait",
        "FAULT SMA_ON_LIMIT on sma-left",
        "gait stopped: FAULT after 3 cycles",
        "step 1 reached state 10",  # states by label, as the console names them ("state 2" before)
    ]
    # one implementation: the console's, which names states through the robot's labels
    assert texts == [event_text(f, RobotNames.for_robot(ROBOT), ROBOT.transitions.label) for f in events]


@pytest.mark.parametrize("where, why, status", [("missing/x.mcap", "No such file or directory", 2),
                                                ("folder.csv", "Is a directory", 1)])
@pytest.mark.parametrize("command", [["console", "--sim", "paper-r1", "--plain", "--duration", "0.5"],
                                     ["sim", "paper-r1", "--duration", "0.5"]])
def test_a_recording_that_cannot_be_written_is_refused_before_the_robot_is_touched(tmp_path, capsys, where, why,
                                                                                  status, command):
    """A folder that does not exist is a usage mistake (exit 2, as every command's output
    directory; sim and run said 1); a directory in the file's place cannot be written (1)."""
    from proleg.cli.main import main

    (tmp_path / "folder.csv").mkdir()
    code = main([*command, "--record", str(tmp_path / where)])
    err = capsys.readouterr().err
    assert code == status and f"cannot write record file {tmp_path / where}: {why}" in err
    assert "robot stopped" not in err  # never connected, so nothing to stop


def _edit_line(path: Path, n: int, edit) -> None:
    lines = path.read_text().split("\n")
    lines[n - 1] = edit(lines[n - 1])
    path.write_text("\n".join(lines))


def _jsonl_field(n: int, **fields):
    return lambda path: _edit_line(path, n, lambda line: json.dumps({**json.loads(line), **fields}))


def _first(msg: str, **fields):
    def edit(path: Path) -> None:
        lines = path.read_text().splitlines(keepends=True)
        n = next(i for i, line in enumerate(lines) if f'"{msg}"' in line)
        lines[n] = json.dumps({**json.loads(lines[n]), **fields}) + "\n"
        path.write_text("".join(lines))
    return edit


def _csv_cell(column: str, value: str, *, events: bool = False):
    def edit(path: Path) -> None:
        target = path.with_name("run.events.csv") if events else path
        header = target.read_text().splitlines()[0].split(",")
        i = header.index(column)
        _edit_line(target, 3, lambda line: ",".join(value if k == i else c for k, c in enumerate(line.split(","))))
    return edit


@pytest.mark.parametrize("suffix, spoil, where, says", [
    (".csv", _csv_cell("t_s", "bar", events=True), "run.events.csv:3", "t_s: expected a finite number, got 'bar'"),
    (".csv", _csv_cell("t_s", "abc0.1"), "run.csv:3", "t_s: expected a finite number, got 'abc0.1'"),
    (".csv", _csv_cell("seq", "nan"), "run.csv:3", "seq: expected an integer, got nan"),
    # a damaged file's 1e308 was plotted, with numpy's "overflow encountered" warnings and exit 0
    (".csv", _csv_cell("t_s", "1e308"), "run.csv:3", "t_s: expected a finite number within ±1e+12 (a damaged "
                                                     "file?), got 1e+308"),
    (".csv", _csv_cell("psi_left_deg", "-inf"), "run.csv:3", "psi_left_deg: expected a number or empty within "
                                                             "±1e+12 (a damaged file?), got -inf"),
    (".csv", _csv_cell("seq", "1.5"), "run.csv:3", "seq: expected an integer, got 1.5"),
    (".csv", lambda p: _edit_line(p, 3, lambda line: line + ",9,9"), "run.csv:3", "16 cells, expected 14"),
    (".jsonl", _jsonl_field(1, psi_star_deg="abc"), "run.jsonl:1", "psi_star_deg: expected a list of lists"),
    (".jsonl", _jsonl_field(1, limb_names=5), "run.jsonl:1", "limb_names: expected a list of names, got 5"),
    (".jsonl", _first("INJECT", t_s="abc"), "run.jsonl:", "t_s: expected a finite number, got 'abc'"),
    (".jsonl", _first("TELEMETRY", seq=1.5), "run.jsonl:", "seq: expected an integer, got 1.5"),
    (".jsonl", _first("TELEMETRY", t_s="0.1"), "run.jsonl:", "t_s: expected a finite number, got '0.1'"),
    (".mcap", lambda p: p.write_text("1,2\n"), "run.mcap", "not a readable MCAP recording (it ends early"),
    # its magic and a few bytes, shorter than the footer the index is read from (a recorder
    # killed as it began): the reader's seek back from the end was "cannot write: Invalid
    # argument", exit 1
    (".mcap", lambda p: p.write_bytes(p.read_bytes()[:20]), "run.mcap",
     "not a readable MCAP recording (it ends early"),
    # cut inside its one chunk: no message was written whole (a cut after a whole chunk reads
    # back up to it: test_a_killed_mcap_recorder_keeps_every_chunk_it_completed)
    (".mcap", lambda p: p.write_bytes(p.read_bytes()[:len(p.read_bytes()) // 2]), "run.mcap",
     "not a readable MCAP recording ("),
])
def test_a_bad_recording_is_one_line_naming_its_file_and_line_and_exit_2(tmp_path, capsys, suffix, spoil, where, says):
    from proleg.cli.main import main

    if suffix == ".mcap":
        pytest.importorskip("mcap")
    path = tmp_path / f"run{suffix}"
    record(path, 20, inject_at=10)
    spoil(path)
    code = main(["plot", str(path), "-o", str(tmp_path / "out.png")])
    err = capsys.readouterr().err
    assert code == 2, err
    assert err.count("\n") == 1 and f"{tmp_path / where}" in err and says in err, err
    assert not (tmp_path / "out.png").exists()


def _meta_json(**fields):
    def edit(path: Path) -> None:
        meta = path.with_name(f"{path.stem}.meta.json")
        meta.write_text(json.dumps({**json.loads(meta.read_text()), **fields}))
    return edit


@pytest.mark.parametrize("suffix, spoil, says", [
    (".csv", _meta_json(limb_names=["left"]), "names limbs left and actuators sma-left, sma-right, but its rows "
                                              "have a column psi_right_deg it does not name"),
    (".csv", _meta_json(channel_names=[]), "but its rows have a column duty_sma_left_pct it does not name"),
    (".jsonl", _jsonl_field(1, limb_names=["left", "right", "middle"]), "but no row has a column psi_middle_deg"),
])
def test_a_recording_whose_metadata_is_another_recordings_is_refused(tmp_path, capsys, suffix, spoil, says):
    """A .meta.json copied or edited beside the CSV was plotted without a word, exit 0: a limb
    it does not name left out (and matplotlib's "No artists with labels" warning for no coil),
    one it names but no row has drawn as nothing."""
    from proleg.cli.main import main

    path = tmp_path / f"run{suffix}"
    record(path, 20)
    spoil(path)
    code = main(["plot", str(path), "-o", str(tmp_path / "out.png")])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and f"{path}: its metadata " in err and says in err, err
    assert "the metadata is not this recording's" in err and not (tmp_path / "out.png").exists()


@pytest.mark.parametrize("suffix", [".csv", ".jsonl"])
def test_a_killed_recorders_torn_last_row_is_dropped_with_a_warning(tmp_path, capsys, suffix):
    from proleg.cli.main import main

    path = tmp_path / f"run{suffix}"
    record(path, 20)
    with path.open("a") as f:
        f.write("2.662,2.66,132,3,1,0,0" if suffix == ".csv" else '{"msg": "TELEM')
    lines = path.read_text().count("\n") + 1
    assert read_recording(path).time_s.size == 20
    assert main(["plot", str(path), "-o", str(tmp_path / "out.png")]) == 0
    err = capsys.readouterr().err
    assert f"warning: {path}:{lines}: torn last line dropped" in err


def test_a_csv_recording_whose_events_file_cannot_be_opened_names_it_and_leaves_nothing(tmp_path):
    (tmp_path / "run.events.csv").mkdir()
    meta = RecordingMeta.for_robot(robot=ROBOT, board="fake")
    with pytest.raises(LinkError, match=f"cannot write record file {tmp_path / 'run.events.csv'}: Is a directory"):
        Logger(tmp_path / "run.csv", meta)
    assert [p.name for p in tmp_path.iterdir()] == ["run.events.csv"]  # no run.csv, no run.meta.json
    from proleg.record import check_suffix

    with pytest.raises(LinkError, match="run.events.csv: Is a directory"):
        check_suffix(tmp_path / "run.csv")  # refused before connecting, as for run.csv itself


def test_a_full_disk_while_opening_a_csv_recording_leaves_no_empty_files(tmp_path):
    if not Path("/dev/full").exists():
        pytest.skip("no /dev/full")
    (tmp_path / "run.events.csv").symlink_to("/dev/full")
    with pytest.raises(LinkError, match="No space left on device"):
        Logger(tmp_path / "run.csv", RecordingMeta.for_robot(robot=ROBOT, board="fake"))
    assert [p.name for p in tmp_path.iterdir()] == ["run.events.csv"]  # the link stays; no run.csv, no meta


def test_gait_plot_says_which_answers_have_no_gait(tmp_path, capsys, monkeypatch):
    """A robot with no gait in either direction (one limb, whose two transitions cancel) drew an
    empty figure titled "10 passes of each gait", with matplotlib's 'No artists with labels
    found to put in legend' UserWarning on stderr; the one-actuator R1, which has no -x gait,
    left -x out of the figure without a word. The figure now says which answers have none."""
    import proleg.plot
    from proleg.cli.main import main

    drawn = []
    real = proleg.plot.write_figure
    monkeypatch.setattr(proleg.plot, "write_figure", lambda fig, path: (drawn.append(fig), real(fig, path)))
    one = tmp_path / "one.toml"
    one.write_text('[robot]\nname = "one-leg"\n[[limb]]\nname = "only"\npsi_star_deg = [20.0]\nactuator = "c"\n'
                   '[[actuator]]\nname = "c"\n[transitions]\nmatrix = [[0, 1], [-1, 0]]\n')
    out = tmp_path / "none.png"
    with _no_warning():  # a warning is an error here (matplotlib's legend of nothing was one)
        assert main(["gait", str(one), "--plot", str(out)]) == 0
    err = capsys.readouterr().err
    assert "UserWarning" not in err and out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    texts = [t.get_text() for t in drawn[-1].axes[0].texts]
    assert "no gait moves the robot: +x, -x" in texts
    assert main(["gait", "paper-r1-one-actuator", "--plot", str(tmp_path / "one-way.png")]) == 0
    ax = drawn[-1].axes[0]
    assert [t.get_text() for t in ax.texts if t.get_text()] == ["no gait moves the robot: -x"]
    assert [t.get_text() for t in ax.get_legend().get_texts()][0].startswith("+x: ")


def _no_warning():
    import warnings

    class _Raise(warnings.catch_warnings):
        def __enter__(self):
            super().__enter__()
            warnings.simplefilter("error")
    return _Raise()


def test_gait_plot_with_evaluate_draws_the_sequence_and_cycles_alone_is_refused(tmp_path, capsys):
    from proleg.cli.main import main

    out = tmp_path / "walk.png"
    assert main(["gait", "paper-r1", "--evaluate", "00,10,11,01,00", "--plot", str(out), "--cycles", "3"]) == 0
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert capsys.readouterr().out.splitlines()[0] == f"wrote {out}"  # as plot and dbc say it
    for argv in (["--cycles", "3"], ["--evaluate", "00,10,11,01,00", "--cycles", "3"]):
        assert main(["gait", "paper-r1", *argv]) == 2
        assert "--cycles 3: only with --plot" in capsys.readouterr().err
    assert main(["gait", "paper-r1", "--heading", "0", "--cycles", "3"]) == 0  # planar text composes 3 passes
    assert "after 3 passes" in capsys.readouterr().out


def test_gait_plot_to_a_directory_or_a_full_disk_names_the_users_file(tmp_path, capsys, monkeypatch):
    from proleg.cli.main import main

    (tmp_path / "d.png").mkdir()
    assert main(["gait", "paper-r1", "--plot", str(tmp_path / "d.png")]) == 1  # as every output (was 2)
    assert capsys.readouterr().err == f"proleg: error: gait --plot: cannot write {tmp_path / 'd.png'}: Is a directory\n"

    def full(*a, **k):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr("matplotlib.figure.Figure.savefig", full)
    out = tmp_path / "x.png"
    assert main(["gait", "paper-r1", "--plot", str(out)]) == 1
    assert capsys.readouterr().err == f"proleg: error: cannot write plot {out}: No space left on device\n"
    assert [p.name for p in tmp_path.iterdir()] == ["d.png"]  # no temp file left


def test_a_three_level_robots_recorded_states_are_labels_not_indices(tmp_path, capsys):
    # tri-mixed-meas recorded "step 2 reached state 5" where the console showed 021
    from proleg.cli import main

    robot = Path(__file__).parent / "fixtures" / "tri-mixed-meas.toml"
    assert main(["sim", str(robot), "--duration", "4", "--record", str(tmp_path / "r.jsonl")]) == 0
    labels = set(load_robot(robot).transitions.labels())
    reached = [e["text"] for e in read_recording(tmp_path / "r.jsonl").events if e["kind"] == "STATE_REACHED"]
    assert len(reached) > 2 and all(t.rsplit(" ", 1)[1] in labels for t in reached), reached


def test_a_sim_recording_carries_the_firmwares_info_as_run_sim_does(tmp_path, capsys):
    # docs/data.md promises info (build id, gait-table hash, protocol version, rates, link);
    # proleg sim --record wrote "info": {}
    from proleg.cli import main

    assert main(["sim", "paper-r1", "--duration", "2", "--record", str(tmp_path / "sim.jsonl")]) == 0
    assert main(["run", "paper-r1", "--sim", "--duration", "2", "--record", str(tmp_path / "run.jsonl")]) == 0
    sim, run = (read_recording(tmp_path / f"{n}.jsonl").meta for n in ("sim", "run"))
    keys = {"firmware_build_id", "gait_table_hash", "protocol_version", "tick_hz", "telemetry_hz", "link"}
    assert set(sim.info) == set(run.info) == keys
    assert {k: sim.info[k] for k in keys - {"link"}} == {k: run.info[k] for k in keys - {"link"}}
    assert sim.info["link"] == "simulated host-sim board"
    assert sim.board == run.board == "host-sim"


def test_every_format_reads_the_events_back_alike_numbers_as_numbers(tmp_path):
    """read_recording of a CSV recording gave each event's t_host_s, code and detail as text
    ('0.002', '1'), where the JSONL and MCAP readers give floats and ints (docs/data.md: code
    and detail are ints): a script that reads any format compared '1' with 1."""
    pytest.importorskip("mcap")
    got = {}
    for suffix in (".csv", ".jsonl", ".mcap"):
        record(tmp_path / f"run{suffix}", 20, inject_at=10)
        got[suffix] = read_recording(tmp_path / f"run{suffix}").events
    for suffix, events in got.items():
        assert events and all(isinstance(e["code"], int) and isinstance(e["detail"], int)
                              and isinstance(e["t_host_s"], (int, float)) for e in events), (suffix, events[:2])
        assert [(e["msg"], e["kind"], e["code"], e["detail"], e["text"]) for e in events] == \
            [(e["msg"], e["kind"], e["code"], e["detail"], e["text"]) for e in got[".jsonl"]], suffix


@pytest.mark.parametrize("channels", [(1, 0), (3, 1)])
def test_duty_columns_name_the_actuator_the_firmware_sends_whatever_its_channel(tmp_path, channels):
    """TELEMETRY carries one duty per actuator in the robot file's order (core/telemetry.c).
    The recording named them by PWM channel: with R1's coils on swapped channels the left
    coil's heat was filed under sma-right, and channels 3 and 1 gave duty_ch0_pct…"""
    from proleg.cli import main

    text = (Path(__file__).parents[1] / "robots" / "paper-r1.toml").read_text()
    assert text.count("channel = 0") == 1 and text.count("channel = 1") == 1
    text = text.replace("channel = 0", "channel = @L").replace("channel = 1", "channel = @R")
    robot = tmp_path / "r1.toml"
    robot.write_text(text.replace("@L", str(channels[0])).replace("@R", str(channels[1])))
    assert main(["sim", str(robot), "--duration", "4", "--record", str(tmp_path / "r.jsonl")]) == 0
    rec = read_recording(tmp_path / "r.jsonl")
    assert rec.meta.channel_names == ("sma-left", "sma-right")
    left, right = rec.duty_pct[:, 0], rec.duty_pct[:, 1]
    psi_left = rec.psi_deg[:, 0]
    first_up = int(np.argmax(psi_left > 20.0))  # gait 0 starts 00 -> 10: the left coil alone raises it
    assert first_up > 0
    assert left[:first_up].max() > 50.0 and right[:first_up].max() == 0.0


def test_a_name_the_plot_font_cannot_draw_is_one_warning_line(tmp_path, capsys):
    """Limbs named in Japanese (後ろ足): proleg plot printed matplotlib's raw UserWarning, with
    its source line, once per character and panel (18 lines for one name); now one line names
    the characters, and the plot is still written."""
    from proleg.cli.main import main

    text = ROBOT_FILE.read_text().replace('name = "left"', 'name = "後ろ足"')
    robot = tmp_path / "jp.toml"
    robot.write_text(text, encoding="utf-8")
    path = tmp_path / "run.csv"
    assert main(["sim", str(robot), "--duration", "2", "--record", str(path), "-q"]) == 0
    capsys.readouterr()
    from matplotlib.font_manager import FontProperties, findfont
    from matplotlib.ft2font import FT2Font

    if FT2Font(findfont(FontProperties())).get_char_index(ord("後")):
        pytest.skip("the plot font draws CJK here")
    import warnings

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        assert main(["plot", str(path), "-o", str(tmp_path / "out.png")]) == 0
    err = capsys.readouterr().err
    assert not [w for w in caught if "Glyph" in str(w.message)] and err.count("\n") == 1, err
    assert "has no glyph for 後 ろ 足, drawn as boxes" in err
    assert (tmp_path / "out.png").exists()


class _DiskFillsAt:
    """``open`` for a recording whose disk fills after ``limit`` bytes of a file: the write(2)
    that crosses it writes what fits, the next fails with ENOSPC (as a full file system does)."""

    def __init__(self, limit: int):
        self.limit = limit

    def __call__(self, path, mode="w", **kw):
        import errno
        import io

        limit = self.limit

        class Filling(io.FileIO):
            written = 0

            def write(self, b):
                room = limit - self.written
                if room <= 0:
                    raise OSError(errno.ENOSPC, "No space left on device", str(path))
                n = super().write(bytes(b)[:room])
                self.written += n
                return n

        raw = Filling(path, "w")
        return io.TextIOWrapper(io.BufferedWriter(raw), encoding=kw.get("encoding", "utf-8"),
                                newline=kw.get("newline"), write_through=False)


@pytest.mark.parametrize("suffix", [".csv", ".jsonl"])
def test_a_disk_that_fills_mid_row_leaves_the_recording_whole_up_to_its_last_row(tmp_path, monkeypatch, caplog,
                                                                                  suffix):
    """A full disk mid-session left half a row at the end of the file (read back with a "torn last
    line" warning, and by pandas as a broken row), and nothing was said until the command ended.
    The file is now cut back to its last whole row, and a warning says so at once."""
    import logging

    from proleg.record import base

    monkeypatch.setattr(base, "open", _DiskFillsAt(6000), raising=False)
    path = tmp_path / f"run{suffix}"
    _, client, rec = _recording(path)
    with caplog.at_level(logging.WARNING, logger="proleg"):
        for _ in range(200):
            rec.on_message(client.recv_received(1.0))
    rec.stop()
    assert rec.error is not None and "No space left on device" in str(rec.error)
    assert any("the recording stopped here (kept up to its last whole row)" in r.getMessage() for r in caplog.records)
    text = path.read_text()
    assert 0 < len(text) <= 6000 and text.endswith("\n")
    caplog.clear()
    with caplog.at_level(logging.WARNING, logger="proleg"):
        rows = read_recording(path)
    assert len(rows.time_s) > 10 and not [r for r in caplog.records if "torn" in r.getMessage()]


@pytest.mark.parametrize("suffix", [".csv", ".jsonl", ".mcap"])
def test_an_earlier_recording_of_the_same_name_stays_until_the_new_one_records(tmp_path, suffix):
    """A session that opens a recording and never records (interrupted before START, a link
    that never came up) leaves an earlier file of that name as it was; once it records, the new
    recording takes the name, and no file of its own is left beside it."""
    path = tmp_path / f"run{suffix}"
    record(path, frames=20)
    earlier = {p.name: p.read_bytes() for p in tmp_path.iterdir()}
    meta = RecordingMeta.for_robot(robot=ROBOT, board="fake")
    Logger(path, meta).discard()
    assert {p.name: p.read_bytes() for p in tmp_path.iterdir()} == earlier
    record(path, frames=40)
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(earlier)  # no .proleg-new left
    assert len(read_recording(path).time_s) == 40


def test_a_recording_made_before_names_kept_their_script_still_reads(tmp_path):
    """Recordings made before non-ASCII characters were written as their code points name such a
    limb's column with '_' (tête → t_te): read back, its ψ is that column, not missing."""
    meta = RecordingMeta(robot="x", limb_names=("tête", "b"), channel_names=("sma-a",))
    row = {"t_host_s": 0.0, "t_s": 0.0, "seq": 0, "measured": 0, "target": 0, "step": 0, "flags": 0,
           "psi_t_te_deg": 12.5, "psi_b_deg": 3.0, "duty_sma_a_pct": 0.0}
    from proleg.record.base import Recording

    rec = Recording.from_rows(tmp_path / "old.csv", meta, [("old.csv:2", row)], [])
    assert rec.psi_deg.tolist() == [[12.5, 3.0]]
