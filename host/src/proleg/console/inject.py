"""Faults injected into a simulated robot while the console watches it (``proleg console
--sim ROBOT --inject dead-actuator:sma-right+10``), to see what the firmware and the
console do about them. ``FAULT`` names are the simulator's (``proleg.sim.closed_loop.FAULTS``);
``+T``: T seconds of simulated time after the console started (default: at once); a ``+``
followed by anything but a number belongs to the name (a limb called ``front+pad``), and so does
one followed by a number when the whole spec names a fault the robot has (a limb called ``leg+2``;
``dead-actuator:leg+2+5`` injects it at 5 s).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import Any

from ..errors import SimError
from ..link.client import Received
from ..link.listeners import Listener


def parse_injection(spec: str, run_s: float | None = None,
                    names_fault: Callable[[str], bool] | None = None) -> tuple[float, str]:
    """``FAULT[+T]`` → (T seconds, FAULT); ``SimError`` naming the spec when the fault is
    unknown, T is no finite number ≥ 0, or T is after the run ends (``run_s``, the
    ``--duration``; None: no end), where the fault would never be injected.
    ``names_fault(spec)``: whether the whole spec is a fault of the robot's (its limb or coil
    name ends in ``+`` and a number); then it is that fault, at once."""
    from ..sim.closed_loop import FAULTS, split_fault

    if names_fault is not None and "+" in spec and names_fault(spec):
        return 0.0, spec
    fault, plus, at = spec.rpartition("+")
    t = 0.0
    if plus and not at.strip():
        raise SimError(f"--inject {spec}: no time after '+' (expected FAULT+T, T seconds after the start)")
    if plus and not _number(at):
        fault, plus = spec, ""  # a '+' inside a limb's or coil's name ("front+pad"), no time
    if not plus:
        fault = spec
    else:
        t = float(at)
        if not (t >= 0 and math.isfinite(t)):
            raise SimError(f"--inject {spec}: the time after '+' must be a finite number ≥ 0 s, got {at!r}")
    if split_fault(fault)[0] not in FAULTS:
        raise SimError(f"--inject {spec}: unknown fault (expected one of: {', '.join(sorted(FAULTS))})")
    if run_s is not None and t > run_s:
        # .15g, not g: 5.0000001 was shown as "5 s is after the run ends (--duration 5 s)"
        raise SimError(f"--inject {spec}: {t:.15g} s is after the run ends (--duration {run_s:.15g} s), so it would "
                       f"never be injected; expected a time in [0, {run_s:.15g}] s")
    return t, fault


def fault_checker(check: Callable[[str], None]) -> Callable[[str], bool]:
    """``names_fault`` for ``parse_injection`` from a simulated robot's ``check_fault``."""
    def names_fault(spec: str) -> bool:
        try:
            check(spec)
        except SimError:
            return False
        return True

    return names_fault


def _number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


class Injector(Listener):
    """Injects each ``(at_s, fault)`` into ``sim`` (a ``SimulatedRobot``) once its clock has run
    ``at_s`` past where it stood at construction; ``say`` tells each injection."""

    def __init__(self, sim, faults: Sequence[tuple[float, str]], say: Callable[[str], None] = print,
                 marks: Sequence[Any] = ()):
        self.sim = sim
        self.t0 = float(sim.time_s)
        self.due = sorted(faults)
        self.say = say
        self.marks = marks  # listeners whose ``mark`` records each injection (the recorder: INJECT rows)

    def on_message(self, rx: Received) -> None:
        now = float(self.sim.time_s)
        while self.due and now - self.t0 >= self.due[0][0]:
            at, fault = self.due.pop(0)
            self.sim.inject(fault)
            for listener in self.marks:  # as proleg sim does: the recording's INJECT row, the plot's marker
                mark = getattr(listener, "mark", None)
                if callable(mark):
                    mark(rx.time, now, fault)
            self.say(f"injected {fault} at {now:.1f} s (simulated)")
