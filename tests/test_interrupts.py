"""proleg.interrupts: while held, a Ctrl-C inside a deferred() block is raised once, after it."""

from __future__ import annotations

import os
import signal
import threading

import pytest
from proleg import interrupts
from proleg.interrupts import deferred


@pytest.fixture
def held():
    """Python's own SIGINT handler (a worker started in the background ignores SIGINT), held."""
    old = signal.signal(signal.SIGINT, signal.default_int_handler)
    interrupts.hold()
    yield
    interrupts.release()
    signal.signal(signal.SIGINT, old)


def _ctrl_c() -> None:
    os.kill(os.getpid(), signal.SIGINT)


def test_a_ctrl_c_inside_the_block_is_raised_once_after_it(held):
    done = []
    with pytest.raises(KeyboardInterrupt):
        with deferred():
            _ctrl_c()
            _ctrl_c()
            done.append("the rest of the block")
    assert done == ["the rest of the block"]
    with deferred():  # nothing pending afterwards
        pass
    with pytest.raises(KeyboardInterrupt):
        _ctrl_c()  # and outside a block, at once


def test_the_ctrl_c_wins_over_an_error_of_the_block(held):
    with pytest.raises(KeyboardInterrupt) as e:
        with deferred():
            _ctrl_c()
            raise OSError("disk full")
    assert isinstance(e.value.__context__, OSError)


def test_the_last_release_gives_python_its_handler_back():
    old = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        interrupts.hold()
        interrupts.hold()
        interrupts.release()
        assert signal.getsignal(signal.SIGINT) is not signal.default_int_handler  # one holder left
        interrupts.release()
        assert signal.getsignal(signal.SIGINT) is signal.default_int_handler
        with deferred(), pytest.raises(KeyboardInterrupt):  # not held: at once, as Python does
            _ctrl_c()
    finally:
        signal.signal(signal.SIGINT, old)


def test_an_ignored_sigint_stays_ignored_and_another_handler_is_left_alone():
    old = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        interrupts.hold()
        assert signal.getsignal(signal.SIGINT) is signal.SIG_IGN
        interrupts.release()
        seen = []
        signal.signal(signal.SIGINT, lambda *_: seen.append(1))
        interrupts.hold()
        with deferred():
            _ctrl_c()
        interrupts.release()
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
