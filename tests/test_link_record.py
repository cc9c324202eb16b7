"""Recording (CSV / JSON Lines), plots, DBC output, and bad input → one LinkError line."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from proleg.errors import LinkError
from proleg.link import RobotClient
from proleg.cli.link_commands import console_main, dbc_main, plot_main
from fake_board import FakeBoard
from proleg.plot import plot_recording
from proleg.record import Recorder, read_recording
from proleg.link.sim_link import SimLink


def record(path: Path, frames: int = 120) -> FakeBoard:
    board = FakeBoard()
    client = RobotClient(SimLink(board))
    info = client.connect()
    rec = Recorder(path, {**info.header(), "psi_star_deg": "20;20"}, limbs=info.limbs, channels=info.actuators)
    client.start(0, "+x")
    n = 0
    while n < frames:
        rx = client.recv_received(1.0)
        assert rx is not None
        rec.on_message(rx)
        n += rx.message.name == "TELEMETRY"
        if n == frames // 2 and rx.message.name == "TELEMETRY":
            # flushed per line: everything so far is already in the file
            assert path.read_text().count("\n") == rec.lines
    rec.stop()
    return board


def test_csv_recording_has_a_comment_header_and_one_row_per_message(tmp_path):
    path = tmp_path / "run.csv"
    board = record(path)
    lines = path.read_text().splitlines()
    assert lines[0] == "# robot: paper-r1"
    assert "# firmware_build_id: 00c0ffee" in lines and "# gait_table_hash: 1234abcd" in lines
    rec = read_recording(path)
    assert rec.psi_deg.shape == (120, 2) and rec.duty_pct.shape == (120, 2)
    assert rec.header["board"] == "fake"
    assert rec.displacement_mm is not None and rec.displacement_mm[-1] == pytest.approx(board.displacement_mm, abs=10)
    assert any(e["msg"] == "ACK" for e in rec.events)


def test_jsonl_recording_starts_with_its_header_and_keeps_protocol_units(tmp_path):
    path = tmp_path / "run.jsonl"
    record(path)
    lines = path.read_text().splitlines()
    assert json.loads(lines[0])["header"]["robot"] == "paper-r1"
    tel = [json.loads(x) for x in lines[1:] if '"TELEMETRY"' in x]
    assert len(tel) == 120 and isinstance(tel[0]["psi"][0], int)
    rec = read_recording(path)
    assert rec.psi_deg[5, 0] == pytest.approx(tel[5]["psi"][0] / 100)


def test_a_killed_recorders_half_line_is_ignored(tmp_path):
    path = tmp_path / "run.jsonl"
    record(path, 20)
    with path.open("a") as f:
        f.write('{"t": 1.0, "msg": "TELEM')
    assert read_recording(path).time_s.size == 20


def test_plot_writes_the_image_atomically(tmp_path):
    src = tmp_path / "run.csv"
    record(src)
    out = plot_recording(src, tmp_path / "run.png")
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.csv", "run.png"]


@pytest.mark.parametrize("content, match", [
    (None, "does not exist"),
    ("hello\n", "not a proleg CSV recording"),
    ("# robot: r\nhost_s,msg\n1.0,ACK\n", "no TELEMETRY frames"),
])
def test_unreadable_record_file_is_one_link_error_and_no_output(tmp_path, content, match):
    src = tmp_path / "bad.csv"
    if content is not None:
        src.write_text(content)
    with pytest.raises(LinkError, match=match) as e:
        plot_main(record_file=str(src), out=str(tmp_path / "out.png"))
    assert "\n" not in str(e.value)
    assert not (tmp_path / "out.png").exists()
    assert [p.name for p in tmp_path.iterdir() if p.name != "bad.csv"] == []


def test_unknown_record_extension_is_refused_before_connecting(tmp_path):
    with pytest.raises(LinkError, match="use .csv or .jsonl"):
        console_main(port="/dev/ttyNOPE", record=str(tmp_path / "run.txt"), plain=True)


def test_console_on_a_missing_port_is_one_clear_line(tmp_path):
    with pytest.raises(LinkError, match="^cannot open serial port /dev/ttyNOPE-proleg:"):
        console_main(port="/dev/ttyNOPE-proleg", record=str(tmp_path / "run.csv"), plain=True)
    assert not (tmp_path / "run.csv").exists()


def test_console_on_an_unknown_can_interface_is_one_clear_line():
    with pytest.raises(LinkError, match="unknown or unavailable CAN interface 'bogus'"):
        console_main(can_channel="can0", interface="bogus", plain=True)


def test_dbc_command_writes_a_file_cantools_loads(tmp_path, capsys):
    import cantools

    out = tmp_path / "robot.dbc"
    assert dbc_main(out=str(out), nodes=[1]) == 0
    assert len(cantools.database.load_file(str(out)).messages) == 8
    assert "wrote" in capsys.readouterr().out
    with pytest.raises(LinkError, match="does not exist"):
        dbc_main(out=str(tmp_path / "no" / "robot.dbc"))
