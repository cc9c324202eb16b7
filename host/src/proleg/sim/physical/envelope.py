"""The firmware's safety envelope, for the idealised drive (``drive._run_to``).

The claim bench asks whether the coils *can* complete a gait under a condition
(``report.claim.physically_possible``). The firmware may only try within its safety envelope
(docs/safety.md), so the idealised drive is held to the same rules, per coil:

- *on-time debt*: every second on (a duty above the hold ceiling) adds a second, every second
  not on pays back ``max_on_ms / min_cooldown_ms`` seconds (at most 39: sma.c's refill_q8 ≤
  10000); a request that would take the debt past ``max_on_ms`` is an on-limit hit: the coil is
  cut and stays off until the debt is paid; ``on_limit_latch`` hits, on any coils together,
  latch the fault SMA_ON_LIMIT unless every coil that hit has since heated on the way to a
  target reached (core/safety.c);
- *mean duty*: the duty charged to a coil over the last window of ``duty_window_ms`` stays at
  most ``max_mean_duty`` × the window (a request that would not fit gets 0, not a hit: the
  firmware's hit for a refused *hold*, sma.c's ``holding``, is not modelled; the idealised
  drive holds a reached state 0.3 s). As in
  sma.c the window is 9 slots of 1/8 window (their sum spans 1 to 9/8 windows) and the charge
  is counted in ‱·µs / 1024, rounded as the firmware rounds it;
- *coil heat ceiling* (where the robot file sets ``[safety] coil_heat_ceiling = true``): each
  coil's duty smoothed with its thermal time constant (sma.c heat_step, in its integer units);
  a coil whose heat reached ``max_mean_duty`` gets at most that, across a latched fault and
  its rest as across the firmware's STOP and START (docs/safety.md, "The coil's heat ceiling").
  Without it the idealised drive, boosted to ``max_duty`` on such a body by default
  (``robot_reach.boost_ms_of``), measured caterpillar-4 at power 0.5 in full where the firmware,
  held to the ceiling, timed out at its first step;
- *state timeout*: a target not reached ``state_timeout_ms`` after it was first demanded
  latches STATE_TIMEOUT (``_run_to`` checks that one, on a ``StepClock``: where the firmware
  is built with it, a fall still coming down does not count, ctl.h CTL_FALL_PROGRESS_MS). The firmware also times out each coil's
  own time heated towards targets not reached, across STOP and START (safety.c); the
  idealised drive never restarts, so that time is never longer than the step's and needs no
  model here.

The numbers are the ones the firmware is built with (``firmware.render``: the robot file's
``[safety]`` in whole ticks, as sma.c takes max_on and the cool-down, and the thermal budget).
Stepped at the firmware's tick this is sma.c tick for tick (``tests/test_envelope_vs_sma.py``).
The idealised drive steps at 2 ms, which is not every robot's tick (R1's is 1 ms, inchworm-3's
1.25 ms, caterpillar-4's 2 ms, and a robot file may ask for 200 Hz): the model looks one step or
one tick ahead, whichever is longer, so that it cuts no later than the firmware would. Where it is still looser than the firmware: the idealised drive
switches a waiting coil off where the firmware keeps it at the hold duty, which fills the
firmware's window a little more. So a condition this calls possible may still be one the
firmware's envelope stops; the bench reports what the firmware does.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any


#: sma.c's SMA_WIN_SLOTS: the window as 8 slots plus the one being filled.
WIN_SLOTS = 9


class EnvelopeLatched(Exception):
    """The envelope latched a fault: ``code`` is the firmware's fault name."""

    def __init__(self, code: str, why: str):
        super().__init__(why)
        self.code = code


class Envelope:
    """Per channel, the duties the envelope lets through (``gate``), stepped at ``dt_s``. In
    sma.c's order and integer units: first the interval since the last step is charged at the
    duty the coil carried (µs of debt, or paid back at sma.c's rate), then the new duty is
    decided (cut while the debt is being paid; cut, as a hit, if one more step would pass
    max_on_ms)."""

    def __init__(self, robot: Any, n_channels: int, dt_s: float):
        from ...firmware.render import control_part
        from ...gait.coil_debt import refill_q8

        c = control_part(robot)
        self.dt_us = round(dt_s * 1e6)
        # sma.c decides for the tick to come: a step longer than the tick looks that far ahead
        self.ahead_us = max(self.dt_us, c.tick_us)
        # sma.c set_times(CFG_MAX_ON_TICKS × CFG_TICK_US, CFG_MIN_COOLDOWN_TICKS × CFG_TICK_US):
        # each µs off pays back refill_q8 / 256 µs of debt
        self.max_on_us = c.max_on_ticks * c.tick_us
        self.refill_q8 = refill_q8(self.max_on_us, c.cooldown_ticks * c.tick_us)
        self.max_duty_pm = c.max_duty_pm
        self.hold_ceiling_pm = c.hold_max_duty_pm
        self.latch = c.on_limit_latch
        self.state_timeout_s = c.timeout_ms / 1000.0
        window_us = c.duty_window_ms * 1000
        self.slot_len_us = window_us // (WIN_SLOTS - 1)
        self.win_limit = c.mean_duty_pm * (window_us >> 10)  # SMA_WIN_LIMIT
        self.debt = [0] * n_channels      # µs
        self.charged = [0] * n_channels   # ‱ the coil carried over the last step
        self.cut = [False] * n_channels
        self.hits = 0  # on-limit hits counting towards the latch, every coil together (safety.c)
        self.hit_bits = 0
        self.hit_mask = 0  # coils hit since each last heated on the way to a target reached
        self.heated = 0    # coils heated above the hold ceiling since the last target reached
        self.win = [[0] * n_channels for _ in range(WIN_SLOTS)]
        self.win_sum = [0] * n_channels  # per channel, the sum over every slot (kept as they change)
        self.win_rem = [0] * n_channels
        self.pay_rem = [0] * n_channels  # the pay-back's fraction of a µs (× 256), as sma.c
        self.slot, self.slot_us = 0, 0
        # sma.c's coil heat ceiling (CFG_COIL_TAU_MS; 0: not built): SMA_HEAT_K = 2^32 / tau in µs,
        # rounded up, and each coil's heat in ‱ × 256
        self.heat_k = 0xFFFFFFFF // (c.coil_tau_ms * 1000) + 1 if c.coil_tau_ms else 0
        self.mean_duty_pm = c.mean_duty_pm
        self.heat = [0] * n_channels

    def reached(self) -> None:
        """A target was reached: on-limit hits start counting again once every coil that hit
        has heated on the way to it (as safety.c: what other coils reach is no progress)."""
        self.hit_mask &= ~self.heated
        self.heated = 0
        if not self.hit_mask:
            self.hits = 0

    def acknowledge(self) -> None:
        """The operator cleared a latched fault (safety.c guard_ack): the hits count again from
        none; the debt and the window are not refunded."""
        self.hits, self.hit_mask = 0, 0

    def gate(self, duties: Sequence[float]) -> list[float]:
        """The duties after the envelope; raises EnvelopeLatched when a fault latches."""
        out = []
        self.hit_bits = 0  # the coils that hit the on-time limit in this step (sma_tick's return)
        self._advance_window()
        w = self.win[self.slot]
        for ch, duty in enumerate(duties):
            if not duty and not self.charged[ch] and not self.debt[ch] and not self.heat[ch]:
                # off, and off, paid up and cool (its heat-ceiling heat, where built, at 0) before:
                # nothing to charge, pay or cool (what the steps below come to for such a coil;
                # most coils are off most of the time)
                self.pay_rem[ch] = 0
                self.cut[ch] = False
                out.append(0.0)
                continue
            x = self.charged[ch] * self.dt_us + self.win_rem[ch]  # charge the step just gone
            w[ch] += x >> 10
            self.win_sum[ch] += x >> 10
            self.win_rem[ch] = x & 1023
            if self.charged[ch] > self.hold_ceiling_pm:
                self.debt[ch] += self.dt_us
                self.pay_rem[ch] = 0
            else:
                y = self.dt_us * self.refill_q8 + self.pay_rem[ch]  # the fraction carries on
                self.pay_rem[ch] = y & 255
                self.debt[ch] = max(0, self.debt[ch] - (y >> 8))
                if self.debt[ch] == 0:
                    self.cut[ch] = False
                    self.pay_rem[ch] = 0
            pm = min(round(duty * 10000), self.max_duty_pm)  # sma_clamp: the duty ceiling first
            if self.heat_k:
                pm = min(pm, self._heat_step(ch))  # as hot as the mean-duty ceiling held for ever: that at most
            if self.cut[ch]:
                pm = 0  # cooling after an on-limit hit: off until the debt is paid
            elif pm > self.hold_ceiling_pm and self.debt[ch] + self.ahead_us <= self.max_on_us:
                self.heated |= 1 << ch  # heats on from now (sma.c's heated)
            elif pm > self.hold_ceiling_pm:
                pm = 0
                self.cut[ch] = True
                self.hit_bits |= 1 << ch
                self.hit_mask |= 1 << ch
                self.hits += 1
                if self.hits >= self.latch:
                    raise EnvelopeLatched("SMA_ON_LIMIT", (
                        f"the safety envelope's on-time limit: {self.latch} on-limit hits (max_on_ms "
                        f"{self.max_on_us / 1000:.0f} ms of heating, the last on channel {ch}) without reaching the state"))
            if pm > 0 and self.win_sum[ch] + ((pm * self.ahead_us + 1023) >> 10) > self.win_limit:
                pm = 0  # does not fit the mean-duty window: 0 (not a hit)
            self.charged[ch] = pm
            out.append(pm / 10000.0)
        return out

    def _heat_step(self, ch: int) -> int:
        """sma.c heat_step: the coil's heat moves towards the duty it carried over the step just
        gone by dt / tau (in 1/65536); the most it may get now (the mean-duty ceiling once its
        heat has reached it, else no limit). Integer arithmetic as the firmware's (an arithmetic
        shift of a negative difference, as its int32 ``>>``)."""
        f = ((self.dt_us * self.heat_k) & 0xFFFFFFFF) >> 16
        d = (self.charged[ch] << 8) - self.heat[ch]
        self.heat[ch] += ((d >> 8) * f) >> 8
        return self.mean_duty_pm if self.heat[ch] >= self.mean_duty_pm << 8 else 0xFFFF

    def _advance_window(self) -> None:
        """sma.c advance_window: slots older than the window fall out."""
        self.slot_us += min(self.dt_us, self.slot_len_us * WIN_SLOTS)
        while self.slot_us >= self.slot_len_us:
            self.slot_us -= self.slot_len_us
            self.slot = (self.slot + 1) % WIN_SLOTS
            for ch, gone in enumerate(self.win[self.slot]):
                self.win_sum[ch] -= gone
            self.win[self.slot] = [0] * len(self.win_rem)


#: ctl.h CTL_FALL_PROGRESS_MS and CTL_CLIMB_CDEG
FALL_PROGRESS_S = 1.5
FALL_DROP_DEG = 1.0


class StepClock:
    """The time a target has been demanded and not reached, as the firmware counts it toward
    the state timeout (seq.c, safety.c). In builds with ``pause`` (seq.h SEQ_CLOCK_PAUSE: a limb
    with a full stroke, or three or more limbs) a tick does not count while a fall still comes
    down: no coil heats, no limb is below its target level, and every limb off its target level
    has made a new low of this step ``FALL_DROP_DEG`` below the last within ``FALL_PROGRESS_S``
    (ctl.h; the firmware looks at the smoothed ψ, this at the true one)."""

    def __init__(self, psi: Sequence[float], pause: bool):
        self.pause = pause
        self.low = [float(p) for p in psi]
        self.quiet = [FALL_PROGRESS_S] * len(self.low)  # no drop seen yet
        self.away_s = 0.0

    def tick(self, dt: float, psi: Sequence[float], level: Sequence[int], want: Sequence[int],
             heating: bool) -> float:
        """Account ``dt`` at ``psi`` (each limb at ``level``) with levels ``want`` demanded; the
        time counted so far."""
        off = [i for i, (lv, w) in enumerate(zip(level, want)) if lv != w]
        for i in off:
            if psi[i] <= self.low[i] - FALL_DROP_DEG:
                self.low[i], self.quiet[i] = float(psi[i]), 0.0
            else:
                self.quiet[i] = min(FALL_PROGRESS_S, self.quiet[i] + dt)
        coming_down = (self.pause and bool(off) and not heating
                       and all(level[i] > want[i] and self.quiet[i] < FALL_PROGRESS_S for i in off))
        if not coming_down:
            self.away_s += dt
        return self.away_s
