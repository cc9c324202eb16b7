"""The robot file's ``[safety]`` and ``[control]`` tables: the safety envelope the firmware
enforces (``Safety``, docs/safety.md) and the control settings it runs with (``Control``).
``_safety`` and ``_control`` (called by ``proleg.robot.robot_from_dict``) check every key
against its range, and the control's duties against the safety envelope; a bad value raises
RobotFileError naming the file and the key, never clamped. Re-exported by ``proleg.robot``."""

from __future__ import annotations

import math

from dataclasses import dataclass
from pathlib import Path
from typing import Any

from .names import counted
from .robot_climb import ClimbLimit, climb_limit
from .robot_fields import Fields

#: ``[safety] min_cooldown_ms`` is at most this many ``max_on_ms`` (sma.c's pay-back rate,
#: max_on/min_cooldown in steps of 1/256, must not round to 0; SET_PARAM refuses the same).
MAX_COOLDOWN_PER_ON = 255

#: The most on-limit hits that may latch: the guard counts them in a byte and, in the tick it
#: reaches the limit, up to 8 coils may hit at once (core/safety.c asserts the same).
MAX_ON_LIMIT_LATCH = 255 - 8
#: The mean-duty window's range (ms; docs/safety.md: kept as 8 slots of a window / 8).
DUTY_WINDOW_MS_RANGE = (8, 600_000)

#: The shortest link watchdog a robot file may set (0 turns it off): the host's heartbeat
#: comes every quarter of it (``proleg.link.stream.WATCHDOG_SHARE``).
MIN_LINK_WATCHDOG_MS = 100


@dataclass(frozen=True)
class Safety:
    max_on_ms: int = 3000
    min_cooldown_ms: int = 800
    max_duty: float = 0.8
    state_timeout_ms: int = 8000
    link_watchdog_ms: int = 2000  # on by default: a host that goes away stops the robot (docs/safety.md)
    #: the thermal budget (docs/safety.md): a duty at or below hold_max_duty is holding, never
    #: on-time (None: max(0.3, control.hold_duty)); the mean duty over any duty_window_ms is at
    #: most max_mean_duty; on_limit_latch on-limit hits without progress latch SMA_ON_LIMIT.
    #: 0.45: held for ever the paper robots' coils settle at 115 °C, 5 K under the 120 °C that
    #: wears NiTi out (materials.NITI_OVERHEAT_C); 0.5 settled at 125 °C, and a host flicking a
    #: held limb's threshold kept a coil there without a fault (docs/safety.md, "Keys")
    hold_max_duty: float | None = None
    max_mean_duty: float = 0.45
    duty_window_ms: int = 10_000
    on_limit_latch: int = 3
    #: opt-in (docs/safety.md, "The coil's heat ceiling"): the firmware smooths each coil's duty
    #: with the coil's thermal time constant and gives a coil whose smoothed duty reached
    #: max_mean_duty at most max_mean_duty, whatever STOP, START or SET_PARAM did in between.
    #: It takes every coil for the nominal one: a weak coil (low supply, mismatch, draught) that
    #: walked may stop with STATE_TIMEOUT. False: none of its code is built in.
    coil_heat_ceiling: bool = False

    @property
    def mean_ceiling(self) -> float:
        """The most a duty held for ever may be: it fits the mean-duty window and max_duty."""
        return min(self.max_mean_duty, self.max_duty)

    def hold_ceiling(self, hold_duty: float) -> float:
        """``hold_max_duty``, or its default: max(0.3, the control's hold duty), at most
        ``mean_ceiling`` (a duty the coil may hold forever fits the window)."""
        if self.hold_max_duty is not None:
            return self.hold_max_duty
        return min(self.mean_ceiling, max(0.3, hold_duty))


#: control.boost_ms: 0 (off) or this range. Below 100 ms a coil still heating back to As (its
#: dead time, 0.15-0.6 s) would count as lagging at every rise; at or above the stall
#: detector's 5 s (CTL_STALL_MS) the limb is cut off as "cannot reach" first.
BOOST_MIN_MS = 100
BOOST_MAX_MS = 4000
#: the default where the body leaves the boost safe (robot_reach.boost_ms_of; docs/control.md, "The boost")
BOOST_DEFAULT_MS = 700


@dataclass(frozen=True)
class Control:
    tick_hz: int = 1000
    drive_duty: float = 0.6
    hold_duty: float = 0.25
    debounce_ticks: int = 5
    hold_ms: int = 100
    hold_margin_deg: float = 4.0
    telemetry_hz: int = 50
    overrun_fault: int = 10  # consecutive ticks whose work overran the period: fault TICK_OVERRUN
    #: a rising limb that gets no progress edge closer for this long heats at safety.max_duty
    #: until the next START (core/ctl.h, CTL_BOOST_MS); 0: never; None (not in the file): by the
    #: robot's body, robot_reach.boost_ms_of (docs/robot-file.md)
    boost_ms: int | None = None
    fallback: bool = True  # firmware switches to a build-time fallback gait when it loses an actuator
    #: limbs raised to their strokes together: which crosses psi* first (None: the largest stroke);
    #: lowered together: which goes down first while the others are held at their strokes (None:
    #: they fall as they cool). Limb names.
    stroke_rise_lead: str | None = None
    stroke_fall_lead: str | None = None
    #: the steepest ground (degrees, rising in the gait's direction) a gait is started on, per
    #: direction: START steeper uphill is refused (NACK TOO_STEEP). None: no guard
    #: (docs/calibration.md)
    max_climb_deg: ClimbLimit | None = None


def _safety(path: Path, value: Any) -> Safety:
    f = Fields(path, "safety", value, set(Safety.__dataclass_fields__))
    d = Safety()
    s = Safety(
        max_on_ms=f.integer("max_on_ms", d.max_on_ms, 10, 60_000),
        min_cooldown_ms=f.integer("min_cooldown_ms", d.min_cooldown_ms, 0, 600_000),
        max_duty=f.number("max_duty", d.max_duty, 0.0, 1.0, open_lo=True),
        state_timeout_ms=f.integer("state_timeout_ms", d.state_timeout_ms, 10, 600_000),
        link_watchdog_ms=f.integer("link_watchdog_ms", d.link_watchdog_ms, 0, 600_000),
        hold_max_duty=f.number("hold_max_duty", None, 0.0, 1.0) if f.has("hold_max_duty") else None,
        max_mean_duty=f.number("max_mean_duty", d.max_mean_duty, 0.0, 1.0, open_lo=True),
        duty_window_ms=f.integer("duty_window_ms", d.duty_window_ms, *DUTY_WINDOW_MS_RANGE),
        on_limit_latch=f.integer("on_limit_latch", d.on_limit_latch, 1, MAX_ON_LIMIT_LATCH),
        coil_heat_ceiling=f.table.get("coil_heat_ceiling", d.coil_heat_ceiling),
    )
    if not isinstance(s.coil_heat_ceiling, bool):
        f.fail("coil_heat_ceiling", "true or false (the coil's heat ceiling, docs/safety.md; default false)",
               s.coil_heat_ceiling)
    if s.hold_max_duty is not None and s.hold_max_duty > s.mean_ceiling:
        f.fail("hold_max_duty", f"at most max_mean_duty and max_duty ({s.mean_ceiling:g}): a "
               "duty the coil may hold forever must fit the mean-duty window", s.hold_max_duty)
    # the host feeds the watchdog with a PING every quarter of it (link/stream.py): below
    # 100 ms that is a frame every few ms, and a desktop OS's scheduling alone can miss it
    if 0 < s.link_watchdog_ms < MIN_LINK_WATCHDOG_MS:
        f.fail("link_watchdog_ms", f"0 (off) or at least {MIN_LINK_WATCHDOG_MS} ms", s.link_watchdog_ms)
    # sma.c pays on-time back at max_on/min_cooldown in steps of 1/256: a cool-down of 256
    # on-times or more would pay back nothing, and a coil that hit its limit never heat again
    if s.min_cooldown_ms > MAX_COOLDOWN_PER_ON * s.max_on_ms:
        f.fail("min_cooldown_ms", f"at most {MAX_COOLDOWN_PER_ON} × safety.max_on_ms ({MAX_COOLDOWN_PER_ON * s.max_on_ms})",
               s.min_cooldown_ms)
    return s


def _control(path: Path, value: Any, safety: Safety) -> Control:
    f = Fields(path, "control", value, set(Control.__dataclass_fields__))
    d = Control()
    c = Control(
        tick_hz=f.integer("tick_hz", d.tick_hz, 200, 10_000),
        drive_duty=f.number("drive_duty", d.drive_duty, 0.0, 1.0, open_lo=True),
        hold_duty=f.number("hold_duty", d.hold_duty, 0.0, 1.0),
        debounce_ticks=f.integer("debounce_ticks", d.debounce_ticks, 1, 1000),
        hold_ms=f.integer("hold_ms", d.hold_ms, 0, 600_000),  # as SET_PARAM's (core/param.c)
        hold_margin_deg=f.number("hold_margin_deg", d.hold_margin_deg, 0.0, 30.0),
        telemetry_hz=f.integer("telemetry_hz", d.telemetry_hz, 1, 1000),
        overrun_fault=f.integer("overrun_fault", d.overrun_fault, 1, 1000),
        boost_ms=f.integer("boost_ms", 0, 0, BOOST_MAX_MS) if f.has("boost_ms") else None,
        fallback=f.table.get("fallback", d.fallback),
        stroke_rise_lead=f.string("stroke_rise_lead") if f.has("stroke_rise_lead") else None,
        stroke_fall_lead=f.string("stroke_fall_lead") if f.has("stroke_fall_lead") else None,
        max_climb_deg=climb_limit(f),
    )
    if not isinstance(c.fallback, bool):
        f.fail("fallback", "true or false", c.fallback)
    if c.drive_duty > safety.max_duty:
        f.fail("drive_duty", f"at most safety.max_duty ({safety.max_duty})", c.drive_duty)
    if c.hold_duty > c.drive_duty:
        f.fail("hold_duty", f"at most control.drive_duty ({c.drive_duty})", c.hold_duty)
    if safety.hold_max_duty is None and c.hold_duty > safety.mean_ceiling:
        f.fail("hold_duty", f"at most safety.max_mean_duty ({safety.mean_ceiling:g}): "
               "a duty that holds a state must fit the mean-duty window (or set safety.hold_max_duty "
               "below it, and the hold counts as on-time)", c.hold_duty)
    ceiling = safety.hold_ceiling(c.hold_duty)
    if c.drive_duty <= ceiling:
        # at or below the hold ceiling a duty is holding, never on-time (docs/safety.md): a coil
        # driven there would never meet max_on_ms, the cool-down or the on-limit latch
        f.fail("drive_duty", f"above the hold ceiling {ceiling:g} (safety.hold_max_duty, by default "
               "max(0.3, control.hold_duty)): at or below it heating counts as holding, never as on-time, "
               "so max_on_ms, the cool-down and the on-limit latch would never apply", c.drive_duty)
    if c.telemetry_hz > c.tick_hz:
        f.fail("telemetry_hz", f"at most control.tick_hz ({c.tick_hz})", c.telemetry_hz)
    if c.boost_ms is not None and 0 < c.boost_ms < BOOST_MIN_MS:
        f.fail("boost_ms", f"0 (off) or {BOOST_MIN_MS} .. {BOOST_MAX_MS} ms", c.boost_ms)
    # a step changes a limb's level only after debounce_ticks samples past its band, and counts
    # it settled only after as many again clear of its edges (docs/control.md), all the while
    # under the state timeout: 1000 ticks at 200 Hz (5 s) with a 2 s timeout loaded, built, and
    # every step of every gait ended in STATE_TIMEOUT "every limb at its level, one would not
    # settle". Twice the debounce is what a step needs at the least (the hold's dips restart
    # the settle count: R1 at 200 Hz with 400 ticks, 4 s of an 8 s timeout, still timed out).
    debounce_ms = c.debounce_ticks * 1000.0 / c.tick_hz
    if 2 * debounce_ms >= safety.state_timeout_ms:
        ticks = math.ceil(safety.state_timeout_ms * c.tick_hz / 1000.0)
        f.fail("debounce_ticks", f"under half the {counted(ticks, 'tick')} safety.state_timeout_ms lasts at {c.tick_hz} Hz (a "
               f"step changes a limb's level after debounce_ticks samples and settles it after as many again): "
               f"{counted(c.debounce_ticks, 'tick')} take {debounce_ms:g} ms, twice that {2 * debounce_ms:g} ms, and every "
               f"step would end in STATE_TIMEOUT after {safety.state_timeout_ms} ms", c.debounce_ticks)
    return c


def window_warning(path: Path, safety: Safety, control: Control) -> str | None:
    """A line when ``duty_window_ms`` is shorter than ``max_on_ms`` and the drive duty above the
    mean-duty limit: the limit then holds within one on-period, and a rise that needs the
    drive duty for longer is throttled (R1 at 100, 300 and 1000 ms ran into SMA_ON_LIMIT; it
    loaded without a word). None otherwise."""
    w, x, d = safety.duty_window_ms, safety.max_mean_duty, control.drive_duty
    if w >= safety.max_on_ms or d <= x:
        return None
    return (f"{path}: safety.duty_window_ms {w} is shorter than max_on_ms {safety.max_on_ms}, so the mean-duty "
            f"limit max_mean_duty {x:g} already holds within one on-period: a coil driven at control.drive_duty "
            f"{d:g} is throttled to {x:g} once it has been on about {w * x / d:.0f} ms of a window, and a rise that "
            "takes longer can run into its on-time limit (SMA_ON_LIMIT); the window is meant to span many cycles "
            f"(default {Safety.duty_window_ms})")
