"""``proleg learn`` when the trial log's disk fills: the log was left with half a trial at its end
and the command said only "cannot write: No space left on device", naming no file and nothing kept."""

from __future__ import annotations

import errno
import os

from build_checks import R1, cli
from proleg.learn import measure
from proleg.learn.measure import Trial, TrialLog


def _trial(k: int) -> Trial:
    return Trial("00", "10", k * 1.0, k * 1.0 + 0.5, 4.0 + k, None, None, "sim")


def test_a_trial_that_does_not_fit_is_cut_back_and_the_log_named(tmp_path, monkeypatch):
    p = tmp_path / "log.jsonl"
    log = TrialLog(p)
    log.append(_trial(0))
    real = os.fsync

    def full(fd):  # the write went half way (the page cache took it); the disk says no at the sync
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(measure.os, "fsync", full)
    try:
        log.append(_trial(1))
        raise AssertionError("no error")  # pragma: no cover
    except OSError as e:
        assert e.errno == errno.ENOSPC and e.filename == str(p)
    monkeypatch.setattr(measure.os, "fsync", real)
    assert p.read_text().endswith("\n") and [t.dx for t in TrialLog(p).trials] == [4.0]


def test_learn_on_a_full_disk_names_the_log_and_what_it_kept(tmp_path, capsys, monkeypatch):
    real = TrialLog.append

    def append(self, trial):
        if len(self.trials) >= 5:
            raise OSError(errno.ENOSPC, "No space left on device")
        real(self, trial)

    monkeypatch.setattr(TrialLog, "append", append)
    log = tmp_path / "trials.jsonl"
    code, _, err = cli(capsys, "learn", R1, "--sim", "--plant", "table", "--log", log, "--repeats", "3", "-q")
    assert code == 1
    assert err == (f"proleg: error: learn: cannot write trial log {log}: No space left on device (it keeps "
                   "the 5 trials recorded before, whole; the robot was stopped; make room and run the same "
                   "command to resume)\n")
    assert len(TrialLog(log).trials) == 5


def test_learn_whose_link_is_lost_says_the_trials_are_kept(tmp_path, capsys, monkeypatch):
    """A cable pulled mid-learn ended with the link's error alone: nothing said the trials so far
    were kept and that the same command resumes."""
    from proleg.errors import LinkError
    from proleg.link import sim_link

    real_read = sim_link.SimLink.read

    def read(self, timeout):
        if self.board.time_s > 12.0:
            raise LinkError("sim paper-r1: device disconnected and not back within 10 s")
        return real_read(self, timeout)

    monkeypatch.setattr(sim_link.SimLink, "read", read)
    log = tmp_path / "trials.jsonl"
    code, _, err = cli(capsys, "learn", R1, "--sim", "--plant", "table", "--log", log, "--repeats", "3", "-q")
    n = len(TrialLog(log).trials)
    assert code == 1 and n > 0
    assert err == (f"proleg: error: learn: sim paper-r1: device disconnected and not back within 10 s ({log} keeps "
                   f"the {n} trials recorded; run the same command to resume)\n")
