"""``proleg.interrupts.in_workers``: a command's work in forked worker processes (``proleg
check --jobs``, ``--measure-matrix --hold-range --jobs``, the benches), in order; a worker
that dies is said (``WorkerLost``, exit 1), where ``multiprocessing.Pool`` waited for its lost
answer for ever."""

from __future__ import annotations

import os
import signal
from concurrent.futures import ThreadPoolExecutor

import pytest
from build_checks import cli

from proleg.errors import WorkerLost
from proleg.interrupts import in_workers

R1 = "paper-r1"


def _square_or_die(x: int) -> int:
    if x == 3:
        os.kill(os.getpid(), signal.SIGKILL)  # the system's OOM killer, or a kill -9
    return x * x


def _within(seconds: float, fn):
    """``fn()``'s result, or a failure after ``seconds`` (the bug was a wait for ever)."""
    with ThreadPoolExecutor(1) as ex:
        return ex.submit(fn).result(timeout=seconds)


def test_the_results_come_in_order():
    assert _within(60, lambda: list(in_workers(_square_or_die, [5, 1, 4, 2, 0], 2))) == [25, 1, 16, 4, 0]


def test_a_worker_that_dies_is_said_and_not_waited_for():
    def run():
        with pytest.raises(WorkerLost, match="a worker process died while squaring"):
            list(in_workers(_square_or_die, [1, 2, 3, 4], 2, "squaring"))
        return True

    assert _within(60, run)


def _killed_on_a_drawn_row(job):
    from proleg.cli import check

    if job[1]:  # a drawn row's conditions (row 0, the nominal one, has none)
        os.kill(os.getpid(), signal.SIGKILL)
    return check._work.__wrapped__(job)


def test_a_check_whose_worker_is_killed_exits_1_naming_it(capsys, monkeypatch):
    from proleg.cli import check

    _killed_on_a_drawn_row.__wrapped__ = check._work
    monkeypatch.setattr(check, "_work", _killed_on_a_drawn_row)
    code, out, err = _within(300, lambda: cli(capsys, "check", R1, "--rows", "2", "--jobs", "2"))
    assert code == 1 and out == ""
    assert "proleg: error: a worker process died while running the check's rows" in err
