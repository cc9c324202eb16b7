"""A link that goes silent near the end of a run loses frames no sequence gap shows: no frame
comes after them to count from. ``proleg sim --inject link-drop:1+5`` for 20 s said "250 frames,
0 lost" (and ``telemetry_lost`` 0) while the last 15 s and STOP's tries heard nothing; the
report now says from when nothing came (``GaitRun.end_silence``), on ``sim`` and on ``run``;
and ``run`` counts the frames lost in the run, as ``sim`` does."""

from __future__ import annotations

import json

import pytest
from build_checks import R1, cli
from hypothesis import given, settings
from hypothesis import strategies as st

from proleg.link import sim_link
from proleg.report.gait_run import SILENT_FRAMES, SILENT_MIN_S, GaitRun


def test_sim_says_the_link_went_silent_after_5_s(capsys):
    code, out, _err = cli(capsys, "sim", R1, "--duration", "12", "--inject", "link-drop:1+5", "--json")
    doc = json.loads(out)
    assert code == 1 and doc["telemetry_lost"] == 0  # no frame after the silence to count a gap from
    assert doc["telemetry_silent_s"] > 12 - 5  # the run's last 7 s and STOP's tries
    code, out, _err = cli(capsys, "sim", R1, "--duration", "12", "--inject", "link-drop:1+5")
    assert "none after 5.0 s of the run (" in out


def test_an_undisturbed_run_has_no_silence(capsys):
    code, out, _err = cli(capsys, "sim", R1, "--duration", "6", "--json")
    assert code == 0 and json.loads(out)["telemetry_silent_s"] == 0
    code, out, _err = cli(capsys, "sim", R1, "--duration", "6")
    assert "none after" not in out


def test_run_says_when_its_board_went_quiet(capsys, monkeypatch):
    """``proleg run``: the board's frames stop reaching the host 4 s into an 8 s run; STOP's
    answer is lost with them, and the run fails."""
    real_read = sim_link.SimLink.read

    def read(self, timeout):
        data = real_read(self, timeout)
        return b"" if self.board.time_s > 4.0 else data

    monkeypatch.setattr(sim_link.SimLink, "read", read)
    code, out, err = cli(capsys, "run", R1, "--sim", "--duration", "8", "--format", "jsonl", "-q")
    doc = next(json.loads(ln) for ln in out.splitlines() if '"RESULT"' in ln)
    assert code == 1 and doc["telemetry_silent_s"] > 4.0, (out, err)


@settings(max_examples=200, deadline=None)
@given(frames=st.integers(0, 50), interval=st.floats(0.001, 1.0), gap=st.floats(0.0, 30.0),
       start=st.floats(0.0, 100.0))
def test_silence_is_the_time_since_the_last_frame_past_five_intervals(frames, interval, gap, start):
    """Against the rule by hand: frames every ``interval`` from START, then ``gap`` seconds to
    the end; silent when the gap is longer than 5 intervals and 0.5 s."""
    run = GaitRun("r", "+x", 0, 1.0)
    for k in range(frames):
        run.telemetry_frames += 1
        run.last_frame_at = start + k * interval
        run.first_frame_at = start if run.first_frame_at is None else run.first_frame_at
    last = start + (frames - 1) * interval if frames else start
    end = last + gap
    run.end_silence(start, end, telemetry_hz=50.0)
    step = (run.last_frame_at - run.first_frame_at) / (frames - 1) if frames > 1 else 1 / 50.0
    quiet = end - last  # the gap as the clock's floats give it (0.5 s may come out 0.5000000000000001)
    silent = quiet > max(SILENT_MIN_S, SILENT_FRAMES * step)
    assert run.telemetry_silent_s == (pytest.approx(gap) if silent else 0.0)
    assert (run.lost_text() != "0 lost") == silent


@pytest.mark.parametrize("argv", [("sim", R1, "--json"), ("run", R1, "--sim", "--format", "jsonl", "-q")])
def test_a_run_that_heard_one_frame_judges_its_silence_by_the_board_telemetry_rate(capsys, monkeypatch, argv):
    """With fewer than two frames there is no interval to measure: ``proleg sim`` took the
    robot's telemetry rate (50 Hz: silent past 0.5 s) and ``proleg run`` none (silent only past
    5 × 0.5 s), so a 1.5 s run that heard a single frame was silent in one and not the other."""
    from proleg.report.gait_run import GaitRunListener

    real = GaitRunListener.on_message

    def one_frame(self, rx):
        if rx.message.name != "TELEMETRY" or self.run.telemetry_frames == 0:
            real(self, rx)

    monkeypatch.setattr(GaitRunListener, "on_message", one_frame)
    _code, out, err = cli(capsys, *argv, "--duration", "1.5")
    doc = next(json.loads(ln) for ln in reversed(out.splitlines()) if ln.startswith("{"))
    assert doc["telemetry_frames"] == 1 and doc["telemetry_silent_s"] > 1.5, (out, err)


def test_run_counts_the_frames_lost_in_the_run_not_since_connecting():
    """``run``'s ``telemetry_lost`` was the link's count since it connected, so frames lost
    while the host waited for the board's state before START counted as the run's (``sim``
    counts the run's own)."""
    from proleg.link import RobotClient, open_link
    from proleg.report import run_gait_on

    link = open_link("sim://paper-r1")
    with RobotClient(link) as client:
        client.connect()
        client.stats.lost += 7  # lost before START
        result = run_gait_on(client, 0, "+x", 3.0)
    assert result.ok and result.telemetry_lost == 0, result
