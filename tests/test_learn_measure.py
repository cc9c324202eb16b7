"""Trial logs (append-only, resumable), position sources, tracker clock alignment."""

from __future__ import annotations

import json
import warnings
from pathlib import Path

import numpy as np
import pytest

from proleg.learn.measure import Trial, TrialLog, TrialLogError, counts, manual_trial, planar_delta, remaining
from proleg.learn.tours import exploration
from proleg.learn.tracker import Track, TrackerError, TrackerSource, estimate_offset, read_track, trials_from_events
from proleg.robot import load_robot

ROOT = Path(__file__).resolve().parent.parent


def _trial(k: int) -> Trial:
    return Trial("00", "10", k * 1.0, k * 1.0 + 0.5, 4.0 + k, None, None, "sim")


def test_every_record_is_on_disk_before_the_next_transition(tmp_path):
    p = tmp_path / "log.jsonl"
    with TrialLog(p) as log:
        log.append(_trial(0))
        assert json.loads(p.read_text().splitlines()[0])["dx"] == 4.0  # readable while still open
        log.append(_trial(1))
    assert [t.dx for t in TrialLog(p).trials] == [4.0, 5.0]


def test_a_torn_last_line_is_dropped_with_a_warning_and_the_log_continues(tmp_path):
    p = tmp_path / "log.jsonl"
    with TrialLog(p) as log:
        log.append(_trial(0))
        log.append(_trial(1))
    p.write_bytes(p.read_bytes() + b'{"from": "10", "to": "11", "t_sta')
    with pytest.warns(UserWarning, match="torn last record"):
        log = TrialLog(p)
    assert len(log.trials) == 2
    log.append(_trial(2))
    log.close()
    assert [t.dx for t in TrialLog(p).trials] == [4.0, 5.0, 6.0]


def test_a_complete_last_record_without_newline_is_kept(tmp_path):
    p = tmp_path / "log.jsonl"
    p.write_text(_trial(0).to_json())
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        log = TrialLog(p)
    log.append(_trial(1))
    log.close()
    assert len(TrialLog(p).trials) == 2


def test_a_log_saved_with_a_bom_reads_and_appends(tmp_path):
    # Notepad saves UTF-8 with a byte order mark; it was "Unexpected UTF-8 BOM"
    p = tmp_path / "log.jsonl"
    header = json.dumps({"trial_log": 1, "robot": "r"})
    p.write_bytes(b"\xef\xbb\xbf" + (header + "\n" + _trial(0).to_json() + "\n").encode())
    with TrialLog(p, robot="r") as log:
        assert log.robot == "r" and [t.dx for t in log.trials] == [4.0]
        log.append(_trial(1))
    assert [t.dx for t in TrialLog(p).trials] == [4.0, 5.0]


def test_a_broken_line_in_the_middle_is_an_error_naming_the_line(tmp_path):
    p = tmp_path / "log.jsonl"
    p.write_text(_trial(0).to_json() + "\nnot json\n" + _trial(1).to_json() + "\n")
    with pytest.raises(TrialLogError, match="log.jsonl:2"):
        TrialLog(p)


def test_an_interrupted_run_resumes_with_exactly_the_transitions_still_to_do(tmp_path):
    table = load_robot(ROOT / "robots" / "paper-r1.toml").transitions
    tour = exploration(table, 3, seed=2).tours[0]
    p = tmp_path / "log.jsonl"
    with TrialLog(p) as log:
        for a, b in tour.transitions[:17]:
            log.append(Trial(table.label(a), table.label(b), 0, 1, 1.0, source="sim"))
    done = TrialLog(p).trials
    rest = remaining(table, done, 3)
    assert rest.sum() == 3 * table.n_transitions - 17
    again = exploration(table, demand=rest, start=tour.transitions[16][1], seed=3).tours[0]
    total = counts(table, done) + counts(table, [Trial(table.label(a), table.label(b), 0, 1) for a, b in again.transitions])
    assert total.min() >= 3


def test_manual_entry_asks_again_on_nonsense_and_skips_on_empty():
    answers = iter(["four", "4.5"])
    prompts = []

    def ask(p):
        prompts.append(p)
        return next(answers)

    t = manual_trial("00", "10", 1.0, 2.0, ask=ask)
    assert t is not None and t.dx == 4.5 and t.dy is None and t.source == "manual"
    assert "not a number" in prompts[1]
    assert manual_trial("00", "10", 1.0, 2.0, ask=lambda p: "") is None
    t = manual_trial("00", "10", 1.0, 2.0, ask=lambda p: "1, 2, -3", planar=True)
    assert (t.dx, t.dy, t.dtheta_deg) == (1.0, 2.0, -3.0)


def test_manual_entry_asks_again_for_a_number_the_log_could_not_read_back(tmp_path):
    """1e20 was stored, and from then on every report of that log failed on its line."""
    answers = iter(["1e20", "-2e9", "3.5"])
    prompts = []

    def ask(p):
        prompts.append(p)
        return next(answers)

    t = manual_trial("00", "10", 1.0, 2.0, ask=ask)
    assert t is not None and t.dx == 3.5
    assert "within ±1e9" in prompts[1] and "within ±1e9" in prompts[2]
    with TrialLog(tmp_path / "m.jsonl") as log:
        log.append(manual_trial("00", "10", 1.0, 2.0, ask=lambda p: "1e9"))
    assert [tr.dx for tr in TrialLog(tmp_path / "m.jsonl", append=False).trials] == [1e9]


def test_manual_entry_asks_again_for_a_typo_rather_than_reading_another_number():
    """float() reads '1_0' as 10 (the CLI's number options refuse it as a typo): typed for 1.0 it
    was logged as 10 mm without a word. A decimal comma ('1,5', read as two numbers) was asked
    again with 'expected Δx [mm]', not saying the comma was the trouble."""
    answers = iter(["1_0", "1,5", "1.5"])
    prompts = []

    def ask(p):
        prompts.append(p)
        return next(answers)

    t = manual_trial("00", "10", 1.0, 2.0, ask=ask)
    assert t is not None and t.dx == 1.5
    assert "not a number ('1_0')" in prompts[1]
    assert "a decimal point is '.'" in prompts[2] and "'1,5'" in prompts[2]


def test_planar_delta_is_in_the_start_frame():
    dx, dy, dth = planar_delta((10.0, 0.0, 90.0), (10.0, 5.0, 100.0))
    assert dx == pytest.approx(5.0) and dy == pytest.approx(0.0, abs=1e-12) and dth == pytest.approx(10.0)
    assert planar_delta((0.0, None, None), (3.0, None, None)) == (3.0, None, None)


def test_the_documented_example_tracker_file_reads():
    track = read_track(ROOT / "docs" / "examples" / "tracker-example.csv")
    assert track.y is not None and track.theta_deg is not None and len(track.t) >= 10


def test_a_bad_tracker_file_names_the_line(tmp_path):
    p = tmp_path / "t.csv"
    p.write_text("time,x,y,theta\n0,0,0,0\n0.1,abc,0,0\n")
    with pytest.raises(TrackerError, match="line 3, column x"):
        read_track(p)


def test_a_track_along_x_may_say_so_in_its_header(tmp_path):
    """Rows may give time,x alone; the header had to name y and theta all the same."""
    p = tmp_path / "t.csv"
    p.write_text("time,x\n0,0\n0.1,1.5\n")
    track = read_track(p)
    assert track.x.tolist() == [0.0, 1.5] and track.y is None and track.theta_deg is None


@pytest.mark.parametrize("text, message", [
    ("# c\n\n# c\ntime,x,y,theta\n0,0,0,0\n0.1,abc,0,0\n", r"t\.csv: line 6, column x: expected a number, got 'abc'"),
    ("# c\n# c\ntime,y\n0,0\n", r"t\.csv: line 3: expected the header time,x,y,theta \(or time,x or time,x,y\), "
                                  r"got 'time,y'"),
    # a fifth column passed the header and failed every row after it
    ("time,x,y,theta,z\n0,0,0,0,0\n", r"t\.csv: line 1: expected the header .*got 'time,x,y,theta,z'"),
    ("time,x\n0,0\n0.1,1,2\n", r"t\.csv: line 3: expected time,x as the header says, got '0.1,1,2'"),
    ("time,x,y,theta\n0,0,,\n0.1,1_0,,\n", r"t\.csv: line 3, column x: expected a number, got '1_0'"),
    ("# c\ntime,x,y,theta\n0,0,0,0\n0.1,1e308,0,0\n", r"t\.csv: line 4, column x: expected a finite number within ±1e9"),
    ("# c\ntime,x,y,theta\n0,0,0,0\n# caf\xe9\n", r"t\.csv: line 4: expected UTF-8 text, got byte 0xe9"),
    # these named neither line nor column
    ("time,x,y,theta\n0,0,,\n# c\n0.2,1,,\n0.1,2,,\n",
     r"t\.csv: line 5, column time: expected a time after the previous row's 0\.2 s \(strictly increasing\), got 0\.1"),
    ("time,x,y,theta\n0,0,1,\n0.1,1,,\n", r"t\.csv: line 3, column y: empty, but given on line 2"),
    ("time,x,y,theta\n0,0,,\n", r"t\.csv: expected at least two rows of time,x\[,y\[,theta\]\] after the header, got 1"),
])
def test_tracker_errors_name_the_line_an_editor_shows(tmp_path, text, message):
    """Comment lines were not counted (a bad cell on line 6 was "row 4"), the header error
    always said line 1, and a file that is not UTF-8 was a traceback."""
    p = tmp_path / "t.csv"
    p.write_bytes(text.encode("latin-1"))
    with pytest.raises(TrackerError, match=message):
        read_track(p)


_GOOD = {"from": "00", "to": "10", "t_start": 0.5, "t_end": 1.0, "dx": 4.0, "dy": None, "dtheta_deg": None,
         "source": "sim"}


@pytest.mark.parametrize("line, message", [
    (b"[1, 2, 3]", r"expected a trial record \(a JSON object with from, to, t_start, t_end, dx…\), got '\[1, 2, 3\]'"),
    (json.dumps({k: v for k, v in _GOOD.items() if k != "to"}).encode(), r"to: missing \(expected a state label\)$"),
    (json.dumps({**_GOOD, "to": 2}).encode(), r"to: expected a state label \(a string\), got 2$"),
    (json.dumps({**_GOOD, "dx": "4"}).encode(), r"dx: expected a number within ±1e9 or null, got '4'$"),
    (json.dumps({**_GOOD, "dx": 1e308}).encode(), r"dx: expected a number within ±1e9 or null, got 1e\+308$"),
    (json.dumps({**_GOOD, "t_end": True}).encode(), r"t_end: expected a number within ±1e9, got True$"),
    (json.dumps({**_GOOD, "source": "magic"}).encode(), r"source: expected one of sim, tracker, manual, got 'magic'$"),
    (json.dumps({**_GOOD, "source": "caf\u00e9"}, ensure_ascii=False).encode("latin-1"), r"expected UTF-8 text, got byte 0xe9 at column"),
    (json.dumps({**_GOOD, "to": "00"}).encode(), r"from/to: 00->00 is not one of the robot's allowed transitions"),
])
def test_every_bad_trial_line_is_one_error_naming_the_file_line_and_field(tmp_path, line, message):
    """These were accepted (a string dx, an unknown source), dropped (a self transition), a
    traceback (dx 1e308) or an error without its file and line (not UTF-8) or field."""
    p = tmp_path / "log.jsonl"
    p.write_bytes(b'{"trial_log": 1, "robot": "paper-r1"}\n' + line + b"\n" + _trial(1).to_json().encode() + b"\n")
    t = load_robot(ROOT / "robots" / "paper-r1.toml").transitions
    pairs = list(zip(map(t.label, t.src), map(t.label, t.dst)))
    with pytest.raises(TrialLogError, match=rf"^{p}:2: {message}"):
        TrialLog(p, append=False, robot="paper-r1", states=t.labels(), transitions=pairs)


def test_a_log_of_another_format_version_is_refused(tmp_path):
    p = tmp_path / "log.jsonl"
    p.write_text('{"trial_log": 99, "robot": "paper-r1"}\n' + _trial(0).to_json() + "\n")
    with pytest.raises(TrialLogError, match=rf"^{p}:1: trial_log: expected 1 \(the format this proleg reads\), got 99$"):
        TrialLog(p, append=False)


def _synthetic(offset: float, seed: int):
    """Firmware state-reached events and a tracker that saw the motion ``offset`` s later."""
    rng = np.random.default_rng(seed)
    t, events, step = 0.0, [], []
    for k in range(30):
        t += rng.uniform(0.6, 1.2) + (3.0 if k % 6 == 5 else 0.0)  # pieces with rests
        events.append(t)
        step.append(rng.normal(4.0, 1.0) * (1 if k % 2 else -0.5))
    tt = np.arange(-2.0, t + 3.0, 1 / 30) + offset  # 30 fps camera on its own clock
    x = np.zeros_like(tt)
    for te, dx in zip(events, step):  # motion during the 0.4 s before the state is reached
        x += dx * np.clip((tt - offset - (te - 0.4)) / 0.4, 0, 1)
    x += rng.normal(0, 0.05, len(tt))
    return events, step, Track(tt, x, np.zeros_like(tt), np.zeros_like(tt))


@pytest.mark.parametrize("offset", [-7.3, 0.0, 12.62])
def test_the_tracker_clock_offset_is_recovered_from_a_shifted_track(offset):
    events, step, track = _synthetic(offset, seed=int(abs(offset) * 10))
    est = estimate_offset(track, events, max_offset_s=20.0)
    assert est == pytest.approx(offset, abs=0.05)
    reached = [(t, "10" if k % 2 else "00") for k, t in enumerate(events)]
    trials = trials_from_events(reached, TrackerSource(track, est))
    assert np.allclose([tr.dx for tr in trials], step[1:], atol=0.3)


def test_a_trial_keeps_when_its_new_state_was_seen_and_old_logs_still_read(tmp_path):
    seen = Trial("00", "10", 1.0, 2.0, 4.0, None, None, "sim", 1.4)
    assert Trial.from_json(seen.to_json()) == seen and seen.t_moved == 1.4
    old = Trial.from_json('{"from": "00", "to": "10", "t_start": 1, "t_end": 2, "dx": 4, "source": "sim"}')
    assert old.t_seen is None and old.t_moved == 2.0 and "t_seen" not in old.to_json()


def test_the_offset_is_right_though_a_cooling_limb_is_confirmed_late():
    """Motion ends when the new state is seen; STATE_REACHED follows 0.03 s later for a
    rising limb, 0.4–0.6 s for a cooling one (it settles slowly), more than the 0.5 s the
    estimator once allowed before an event. From the seen times the offset is right; from
    the events it is not (why a trial keeps ``t_seen``)."""
    rng = np.random.default_rng(3)
    t, seen, step = 0.0, [], []
    for k in range(24):
        t += rng.uniform(0.8, 1.4) + (3.0 if k % 6 == 5 else 0.0)
        seen.append(t)
        step.append(4.0 if k % 2 else -4.0)
    late = np.array([0.03 if k % 2 else rng.uniform(0.4, 0.6) for k in range(len(seen))])
    offset = 5.0
    tt = np.arange(-2.0, t + 3.0, 1 / 30) + offset
    x = np.zeros_like(tt)
    for ts, dx in zip(seen, step):
        x += dx * ((tt - offset) >= ts)
    track = Track(tt, x)
    assert estimate_offset(track, seen) == pytest.approx(offset, abs=0.03)
    assert abs(estimate_offset(track, np.array(seen) + late) - offset) > 0.1


def test_a_tracker_csv_saved_with_a_bom_reads_as_without_one(tmp_path):
    """Excel's "CSV UTF-8" starts the file with a BOM: the header read as '\\ufefftime'."""
    from proleg.learn.tracker import read_track

    body = "time,x,y,theta\n0.0,0.0,0.0,0.0\n0.1,0.5,0.0,0.0\n"
    plain, bom = tmp_path / "plain.csv", tmp_path / "bom.csv"
    plain.write_text(body, encoding="utf-8")
    bom.write_bytes(b"\xef\xbb\xbf" + body.encode("utf-8"))
    a, b = read_track(plain), read_track(bom)
    assert list(a.t) == list(b.t) and list(a.x) == list(b.x)
