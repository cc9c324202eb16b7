"""Replanning in the console: a limb lost while the console watches is carried on, as in
``proleg run`` (``proleg.learn.replan.Replanner``: mark what needs the lost actuator
forbidden, compute the best gait of what is left, SET_ACTUATOR_MAP, LOAD_GAIT, CLEAR, START).

The console's messages arrive on the ``Notifier``'s thread, and a request sent from there
would wait for its own reply on the thread that should hand it over. So ``ReplanWorker``
is a listener that only records (``Replanner.on_message``) and, once the replanner is due,
wakes its own thread, which sends the commands; the Notifier goes on reading meanwhile and
hands each reply to it. ``say`` gets one line per step, naming the actuator and the states.
"""

from __future__ import annotations

import threading
from collections.abc import Callable

from ..learn.replan import Replanner
from ..link.client import Received, RobotClient
from ..link.listeners import Listener
from ..robot import Robot


class ReplanWorker(Listener):
    """Carry a gait on after an actuator loss, off the Notifier's thread (module doc)."""

    def __init__(self, robot: Robot, client: RobotClient, say: Callable[[str], None]):
        self.replanner = Replanner(robot, client, None, say=say)
        self._say = say
        self._wake = threading.Event()
        self._running = True
        self._thread = threading.Thread(target=self._run, name="proleg-replan", daemon=True)
        self._thread.start()

    @property
    def actions(self) -> list[str]:
        return self.replanner.actions

    def on_message(self, rx: Received) -> None:
        self.replanner.on_message(rx)
        if self.replanner.due():
            self._wake.set()

    def _run(self) -> None:
        while self._running:
            if not self._wake.wait(0.5):
                continue
            self._wake.clear()
            if not self._running:
                return
            try:
                self.replanner.poll()  # tells LinkErrors of its commands itself
            except Exception as e:  # noqa: BLE001 — a worker thread must not die silently
                self._say(f"replanning failed: {e}")

    def stop(self) -> None:
        self._running = False
        self._wake.set()
        if threading.current_thread() is not self._thread:
            self._thread.join(5.0)
