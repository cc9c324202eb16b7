"""Consumers of the decoded-message stream, python-can style.

``Notifier(client, listeners)`` runs one thread that calls ``client.recv_received`` and hands
every message to each ``Listener``: ``Printer`` (one line per telemetry frame), ``BufferedReader``
(a queue for tests and scripts), the recording writers (``proleg.record.Logger``), the console (``proleg.console``). None of
them knows which link the messages came over.
"""

from __future__ import annotations

import queue
import sys
import threading
from abc import ABC, abstractmethod
from collections.abc import Callable, Iterable
from typing import TextIO

from ..errors import LinkError
from ..protocol.definition import EventKind, FaultCode, Flag
from .client import Received, RobotClient
from .direction import direction_text


class Listener(ABC):
    @abstractmethod
    def on_message(self, rx: Received) -> None:
        """Called for every message, in order, from the Notifier's thread."""

    def on_error(self, exc: Exception) -> None:
        """The Notifier stopped because the link failed."""

    def stop(self) -> None:
        """Flush and release resources."""


class CallbackListener(Listener):
    def __init__(self, callback: Callable[[Received], None], on_error: Callable[[Exception], None] | None = None):
        self._callback = callback
        self._on_error = on_error

    def on_message(self, rx: Received) -> None:
        self._callback(rx)

    def on_error(self, exc: Exception) -> None:
        if self._on_error is not None:
            self._on_error(exc)


class BufferedReader(Listener):
    """Keeps messages for ``get_message(timeout)`` (wall-clock timeout)."""

    def __init__(self, names: Iterable[str] | None = None):
        self._q: queue.Queue[Received] = queue.Queue()
        self._names = None if names is None else frozenset(names)
        self.error: Exception | None = None

    def on_message(self, rx: Received) -> None:
        if self._names is None or rx.message.name in self._names:
            self._q.put(rx)

    def on_error(self, exc: Exception) -> None:
        self.error = exc

    def get_message(self, timeout: float = 0.5) -> Received | None:
        try:
            return self._q.get(timeout=timeout)
        except queue.Empty:
            return None


def format_message(rx: Received, labels: Callable[[int], str] | None = None) -> str:
    """One line for a message (telemetry: time, states, step, flags, ψ in degrees, duty in %)."""
    m = rx.message
    f = m.fields
    if m.name == "TELEMETRY":
        lab = labels or str
        psi = " ".join(f"{p / 100:7.2f}" for p in f["psi"])
        duty = " ".join(f"{d / 100:5.1f}" for d in f["duty"])
        flags = _flag_names(f["flags"])
        line = (f"{f['time_ms'] / 1000:9.3f} seq={f['seq']:5d} state={lab(f['measured'])}"
                f" target={lab(f['target'])} gait={f['gait']} {direction_text(f['direction'])} step={f['step']}"
                f" psi=[{psi}] duty%=[{duty}] flags={flags}")
        if "displacement_mm" in rx.truth:
            line += f" x={rx.truth['displacement_mm']:.1f}mm"
        temps = [v for k, v in rx.truth.items() if k.startswith("temp_")]  # simulated coils, °C
        if temps:
            line += " coil_c=[" + " ".join(f"{t:.0f}" for t in temps) + "]"
        return line
    if m.name == "EVENT":
        try:
            kind = EventKind(f["kind"]).name
        except ValueError:
            kind = str(f["kind"])
        return f"{f['time_ms'] / 1000:9.3f} EVENT {kind} code={f['code']} detail={f['detail']}"
    return f"{'':9s} {m.name} " + " ".join(f"{k}={v}" for k, v in f.items())


def _flag_names(flags: int) -> str:
    names = [fl.name for fl in Flag if fl & flags and fl.name]
    return "|".join(n.lower() for n in names) or "-"


class Printer(Listener):
    """Prints one line per message (``telemetry_only``: TELEMETRY lines only), flushed."""

    def __init__(self, out: TextIO | None = None, *, telemetry_only: bool = False,
                 labels: Callable[[int], str] | None = None):
        self.out = out or sys.stdout
        self.telemetry_only = telemetry_only
        self.labels = labels
        self.closed = False

    def on_message(self, rx: Received) -> None:
        if self.telemetry_only and rx.message.name != "TELEMETRY":
            return
        if self.closed:
            return
        try:
            self.out.write(format_message(rx, self.labels) + "\n")
            self.out.flush()
        except BrokenPipeError:  # the reader went away (`proleg console --plain | head`)
            self.closed = True


class Notifier:
    """Pumps ``client``'s message stream into listeners on a background thread."""

    def __init__(self, client: RobotClient, listeners: Iterable[Listener] = (), *, poll_s: float = 0.05):
        self.client = client
        self.listeners: list[Listener] = list(listeners)
        self.poll_s = poll_s
        self.error: Exception | None = None
        self._lock = threading.Lock()
        self._running = True
        self._thread = threading.Thread(target=self._run, name="proleg-notifier", daemon=True)
        self._thread.start()

    def add_listener(self, listener: Listener) -> None:
        with self._lock:
            self.listeners.append(listener)

    def remove_listener(self, listener: Listener) -> None:
        with self._lock:
            self.listeners.remove(listener)

    @property
    def running(self) -> bool:
        return self._thread.is_alive()

    def _run(self) -> None:
        try:
            while self._running:
                rx = self.client.recv_received(self.poll_s)
                if rx is None:
                    continue
                with self._lock:
                    listeners = list(self.listeners)
                for listener in listeners:
                    listener.on_message(rx)
        except LinkError as e:
            self.error = e
            with self._lock:
                listeners = list(self.listeners)
            for listener in listeners:
                listener.on_error(e)

    def stop(self, timeout: float = 5.0, keep: Iterable[Listener] = ()) -> None:
        """Stop the thread, then stop every listener (flushing recorders) but those in ``keep``,
        which the caller still feeds and stops (the console's recording, through its leaving STOP)."""
        self._running = False
        if threading.current_thread() is not self._thread:
            self._thread.join(timeout)
        kept = {id(listener) for listener in keep}
        with self._lock:
            listeners = [listener for listener in self.listeners if id(listener) not in kept]
        for listener in listeners:
            listener.stop()


class FaultWatch(Listener):
    """Remembers whether the robot faulted while it listened: a FAULT event, or telemetry
    with a latched fault (one latched before the listening began shows only there).
    ``first``: the first fault event's code name, or "latched" when only telemetry said so."""

    def __init__(self) -> None:
        self.first: str | None = None

    def on_message(self, rx: Received) -> None:
        m = rx.message
        if self.first is not None:
            return
        if m.name == "EVENT" and m.fields["kind"] == EventKind.FAULT:
            code = m.fields["code"]
            self.first = FaultCode(code).name if code in FaultCode._value2member_map_ else f"fault {code}"
        elif m.name == "TELEMETRY" and m.fields["flags"] & Flag.FAULT:
            self.first = "latched"
