"""The idealised drive: the physical plant run to a robot state with perfect sensing (no firmware).

``IdealDrive`` commands each actuator +1 heat, 0 hold, −1 cool towards a target state from the
true ψ and ψ*: each limb's own coil heated until its end reaches the target level by
``margin_deg`` (the middle of a level narrower than two margins; a limb's top level at its
``stroke_deg`` if it has one, by core/ctl.h's stroke rules), then held there bang-bang; coils
whose limbs are all to be at level 0 are switched off and cool freely (as the firmware does).
``_run_to`` heats the commanded coils at ``duty`` (a boosted limb's at the duty ceiling: the
firmware's boost, ``IdealDrive._watch_boost``) until the robot has settled in the target and
returns when it first got there (None: not within ``timeout_s``), within the firmware's safety
envelope if given one. ``run_sequence`` and ``walk_within_envelope`` walk a gait with it;
``measure`` measures the reward matrix with it and re-exports these names.
"""

from __future__ import annotations

import math
from bisect import bisect_right
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from ...robot import stroke_leads
from ...robot_reach import boost_ms_of
from ...states import limb_levels
from .conditions import Conditions
from .envelope import Envelope, EnvelopeLatched, StepClock
from .plant import PhysicalPlant


#: How far past a level's critical angle the idealised drive holds a limb (°): the margin the
#: measured matrix is defined at.
MARGIN_DEG = 4.0

#: A walk at less than this share of a reference speed (the nominal row's, the flat's) barely
#: moves: the claim bench counts no row against the firmware where the idealised drive makes
#: less (report.claim_summary), ``proleg check`` calls such a row "drifted", and a grade up
#: which the gait makes less is one it does not climb (``climb.steepest_climb``).
BARELY_MOVES = 0.05


#: The firmware's stroke rules (core/ctl.h) the idealised drive follows: how long a limb falling
#: behind the fall lead is held at its stroke at most (CTL_FALL_WAIT_MS) and how far down the
#: lead is by then (CTL_FALL_SHARE), how long limbs climb in step at most (CTL_CLIMB_MAX_MS),
#: and when a limb rising to its stroke has stopped climbing (CTL_CLIMB_GAIN_CDEG in CTL_CLIMB_STOP_MS).
FALL_WAIT_S = 2.0
FALL_SHARE = 0.5
CLIMB_MAX_S = 3.0
CLIMB_GAIN_DEG = 0.5
CLIMB_STOP_S = 0.15
CLIMB_STOP_DPS = CLIMB_GAIN_DEG / CLIMB_STOP_S
HOVER_S = 0.3  # CTL_HOVER_MS: the stop time of a limb another limb in step waits for
SHARE_SYNC = 13 / 256  # CTL_SHARE_SYNC / CTL_SHARE_FULL
#: A lagging limb below its band is waited for only while it still rises: heated this long
#: without getting one of PROGRESS_DEG closer to its crossing, it is not waited for again in
#: the step (CTL_LAG_MS; psi.h PSI_PROGRESS_CDEG).
LAG_S = 1.0
PROGRESS_DEG = (1, 2, 3, 4, 5, 6, 8, 10, 12, 15, 20, 25, 30)


class IdealDrive:
    """Per actuator: +1 heat, 0 hold, −1 cool, towards a target robot state.

    Limbs with a ``stroke_deg`` follow the firmware's rules (core/ctl.h): raised to the stroke
    on their top level; rising together, the rise lead crosses ψ* first while the others wait,
    then they climb in step (for at most ``CLIMB_MAX_S``, and waiting only for a limb that still
    rises: ``LAG_S``); falling together with a fall lead,
    the others are held at their strokes until it is halfway down its climb (at most
    ``FALL_WAIT_S``; times counted from the ``dt_s`` given to ``command``); a limb climbing in
    step past where another stopped short of its stroke waits there and counts as stopped. Where the firmware
    keeps a waiting coil warm at the hold duty, this drive switches it off; a limb that stopped
    short of its stroke is driven towards it again in later steps (no on-time limit here)."""

    def __init__(self, robot: Any, plant: PhysicalPlant, margin_deg: float):
        names = [a.name for a in robot.actuators]
        self.limb_act = [names.index(lb.actuator) for lb in robot.limbs]
        self.n_act = len(names)
        self.levels = plant.levels
        # states in messages by label ("020"), as everywhere: a check's error said "state 4"
        table = getattr(robot, "transitions", None)
        self.label = table.label if table is not None else str
        self.th = plant.true_psi_star_deg
        self.margin = margin_deg
        self.stroke = [getattr(lb, "stroke_deg", None) for lb in robot.limbs]
        self.half_band = [getattr(lb, "hysteresis_deg", 0.0) / 2 for lb in robot.limbs]
        leads = stroke_leads(robot.limbs, getattr(robot, "control", None))
        self.rise_lead, self.fall_lead = leads if leads else (None, None)
        self._step: tuple[int, float] = (-1, 0.0)   # (target, seconds in it) for the fall hold
        self._raised: set[int] = set()              # limbs the current step raises to their strokes
        self._waits: set[int] = set()               # limbs waiting in the last command
        self._heated: set[int] = set()              # limbs whose coil the last command heated
        self._lag: dict[int, tuple[float, float]] = {}  # limb -> (closest edge to go, s heated since)
        self._given_up: set[int] = set()            # lagging limbs not waited for in this step
        self._capped: set[int] = set()              # waiting past where a limb in step stopped short
        self._gain: dict[int, tuple[float, float]] = {}  # limb -> (ψ at its last CLIMB_GAIN_DEG gain, s since)
        self._ahead: set[int] = set()  # limbs that waited in step for another in the last command
        self._band_cache: dict[tuple[int, tuple[int, ...]], list[tuple[int, int, float, float, bool]]] = {}
        # the firmware's boost (ctl.c CTL_BOOST_MS, as the robot's firmware is built with it): a
        # limb heated rising for boost_s without getting one progress edge closer heats at the duty
        # ceiling from then on, on every heat of its coil (sticky, as until the firmware's next START)
        control, safety = getattr(robot, "control", None), getattr(robot, "safety", None)
        self.boost_s = boost_ms_of(robot) / 1000.0 if control is not None and safety is not None else 0.0
        self.boost_duty = float(safety.max_duty) if safety is not None else 1.0
        self.boosted: set[int] = set()      # limbs boosted
        self.boost_act: set[int] = set()    # actuators the last command heats for a boosted limb
        self._rise: dict[int, tuple[int, int, float, float]] = {}  # limb -> (target, level, best edge, s idle)

    def command(self, psi: Sequence[float], target: int, dt_s: float = 0.0) -> list[int]:
        want = limb_levels(target, self.levels)
        waits, held = self._stroke_rules(psi, want, target, dt_s) if self.rise_lead is not None else (set(), set())
        self._waits = waits
        heat = [False] * self.n_act
        cool = [False] * self.n_act
        active = [False] * self.n_act
        asks: set[int] = set()  # limbs whose own band asks for heat
        for (i, j, lo, hi, raised), p in zip(self._bands(target, held), psi):
            if p > hi:
                cool[j] = True
            elif p < lo and i not in waits:
                heat[j] = True
                asks.add(i)
            if raised:
                active[j] = True
        self._heated = {i for i, j in enumerate(self.limb_act) if heat[j] and not cool[j]}
        if self.boost_s > 0.0:
            self._watch_boost(psi, want, target, dt_s)
            # a coil heats at the ceiling for a boosted limb that asks for heat itself (ctl.c: the
            # coil serves its limbs' strongest want, WANT_HEAT + that limb's boost), not for a
            # boosted limb it heats only because another limb on it, not boosted, asks
            self.boost_act = {self.limb_act[i] for i in self.boosted if i in self._heated and i in asks}
        return [-1 if cool[j] else 1 if heat[j] else 0 if active[j] else -1 for j in range(self.n_act)]

    def _watch_boost(self, psi: Sequence[float], want: Sequence[int], target: int, dt_s: float) -> None:
        """The firmware's boost watch (ctl.c, on stall.c's clock): a limb rising towards a higher
        level, its coil heated, that gets no progress edge closer to the upper edge of the band
        it must cross (psi.c psi_to_go_cdeg) for ``boost_s`` is boosted; the clock restarts on a
        progress edge and on a change of level, the best edge on a new target."""
        if len(self.boosted) == len(psi):
            return
        level = self.level_of(psi)
        for i, (p, k, now) in enumerate(zip(psi, want, level)):
            if i in self.boosted:
                continue
            t, was, best, idle = self._rise.get(i, (-1, -1, math.inf, 0.0))
            if t != target:
                best, idle = math.inf, 0.0
            elif was != now:
                idle = 0.0
            elif k > now and i in self._heated:
                gap = self.th[i][now] + self.half_band[i] - p
                edge = 0 if gap <= 0 else next((e for e in PROGRESS_DEG if gap <= e), math.inf)
                if edge < best:
                    best, idle = edge, 0.0
                else:
                    idle += dt_s
                    if idle >= self.boost_s:
                        self.boosted.add(i)
            self._rise[i] = (target, now, best, idle)

    def _bands(self, target: int, held: set[int]) -> list[tuple[int, int, float, float, bool]]:
        """Per limb, the band ``command`` keeps it in on the way to ``target``: (limb, its
        actuator, lowest ψ, highest ψ, raised off level 0), ``held`` limbs at their strokes.
        They depend on nothing else: made once per target (``command`` runs every step)."""
        key = (target, tuple(sorted(held)) if held else ())
        got = self._band_cache.get(key)
        if got is not None:
            return got
        out = []
        for i, k in enumerate(limb_levels(target, self.levels)):
            th = self.th[i]
            if i in held:   # held at its stroke while the fall lead goes down
                k = len(th)
            lo = th[k - 1] + self.margin if k > 0 else -math.inf
            hi = th[k] - self.margin if k < len(th) else math.inf
            if lo > hi:  # a middle level narrower than two margins: hold in its middle
                lo = hi = (th[k - 1] + th[k]) / 2
            if k == len(th) and self.stroke[i] is not None:  # raised to its stroke (as the firmware)
                lo = max(lo, self.stroke[i])
            out.append((i, self.limb_act[i], lo, hi, k > 0))
        self._band_cache[key] = out
        return out

    def level_of(self, psi: Sequence[float]) -> list[int]:
        """Each limb's level at ``psi``: how many of its true thresholds it is at or past (they
        increase: the count is a bisection, called every step of ``_run_to``)."""
        return [bisect_right(th, p) for p, th in zip(psi, self.th)]

    def _stroke_rules(self, psi: Sequence[float], want: Sequence[int], target: int,
                      dt_s: float) -> tuple[set[int], set[int]]:
        """(limbs waiting for the rise lead to cross, limbs held at their strokes for the fall lead)."""
        t, spent = self._step
        self._step = (target, spent + dt_s if t == target else 0.0)
        level = self.level_of(psi)
        tops = [i for i, s in enumerate(self.stroke) if s is not None]
        if t != target:
            self._raised = {i for i in tops if level[i] < want[i] == len(self.th[i])}
            self._lag, self._given_up, self._gain, self._ahead = {}, set(), {}, set()
        self._watch_lag(psi, dt_s)
        rising = [i for i in range(len(psi)) if want[i] > level[i]]
        falling = [i for i in range(len(psi)) if want[i] < level[i]]
        waits: set[int] = set()
        held: set[int] = set()
        lead = self.rise_lead
        if not falling and lead in rising and want[lead] == len(self.th[lead]):
            waits = {i for i in rising if i in tops and i != lead and want[i] == len(self.th[i])}
        # then they climb in step: a limb more than 5 % of its climb ahead of another waits;
        # one past where a limb that stopped short of its stroke (on its top level, not waiting)
        # stopped has climbed far enough (ctl.c: STOPPED_SHORT)
        climbing = [i for i in self._raised if psi[i] < self.stroke[i]]
        rises = [i for i in climbing if i not in self._given_up]
        self._capped = set()
        if len(climbing) > 1 and rises and self._step[1] < CLIMB_MAX_S:
            share = {i: self._share(i, psi[i]) for i in climbing}
            least = min(share[i] for i in rises)
            ahead = {i for i in climbing if share[i] > least + SHARE_SYNC and level[i] == want[i]}
            waits |= ahead
            waited, self._ahead = bool(self._ahead), ahead
            stopped = [share[i] for i in rises if level[i] == want[i] and self._stopped(i, psi[i], dt_s, waited)]
            if stopped:
                self._capped = {i for i in ahead if share[i] > min(stopped) + SHARE_SYNC}
        lead = self.fall_lead
        if (lead is not None and not rising and lead in falling and level[lead] == len(self.th[lead])
                and self._share(lead, psi[lead]) > FALL_SHARE and self._step[1] < FALL_WAIT_S):
            held = {i for i in falling if i in tops and i != lead and level[i] == len(self.th[i])}
        return waits, held

    def _stopped(self, i: int, psi: float, dt_s: float, waited: bool = False) -> bool:
        """Limb i, climbing on its top level and not waiting, has gained less than
        ``CLIMB_GAIN_DEG`` in ``CLIMB_STOP_S``, or in ``HOVER_S`` while another limb waited for
        it (stall.c: the clock of a climbing limb, CLIMB_STOP); once stopped it stays so for the
        step."""
        limit = HOVER_S if waited else CLIMB_STOP_S
        peak, idle = self._gain.get(i, (psi, 0.0))
        if idle >= limit:
            return True
        if i in self._waits or psi >= peak + CLIMB_GAIN_DEG:
            peak, idle = psi, 0.0
        else:
            idle += dt_s
        self._gain[i] = (peak, idle)
        return idle >= limit

    def _watch_lag(self, psi: Sequence[float], dt_s: float) -> None:
        """The firmware's lag watch (stall.c: ``lagged``, on the stall detector's clock) on the
        limbs this step raises, below their top band: heated ``LAG_S`` without getting one
        progress edge closer to the crossing, a limb is given up for the rest of the step."""
        for i in self._raised - self._given_up:
            gap = self.th[i][-1] + self.half_band[i] - psi[i]
            if gap <= 0:
                continue   # across its band: the hover rule's, not this watch's
            edge = next((e for e in PROGRESS_DEG if gap <= e), math.inf)
            best, idle = self._lag.get(i, (math.inf, 0.0))
            if edge < best:
                best, idle = edge, 0.0
            elif i in self._heated:
                idle += dt_s
                if idle >= LAG_S:
                    self._given_up.add(i)
            self._lag[i] = (best, idle)

    def _share(self, i: int, psi: float) -> float:
        """How much of its climb limb i has covered: 0 at its top band's upper edge, 1 at its stroke."""
        lo = self.th[i][-1] + self.half_band[i]
        return min(1.0, max(0.0, (psi - lo) / (self.stroke[i] - lo)))

    def at_strokes(self, psi: Sequence[float], dpsi: Sequence[float], target: int) -> bool:
        """Every limb wanted on its top level that has a stroke is there, or has stopped climbing
        (the firmware counts a step reached only then)."""
        if self.rise_lead is None:
            return True   # no strokes
        want = limb_levels(target, self.levels)
        return all(s is None or k < len(th) or p >= s
                   or (d < CLIMB_STOP_DPS and (i not in self._waits or i in self._capped))
                   for i, (s, k, th, p, d) in enumerate(zip(self.stroke, want, self.th, psi, dpsi)))


def _run_to(plant: PhysicalPlant, drive: IdealDrive, target: int, duty: float, dt: float,
            timeout_s: float, settle_s: float, envelope: Envelope | None = None) -> float | None:
    """Drive to ``target`` until the robot has stayed in it for ``settle_s``; return the time
    it first reached it (None if it did not settle there within ``timeout_s``). With strokes it
    has reached it once its limbs got to their strokes (``IdealDrive.at_strokes``; latched while
    the state holds, as the firmware's settled flag). ``envelope``: the duties go through the
    firmware's safety envelope, and a fault it would latch raises ``EnvelopeLatched``."""
    chans = [a.channel for a in plant.params.actuators]
    nch = max(chans) + 1
    t0 = plant.time_s
    first = since = None
    arrived = False
    want = limb_levels(target, drive.levels)
    clock = StepClock(plant.psi_now, pause=any(s is not None for s in drive.stroke) or len(drive.th) > 2)
    while True:
        cmd = drive.command(plant.psi_now, target, dt)
        duties = [0.0] * nch
        for j, c in enumerate(cmd):
            if c > 0:
                duties[chans[j]] = max(duty, drive.boost_duty) if j in drive.boost_act else duty
        if envelope is not None:
            duties = envelope.gate(duties)
        plant.step(dt, duties)
        now = plant.time_s - t0
        psi = plant.psi_now
        away = clock.tick(dt, psi, drive.level_of(psi), want, any(d > 0 for d in duties))
        arrived = plant.true_state == target and (arrived or drive.at_strokes(psi, plant.dpsi_now, target))
        if arrived:
            if since is None:
                since = now
                if first is None and envelope is not None:
                    envelope.reached()
                first = now if first is None else first
            if now - since >= settle_s:
                return first
        else:
            since = None
            if envelope is not None and first is None and away > envelope.state_timeout_s:
                raise EnvelopeLatched("STATE_TIMEOUT", (
                    f"the safety envelope's state timeout: state {drive.label(target)} not reached within "
                    f"state_timeout_ms ({envelope.state_timeout_s * 1000:.0f} ms)"))
        if now > timeout_s:
            return None


def run_sequence(robot: Any, states: Sequence[int], *, cycles: int = 3, conditions: Conditions | None = None,
                 duty: float | None = None, margin_deg: float = MARGIN_DEG, settle_s: float = 0.3,
                 timeout_s: float = 12.0, dt_s: float = 0.002, plant: PhysicalPlant | None = None,
                 envelope: bool = False) -> tuple[float, float]:
    """Walk the closed sequence ``states`` (first state repeated at the end or not) with the
    idealised drive, ``cycles`` times after one warm-up cycle; return (mm per cycle, s per
    cycle). Raises SimError if a state cannot be reached; with ``envelope`` the drive keeps to
    the firmware's safety envelope and raises ``EnvelopeLatched`` where it would latch a fault."""
    from ...errors import SimError

    plant = plant or PhysicalPlant(robot, conditions)
    drive = IdealDrive(robot, plant, margin_deg)
    duty = robot.control.drive_duty if duty is None else duty
    seq = list(states)
    if len(seq) > 1 and seq[0] == seq[-1]:
        seq = seq[:-1]
    gate = Envelope(robot, max(a.channel for a in plant.params.actuators) + 1, dt_s) if envelope else None

    def one_cycle() -> None:
        for s in seq[1:] + seq[:1]:
            if _run_to(plant, drive, s, duty, dt_s, timeout_s, settle_s, gate) is None:
                raise SimError(f"run_sequence: state {drive.label(s)} not reached within {timeout_s} s")

    if _run_to(plant, drive, seq[0], duty, dt_s, timeout_s, settle_s, gate) is None:
        raise SimError(f"run_sequence: start state {drive.label(seq[0])} not reached")
    one_cycle()
    x0, t0 = plant.displacement_mm, plant.time_s
    for _ in range(cycles):
        one_cycle()
    return (plant.displacement_mm - x0) / cycles, (plant.time_s - t0) / cycles


@dataclass(frozen=True)
class EnvelopeWalk:
    """What ``walk_within_envelope`` found: mm and seconds per cycle, or (None) why not."""

    mm_per_cycle: float | None  # None: a state was not reached, or the envelope latched a fault
    s_per_cycle: float | None
    latched: str = ""           # the fault the envelope would latch ("" when none)


def walk_within_envelope(robot: Any, states: Sequence[int], plant: PhysicalPlant) -> EnvelopeWalk:
    """The claim bench's and ``--measure-climb``'s question: how far and how fast the idealised
    drive walks ``states`` on ``plant`` within the firmware's safety envelope (two cycles after
    a warm-up, 10 s at most per state); if it cannot, the fault the envelope would latch ("" when
    a state is simply not reached)."""
    from ...errors import SimError

    try:
        mm, s = run_sequence(robot, states, cycles=2, plant=plant, timeout_s=10.0, envelope=True)
    except EnvelopeLatched as e:
        return EnvelopeWalk(None, None, f"{e} ({e.code})")
    except SimError:
        return EnvelopeWalk(None, None)
    return EnvelopeWalk(mm, s)
