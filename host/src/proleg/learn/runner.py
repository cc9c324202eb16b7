"""Driving a robot through exploration pieces over a link (the only module that talks to
one; everything else in ``proleg.learn`` is link-free).

``explore`` repeats until every allowed transition inside a closed tour has ``repeats``
trials in the log (every one the hardware can make: ``makeable.py``): plan a tour of what is still to do from the robot's measured state
(``tours.exploration`` with the remaining demand), take its first piece
(``pieces.split``), run it, rest, append every observed transition to the log. Planning
again after each piece is what makes a run resumable (an interrupted run's log is the
demand already met) and robust to what a piece really did (a timeout, the robot relaxing
into another state while its coils cool).

Which piece comes next is ``next_piece.plan_piece``'s (link-free); ``Explorer.next_piece``
names the transitions no piece from the rest state can reach within the thermal limits. A
run whose pieces keep making nothing it needs (the robot does not do what was planned)
stops after ``STALL_PIECES`` of them with what is left, instead of running for ever.

A fault of making a transition (STATE_TIMEOUT, SMA_ON_LIMIT while a piece's transition is
under way), predicted by the body model or not, does not end the run: ``_after_fault`` records
the transition as not made (``measure.Failure``, in the log), rests the robot with the fault
still latched (``fault_rest_s``), clears it (``RobotClient.clear``) and plans again without it
(from where the robot settles: ``_settled_state``, where no piece starts from where it is first measured);
it is never asked for again in the run (``plan_table``), and what only it led to gets no
trials. Any other stop (an E-stop, a fault while no transition is under way, another kind of
fault) and ``FAULTS_IN_A_ROW`` such faults with no transition made between them end the run
as before, the last fault left latched.

A piece ``p0 → … → pk`` runs as a user gait: LOAD_GAIT of the piece closed by the
shortest way back to p0 (the firmware accepts closed walks only), START, and STOP once
the firmware's STATE_REACHED event says ``pk`` was reached the k-th time. Each reached
state's pose is taken ``settle_s`` after its event (the robot holds a reached state for
the robot's ``hold_ms`` before it moves on; keep settle_s below that), and every pair of
consecutive reached states that is an allowed transition becomes a trial. The telemetry's
measured state is watched meanwhile: the time it first showed a reached state (before the
firmware confirmed it settled) is the trial's ``t_seen``, which a tracker is aligned with,
and every state it showed on the way that lies outside the transition (a limb that should
have held, or the moving one overshooting, crossed a level) is the trial's ``passed``: its
motion includes those crossings, and ``proleg learn --report`` says how often. The
measured state changes only past the hysteresis band (ψ* ± h/2), while a contact's friction
changes at ψ* itself: so each frame's ψ is also read against the bare ψ* (``psi_state``),
and a held limb that sags across ψ* but stays inside the band counts as passing too. The
exploration asks for the fastest telemetry the board takes (``WATCH_HZ``) to see them.
"""

from __future__ import annotations

import logging
import time as _time
from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from ..link.leave import stop_robot
from ..errors import LinkError
from ..link.direction import UNSTATED
from ..protocol.definition import GAIT_USER, MAX_GAIT_STEPS, ClearWhat, EventKind, FaultCode, Flag
from ..robot import Robot
from ..transitions import TransitionTable
from .makeable import makeable_robot, not_asked, without_edges
from .measure import (Failure, Pose, Trial, TrialLog, between_levels, counts, manual_trial, planar_delta, psi_state,
                      remaining)
from .next_piece import plan_piece
from .pieces import Piece, PieceLimits, limits_for
from .tours import _bfs_path, exploration, reached_from, successors

log = logging.getLogger("proleg")


#: seconds of link time that count as "now" when waiting for a moment on the link's clock
CLOCK_EPS_S = 1e-6
#: pieces in a row without a transition still to do before ``Explorer.run`` gives up
STALL_PIECES = 5
#: telemetry frames ``Explorer.measured_state`` reads at most for three with a known state
STATE_FRAMES = 200
#: transitions in a row the robot faults on (no trial made between them) before ``Explorer.run``
#: stops: one fault is the transition's, several in a row more likely the robot's (a dead coil)
FAULTS_IN_A_ROW = 3
#: a robot with no piece from where it is measured is looked at again this often (s), for at most
#: ``SETTLE_MAX_S``, until its state stops changing (``Explorer._settled_state``): a coil cooling
#: through its transformation lowers its limb within a few seconds
SETTLE_LOOK_S = 1.0
SETTLE_MAX_S = 30.0
#: the faults of making a transition (the robot did not get there): ``Explorer.run`` records the
#: transition as not made, cools, clears and goes on; any other fault stops it
MAKING_FAULTS = (FaultCode.STATE_TIMEOUT, FaultCode.SMA_ON_LIMIT)
#: telemetry rates (Hz) an exploration asks for, fastest first: the board refuses what its
#: link cannot carry (telemetry.c: at most half the UART), and the first it takes is used
WATCH_HZ = (250, 200, 150, 100)


class ExplorationError(RuntimeError):
    """The robot stopped (fault, E-stop, timeout); the log keeps every trial made.
    ``transition``: the (from, to) labels being made when it stopped, when known; ``fault``:
    a latched fault or E-stop (cleared on the robot before going on); ``making_failed``: a
    fault of making that transition (STATE_TIMEOUT, SMA_ON_LIMIT), which ``Explorer.run``
    records and goes on from; ``made``: the piece's trials before it stopped; ``what``: the
    event as the firmware reported it."""

    def __init__(self, message: str, *, transition: tuple[str, str] | None = None, fault: bool = False,
                 making_failed: bool = False, made: list[Trial] | None = None, what: str = "",
                 t_fault: float | None = None):
        super().__init__(message)
        self.transition = transition
        self.fault = fault
        self.making_failed = making_failed
        self.made = made or []
        self.what, self.t_fault = what, t_fault


@dataclass(frozen=True)
class Progress:
    done: int          # trials counted toward the goal (at most the goal per transition)
    to_do: int         # trials still needed
    elapsed_s: float   # wall-clock seconds since the start (a simulated robot runs faster than real time)
    eta_s: float       # estimated wall-clock time left at the pace so far


def _closing_gait(robot: Robot, piece: Piece, max_steps: int) -> tuple[int, ...]:
    """The piece closed by its shortest way back (``Piece.gait``), as LOAD_GAIT takes it."""
    t = robot.transitions
    s = piece.states
    if not piece.loadable:
        if s[-1] != s[0] and _bfs_path(t.n_states, successors(t), s[-1], s[0]) is None:
            raise ExplorationError(f"no way back from {t.label(s[-1])} to {t.label(s[0])} to close the piece")
        raise ExplorationError(f"piece {'→'.join(t.label(x) for x in s)} and its way back need more gait steps "
                               f"than the firmware takes ({max_steps})")
    return piece.gait()


class Explorer:
    """One exploration run over ``client`` (a ``proleg.link.RobotClient``, connected)."""

    def __init__(self, client, robot: Robot, log: TrialLog, pose: Callable[[], Pose] | None, *,
                 repeats: int = 5, limits: PieceLimits | None = None, settle_s: float = 0.05,
                 source: str = "sim", seed: int | None = None,
                 on_progress: Callable[[Progress], None] | None = None,
                 rest: Callable[[float], None] | None = None,
                 ask: Callable[[str], str] | None = None,
                 try_unholdable: bool = False, retry_faulted: bool = False):
        # tours over the transitions the hardware can make, the body can hold (unless
        # ``try_unholdable``) and the robot did not fault on before in this log (unless
        # ``retry_faulted``): asked for one of the others, the firmware heats a coil to the
        # state timeout (makeable.py)
        self.full_robot = robot
        self.left_out = not_asked(robot, try_unholdable=try_unholdable, failures=log.failures,
                                  retry_faulted=retry_faulted)
        robot = makeable_robot(robot, self.left_out)
        # edges of ``robot.transitions`` the robot faulted on in this run: not asked for again
        self.failed: dict[int, str] = {}
        self._faults_in_a_row = 0
        self.client, self.robot, self.log, self.pose = client, robot, log, pose
        self.goal: np.ndarray | None = None  # trials wanted per transition (default: repeats each)
        self.repeats, self.settle_s, self.source, self.seed = repeats, settle_s, source, seed
        info_steps = getattr(getattr(client, "info", None), "max_gait_steps", None) or MAX_GAIT_STEPS
        self.max_steps = min(MAX_GAIT_STEPS, int(info_steps))
        base = limits or limits_for(robot)
        # manual entry (``ask``): one transition per piece, the operator measures while the robot rests
        k = 1 if ask is not None else min(base.max_transitions, self.max_steps - 1)
        self.limits = replace(base, max_transitions=k, max_gait_steps=self.max_steps)
        self.ask = ask
        self.on_progress = on_progress
        self._rest = rest or self._rest_on_link
        self._t0 = _time.monotonic()
        self._trials0 = len(log.trials)  # the pace counts this run's trials only (a resumed log)
        self.pieces_run = 0
        # manual entry's end: the transitions still to do that start where the robot does not
        # rest, so no one can measure them by eye (labels; the tracker records them)
        self.left_for_tracker: list[str] = []

    def _clock(self) -> float:
        return float(self.client.link.clock()) if hasattr(self.client.link, "clock") else _time.monotonic()

    def _rest_on_link(self, seconds: float) -> None:
        end = self._clock() + seconds
        # stop within CLOCK_EPS_S of the end: a simulated link counts whole nanoseconds, so
        # a wait shorter than half of one does not advance its clock (this loop then never ended)
        while end - self._clock() > CLOCK_EPS_S:
            self.client.recv(min(0.2, end - self._clock()))

    def measured_state(self) -> int:
        """The robot's state as the telemetry measures it: the third frame whose state is known
        (a frame flagged STATE_UNKNOWN, a limb between levels, is skipped)."""
        known = 0
        for msg in self.client.telemetry(timeout=2.0, count=STATE_FRAMES):
            if not int(msg.flags) & Flag.STATE_UNKNOWN:
                state, known = int(msg.measured), known + 1
                if known == 3:
                    return state
        raise ExplorationError(f"the robot's state stayed unknown over {STATE_FRAMES} telemetry frames (a limb "
                               "between its levels): check it with proleg console")

    def to_do(self) -> np.ndarray:
        """Trials still wanted per allowed transition: up to ``goal`` when set (extra or
        adaptive plans), else up to ``repeats`` each."""
        if self.goal is not None:
            return np.maximum(0, self.goal - counts(self.robot.transitions, self.log.trials))
        return remaining(self.robot.transitions, self.log.trials, self.repeats)

    def run(self, max_pieces: int | None = None) -> list[Trial]:
        """Explore until done (or ``max_pieces``); returns the trials added by this run.
        Raises ``ExplorationError`` when ``STALL_PIECES`` pieces in a row make none of the
        transitions still to do (the robot does not do what was planned), naming them."""
        restore = self._watch_closely()
        self.left_for_tracker = []  # said again by this run's end, if it is manual entry's
        try:
            return self._run(max_pieces)
        finally:
            if restore is not None:
                try:
                    self.client.set_telemetry_rate(restore)
                except LinkError:
                    pass  # the link is gone (the run's own error, if any, says so); a reset restores it

    def _watch_closely(self) -> int | None:
        """Raise the telemetry rate to the fastest of ``WATCH_HZ`` the board takes, so that a
        limb that flickers across a level on the way is seen (``Trial.passed``); the rate to
        restore afterwards, or None (none taken: the build's rate stays)."""
        from ..link.client import CommandRefused

        for hz in WATCH_HZ:
            if hz <= self.robot.control.telemetry_hz:
                return None
            try:
                self.client.set_telemetry_rate(hz)
                return self.robot.control.telemetry_hz
            except CommandRefused:
                continue
        return None

    def plan_table(self) -> TransitionTable:
        """The transitions tours are planned over: the robot's, but those it faulted on."""
        t = self.robot.transitions
        return without_edges(t, self.failed) if self.failed else t

    def _unexplored(self) -> np.ndarray:
        """A mask over ``self.robot.transitions``: the transitions that get no (more) trials:
        those the robot faulted on, those no closed tour of the others can make, and those the
        faulted ones cut off from the rest state (every way there went through one of them)."""
        t = self.robot.transitions
        out = np.zeros(t.n_transitions, dtype=bool)
        out[list(self.failed)] = True
        pt = self.plan_table() if self.failed else t
        if pt.n_transitions:
            for a, b in exploration(pt, 1).uncoverable:
                out[t.lookup(a, b)] = True
        # a part of the graph the rest state has no way into (every way out of rest forbidden)
        # has tours of its own, but the robot, resting, never gets there
        now = reached_from(pt)
        out |= np.array([a not in now for a in t.src.tolist()], dtype=bool)
        return out

    def _run(self, max_pieces: int | None) -> list[Trial]:
        added: list[Trial] = []
        t = self.robot.transitions
        stalled = 0
        while max_pieces is None or self.pieces_run < max_pieces:
            demand = self.to_do()
            demand[self._unexplored()] = 0
            if demand.sum() == 0:
                break
            start = self.measured_state()
            try:
                piece = self.next_piece(start, demand)
            except ExplorationError:
                # no piece from where the robot is: it may not be resting there yet
                settled = self._settled_state(start)
                if settled == start:
                    raise
                piece = self.next_piece(settled, demand)
            if piece is None:  # manual entry did all it can from where the robot rests
                break
            began = self._clock()
            try:
                made = self.run_piece(piece, record=self.ask is None)
                self._faults_in_a_row = 0 if made else self._faults_in_a_row
            except ExplorationError as e:
                made = self._after_fault(e, self._clock() - began)
            if self.ask is None:
                added += made
            else:
                for tr in made:
                    asked = manual_trial(tr.src, tr.dst, tr.t_start, tr.t_end, ask=self.ask, units=self.robot.units)
                    if asked is not None:
                        self.log.append(asked)
                        added.append(asked)
            progress = any(demand[t.lookup(t.index(tr.src), t.index(tr.dst))] > 0 for tr in made)
            stalled = 0 if progress else stalled + 1
            self.pieces_run += 1
            self._report()
            if stalled >= STALL_PIECES:
                left = [f"{t.label(a)}->{t.label(b)}" for a, b, k in zip(t.src, t.dst, demand) if k > 0]
                raise ExplorationError(
                    f"{stalled} pieces in a row made none of the transitions still to do ({', '.join(left)}); "
                    f"the robot did not follow the planned states (last piece "
                    f"{'→'.join(t.label(x) for x in piece.states)}): check it with proleg console, then run "
                    "again with the same --log to go on")
            self._rest(self.limits.rest_s)
        return added

    def _settled_state(self, state: int) -> int:
        """The robot's measured state once it stops changing: rests of ``SETTLE_LOOK_S`` while
        each shows another state than the last, for at most ``SETTLE_MAX_S``. After a fault's
        rest (``fault_rest_s``, from the envelope's ``max_duty`` and ``min_cooldown_ms``) a coil
        may still be cooling through its transformation: a six-limb robot with max_duty 1 and
        min_cooldown_ms 300 was measured at 110000 (a shared coil's two limbs still up) 0.6 s
        after a STATE_TIMEOUT, no piece led from there, and learning stopped with "from 110000,
        where the robot rests, no piece … reaches" every transition left, the robot on its way
        to 000000."""
        waited = 0.0
        while waited < SETTLE_MAX_S:
            self._rest(SETTLE_LOOK_S)
            waited += SETTLE_LOOK_S
            now = self.measured_state()
            if now == state:
                break
            state = now
        return state

    def _after_fault(self, e: ExplorationError, driven_s: float) -> list[Trial]:
        """Go on after the robot faulted while making a transition (``e.making_failed``): record
        it (``Failure``) and ask for it no more, rest (``fault_rest_s``), clear the fault and
        return the piece's trials made before it. Re-raises any other stop, and stops (the fault
        left latched) after ``FAULTS_IN_A_ROW`` such faults without a trial between them."""
        t = self.robot.transitions
        edge = None
        if e.making_failed and e.transition is not None:
            edge = t.lookup(t.index(e.transition[0]), t.index(e.transition[1]))
        if edge is None:
            raise e
        a, b = e.transition
        self.log.append(Failure(a, b, e.t_fault, e.what))
        self.failed[edge] = e.what
        self._faults_in_a_row = (0 if e.made else self._faults_in_a_row) + 1
        if self._faults_in_a_row >= FAULTS_IN_A_ROW:
            recent = [f"{f.src}->{f.dst} ({f.fault})" for f in self.log.failures[-FAULTS_IN_A_ROW:]]
            raise ExplorationError(
                f"the robot faulted on {FAULTS_IN_A_ROW} transitions in a row, with no transition made between them: "
                f"{', '.join(recent)}; that is more likely the robot than the transitions (a dead or weak coil, the "
                "supply): each is recorded as not made in the log; once the robot is fixed, run the same command "
                "with --retry-faulted to ask for them again", transition=None, fault=True)
        rest = self.fault_rest_s(driven_s)
        log.warning("warning: learn: the robot could not make %s->%s: %s; recorded as not made and not asked for "
                    "again: cooling %.1f s, then clearing the fault and going on", a, b, e.what, rest)
        self._rest(rest)
        self.client.clear(ClearWhat.FAULTS)
        return e.made

    def _stopped(self, msg: Any, piece: Piece, reached: list, made: list[Trial]) -> ExplorationError:
        """The ``ExplorationError`` for a piece the robot stopped: ``msg`` the EVENT that says
        why (a fault, an E-stop, the gait stopped), named with the transition under way."""
        from ..console.names import RobotNames, describe_event

        t = self.robot.transitions
        kind = int(msg.kind)
        what = describe_event(msg.fields, RobotNames.for_robot(self.robot), t.label).strip()
        when, _, what = what.partition(" ")
        making = _making(t, piece.states, reached)
        during = f" while making {making[0]}->{making[1]}" if making else ""
        failed = kind == EventKind.FAULT and int(msg.code) in MAKING_FAULTS and making is not None
        return ExplorationError(f"the robot stopped{during}: {what} (firmware time {when})",
                                transition=making, fault=kind in (EventKind.FAULT, EventKind.ESTOP),
                                making_failed=failed, made=made, what=what, t_fault=int(msg.time_ms) / 1000.0)

    def fault_rest_s(self, driven_s: float) -> float:
        """The rest after a fault: as long as the piece's drive so far (``driven_s``) needs at
        ``max_duty`` (its coils may have been on all along), at least the rest between pieces,
        and then ``min_cooldown_ms`` more, the cool-down a whole ``max_on_ms`` on-period owes (the
        coil that faulted may have spent all of it)."""
        safety = self.robot.safety
        duty = max(1e-3, float(safety.max_duty))
        return max(self.limits.rest_s, driven_s * (1.0 / duty - 1.0)) + safety.min_cooldown_ms / 1000.0

    def next_piece(self, start: int, demand: np.ndarray) -> Piece | None:
        """The first piece of a random tour from ``start`` that makes at least one transition
        still to do (a few tours are tried); else the shortest way to one of them. Raises
        ``ExplorationError`` naming the transitions no piece from ``start`` can reach within
        the thermal limits. With manual entry, whose pieces are one transition from where the
        robot rests, the others are its normal end: None, and ``left_for_tracker`` names them.
        ``demand`` is over ``self.robot.transitions``; the pieces go over ``plan_table`` (never
        a transition the robot faulted on)."""
        t = self.plan_table()
        demand = np.delete(demand, sorted(self.failed))
        best = plan_piece(t, start, demand, self.limits, None if self.seed is None else self.seed + self.pieces_run)
        if best is None:
            left = [f"{t.label(a)}->{t.label(b)}" for a, b, k in zip(t.src, t.dst, demand) if k > 0]
            if self.ask is not None:  # one transition a piece: the operator measures from where it rests
                self.left_for_tracker = left
                return None
            raise ExplorationError(
                f"from {t.label(start)}, where the robot rests, no piece within the thermal limits ([safety] "
                f"max_on_ms, min_cooldown_ms; the transition durations) reaches {', '.join(left)}")
        return best

    def tally(self) -> tuple[int, int]:
        """(trials recorded toward the goal, trials still to do); transitions no closed tour
        can make are left out of both."""
        t = self.robot.transitions
        goal = self.goal if self.goal is not None else np.full(t.n_transitions, self.repeats)
        goal = np.where(self._unexplored(), 0, goal)
        have = counts(t, self.log.trials)
        return int(np.minimum(goal, have).sum()), int(np.maximum(0, goal - have).sum())

    def _report(self) -> None:
        if self.on_progress is None:
            return
        done, todo = self.tally()
        el = _time.monotonic() - self._t0
        pace = el / max(1, len(self.log.trials) - self._trials0)
        self.on_progress(Progress(done, todo, el, pace * todo))

    def run_piece(self, piece: Piece, record: bool = True) -> list[Trial]:
        """Run one piece from its first state (see the module docstring); ``record``: append
        its trials to the log as they happen."""
        t = self.robot.transitions
        client = self.client
        gait = _closing_gait(self.robot, piece, self.max_steps)
        client.load_gait(gait)
        client.start(GAIT_USER, UNSTATED)  # a probe of transitions walks neither way: not climb-guarded
        goal = len(piece.transitions)
        timeout = (goal + 2) * self.robot.safety.state_timeout_ms / 1000.0
        deadline = self._clock() + timeout
        reached: list[tuple[float, int, Pose | None]] = []
        hit = None  # an on-time hit's FAULT event, until the next frame says whether it latched
        pending: tuple[float, float, int, float | None] | None = None  # (due, event time, state, seen)
        seen: tuple[int, float] | None = None  # telemetry: measured state and since when (firmware s)
        passed: set[int] = set()  # telemetry: every measured state since the last reached one
        out: list[Trial] = []
        try:
            while len(reached) < goal + 1 or pending is not None:
                now = self._clock()
                if pending is not None and now >= pending[0] - CLOCK_EPS_S:
                    _due, t_ev, state, t_seen = pending
                    pending = None
                    pose = self.pose() if self.pose is not None else None
                    if reached:
                        t0, a, p0 = reached[-1]
                        if t.lookup(a, state) is not None:
                            d = planar_delta(p0, pose) if (p0 is not None and pose is not None) else (None, None, None)
                            stray = tuple(t.label(x) for x in sorted(passed) if not between_levels(t.levels, a, state, x))
                            trial = Trial(t.label(a), t.label(state), t0, t_ev, d[0], d[1], d[2], self.source, t_seen,
                                          stray)
                            if record:
                                self.log.append(trial)
                            out.append(trial)
                    reached.append((t_ev, state, pose))
                    passed = set()
                    continue
                if now > deadline:
                    raise ExplorationError(f"piece {'→'.join(t.label(s) for s in piece.states)} did not finish "
                                           f"within {timeout:.0f} s")
                wait = 0.05 if pending is None else max(0.0, min(0.05, pending[0] - now))
                msg = client.recv(wait)
                if msg is not None and msg.name == "TELEMETRY":
                    if hit is not None:  # the frame after an on-time hit: latched, or cooling and going on
                        if int(msg.flags) & Flag.FAULT:
                            raise self._stopped(hit, piece, reached, out)
                        hit = None
                    if not int(msg.flags) & Flag.STATE_UNKNOWN:
                        m = int(msg.measured)
                        passed.add(m)
                        passed.add(psi_state(self.robot, msg.psi))
                        if seen is None or seen[0] != m:
                            seen = (m, int(msg.time_ms) / 1000.0)
                    continue
                if msg is None or msg.name != "EVENT":
                    continue
                kind = int(msg.kind)
                if kind == EventKind.FAULT and int(msg.code) == FaultCode.SMA_ON_LIMIT and hit is None:
                    # the first on-limit hits are reported unlatched: the coil cools and the gait goes on
                    # (docs/safety.md), and a transition merely slow was marked not made
                    hit = msg
                    continue
                if kind in (EventKind.FAULT, EventKind.ESTOP) or (kind == EventKind.GAIT_STOPPED and int(msg.code) != 0):
                    raise self._stopped(hit if hit is not None and kind == EventKind.GAIT_STOPPED else msg,
                                        piece, reached, out)
                if kind != EventKind.STATE_REACHED:
                    continue
                state = int(msg.detail)
                if (reached and reached[-1][1] == state) or pending is not None:
                    continue  # the same state again, or a new one before the last settled (hold too short)
                t_ev = int(msg.time_ms) / 1000.0
                t_seen = seen[1] if seen is not None and seen[0] == state and seen[1] <= t_ev else None
                pending = (self._clock() + self.settle_s, t_ev, state, t_seen)
        finally:
            # STOP, ESTOP if the STOP gets no answer (as run and console leave a robot); a STOP
            # that failed used to raise from here, masking why the piece ended, and sent no ESTOP
            said = stop_robot(client)
            if said != "robot stopped":
                log.warning("warning: %s", said)
        return out


def _making(t, states: tuple[int, ...], reached: list) -> tuple[str, str] | None:
    """(from, to) labels of the piece's transition under way, given the states ``reached``
    so far (the first is the piece's start); None before the start is reached."""
    k = len(reached)
    if k == 0 or k >= len(states):
        return None
    return t.label(reached[-1][1]), t.label(states[k])
