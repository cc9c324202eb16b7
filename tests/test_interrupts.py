"""proleg.interrupts: while held, a Ctrl-C inside a deferred() block is raised once, after it."""

from __future__ import annotations

import os
import signal
import threading
from pathlib import Path

import pytest
from proleg import interrupts
from proleg.interrupts import deferred


@pytest.fixture(autouse=True)
def nothing_held(monkeypatch):
    """Each test starts from a process nobody holds: the module's state is the process's, and an
    earlier test in the same worker may have left it otherwise (an in-process ``proleg`` run in
    a worker that ignores SIGINT takes SIGTERM/SIGHUP as Ctrl-C for the whole process,
    ``cli.main._catch_termination``; a writer a test never stopped still holds). Put back after."""
    for name, value in (("_holders", 0), ("_inside", False), ("_caught", False), ("_terminations", False)):
        monkeypatch.setattr(interrupts, name, value)


@pytest.fixture
def python_handler():
    """Python's own SIGINT handler, as a terminal's Ctrl-C finds it (a worker started in the
    background ignores SIGINT); the test's handler put back after it."""
    old = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, old)


@pytest.fixture
def held(python_handler):
    """Python's own handler, held."""
    interrupts.hold()
    yield
    interrupts.release()


def _ctrl_c() -> None:
    os.kill(os.getpid(), signal.SIGINT)


def test_a_ctrl_c_inside_the_block_is_raised_once_after_it(held):
    done = []
    with pytest.raises(KeyboardInterrupt):
        with deferred():
            _ctrl_c()
            done.append("the rest of the block")
    assert done == ["the rest of the block"]
    with deferred():  # nothing pending afterwards
        pass
    with pytest.raises(KeyboardInterrupt):
        _ctrl_c()  # and outside a block, at once


def test_a_second_ctrl_c_inside_the_block_is_raised_at_once(held):
    """A write that blocks (a stalled pipe, a hung mount) must not keep the user from
    stopping the robot: the second Ctrl-C does not wait for the block."""
    done = []
    with pytest.raises(KeyboardInterrupt):
        with deferred():
            _ctrl_c()
            done.append("after the first")
            _ctrl_c()
            done.append("after the second")
    assert done == ["after the first"]
    with deferred():  # nothing left pending
        pass


def test_the_ctrl_c_wins_over_an_error_of_the_block(held):
    with pytest.raises(KeyboardInterrupt) as e:
        with deferred():
            _ctrl_c()
            raise OSError("disk full")
    assert isinstance(e.value.__context__, OSError)


def test_the_last_release_gives_python_its_handler_back(python_handler):
    assert interrupts.hold() and interrupts.hold()
    interrupts.release()
    assert signal.getsignal(signal.SIGINT) is not signal.default_int_handler  # one holder left
    interrupts.release()
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler
    with deferred(), pytest.raises(KeyboardInterrupt):  # not held: at once, as Python does
        _ctrl_c()


def test_an_ignored_sigint_stays_ignored_and_another_handler_is_left_alone():
    old = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        assert not interrupts.hold()  # nothing to release
        assert signal.getsignal(signal.SIGINT) is signal.SIG_IGN
        seen = []
        signal.signal(signal.SIGINT, lambda *_: seen.append(1))
        assert not interrupts.hold()
        with deferred():
            _ctrl_c()
        assert seen == [1]
    finally:
        signal.signal(signal.SIGINT, old)


def test_off_the_main_thread_a_block_defers_nothing(held):
    raised = []

    def body():  # a Notifier thread writing a row: a Ctrl-C is the main thread's, not its
        try:
            with deferred():
                _ctrl_c()
        except KeyboardInterrupt:
            raised.append("in the thread")

    t = threading.Thread(target=body)
    with pytest.raises(KeyboardInterrupt):
        t.start()
        t.join()
        for _ in range(1000):  # the main thread's handler runs at its next bytecode
            pass
    t.join()
    assert raised == []


def test_a_writer_that_fails_on_a_notifier_thread_gives_the_handler_back_when_stopped(tmp_path, python_handler):
    """The console's Notifier thread writes the rows: a full disk stops the writer there, and
    its hold is still let go, once, so Python's handler comes back."""
    from proleg.record import Logger, RecordingMeta
    from proleg.robot import load_robot

    robot = load_robot(Path(__file__).resolve().parents[1] / "robots" / "paper-r1.toml")
    writer = Logger(tmp_path / "run.jsonl", RecordingMeta.for_robot(robot=robot))
    assert signal.getsignal(signal.SIGINT) is not signal.default_int_handler  # held

    def full(row):
        raise OSError(28, "No space left on device")

    t = threading.Thread(target=writer._guard, args=(full, {}))
    t.start()
    t.join()
    assert writer.error is not None
    writer.stop()  # the main thread's stop, as the console's finally does
    writer.stop()
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler
    with deferred(), pytest.raises(KeyboardInterrupt):  # nobody holds: at once
        _ctrl_c()


def test_whole_holds_by_itself_and_gives_python_its_handler_back(python_handler):
    """whole() needs no holder around it (a writer being opened has not held yet)."""
    done = []
    with pytest.raises(KeyboardInterrupt):
        with interrupts.whole():
            _ctrl_c()
            done.append("the rest of the block")
    assert done == ["the rest of the block"]
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler
    with interrupts.whole():  # nothing pending afterwards
        pass
