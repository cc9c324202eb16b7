"""The exploration loop's planning and its guard against endless runs (no robot needed:
the piece runner is replaced, so these check the loop's decisions only)."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from proleg.learn.measure import TrialLog
from proleg.learn.runner import STALL_PIECES, ExplorationError, Explorer
from proleg.protocol.definition import EventKind
from proleg.robot import load_robot

ROBOTS = Path(__file__).resolve().parent.parent / "robots"


class _Offline(Explorer):
    """An Explorer whose robot rests in ``rest`` and never moves (run_piece makes nothing)."""

    def __init__(self, robot, log, rest: int = 0, **kw):
        client = SimpleNamespace(info=None, link=SimpleNamespace(clock=lambda: 0.0), set_telemetry_rate=lambda hz: None)
        super().__init__(client, robot, log, None, rest=lambda s: None, **kw)
        self.rest_state = rest
        self.ran: list[tuple[int, ...]] = []

    def measured_state(self) -> int:
        return self.rest_state

    def run_piece(self, piece, record=True):
        self.ran.append(piece.states)
        return []


def test_a_robot_that_does_not_follow_the_plan_ends_the_run_with_what_is_left(tmp_path):
    robot = load_robot(ROBOTS / "inchworm-3.toml")
    with TrialLog(tmp_path / "t.jsonl") as log:
        ex = _Offline(robot, log, repeats=1, seed=1)
        with pytest.raises(ExplorationError, match=r"5 pieces in a row made none of the transitions still to do "
                                                    r"\(000->001, .*111->110\).*same --log"):
            ex.run()
    assert len(ex.ran) == STALL_PIECES


def test_every_piece_starts_where_the_robot_rests_and_makes_a_transition_still_to_do(tmp_path):
    robot = load_robot(ROBOTS / "inchworm-3.toml")
    t = robot.transitions
    with TrialLog(tmp_path / "t.jsonl") as log:
        ex = _Offline(robot, log, rest=t.index("000"), repeats=1, seed=2)
        demand = np.zeros(t.n_transitions, dtype=np.int64)
        demand[t.lookup(t.index("111"), t.index("110"))] = 1  # only the far corner is left
        for _ in range(20):
            piece = ex.next_piece(t.index("000"), demand)
            ex.pieces_run += 1
            assert piece.states[0] == t.index("000") and piece.loadable
            assert (t.index("111"), t.index("110")) in piece.transitions


def test_a_piece_is_planned_from_a_tour_of_a_bounded_demand_however_many_trials_are_asked(tmp_path, monkeypatch):
    """Only a tour's first piece is used, so its tour need not cover every trial still to do:
    --repeats 999999999 planned a tour of 12e9 transitions for R1's first piece (10 GB in 16 s,
    no trial made), and --more's 100,000 extra trials took 10 s a piece."""
    import proleg.learn.next_piece as planner

    robot = load_robot(ROBOTS / "inchworm-3.toml")
    t = robot.transitions
    planned: list[int] = []

    def bounded(table, demand=None, **kw):
        planned.append(int(np.max(demand)))
        assert planned[-1] <= 1000, f"a tour planned for {planned[-1]} trials of a transition"
        return real(table, demand=demand, **kw)

    real = planner.exploration
    monkeypatch.setattr(planner, "exploration", bounded)
    with TrialLog(tmp_path / "t.jsonl") as log:
        ex = _Offline(robot, log, rest=t.index("000"), repeats=10**9, seed=1)
        piece = ex.next_piece(t.index("000"), np.full(t.n_transitions, 10**9, dtype=np.int64))
    assert planned and piece.states[0] == t.index("000") and piece.loadable and piece.transitions


def test_a_transition_no_piece_can_reach_is_named_before_the_robot_moves(tmp_path):
    robot = load_robot(ROBOTS / "inchworm-3.toml")
    t = robot.transitions
    with TrialLog(tmp_path / "t.jsonl") as log:
        ex = _Offline(robot, log, repeats=1)
        ex.limits = replace(ex.limits, max_on_s=1.0)  # one 0.8 s transition per piece
        demand = np.zeros(t.n_transitions, dtype=np.int64)
        demand[t.lookup(t.index("111"), t.index("110"))] = 1
        with pytest.raises(ExplorationError, match=r"from 000, where the robot rests, no piece within the "
                                                    r"thermal limits .* reaches 111->110"):
            ex.next_piece(t.index("000"), demand)


class _Idle:
    """A board that says nothing (SimLink's duck type)."""

    def write(self, data: bytes) -> None:
        pass

    def read(self) -> bytes:
        return b""

    def advance(self, seconds: float) -> None:
        pass


def test_a_rest_on_a_simulated_link_ends_whatever_the_clock_reads(tmp_path):
    """The simulated link counts whole nanoseconds: a rest whose end fell a fraction of one
    after the clock's last tick waited for ever (inchworm-3's proof hung in a rest from 7.158 s)."""
    from proleg.link import RobotClient
    from proleg.link.sim_link import SimLink

    robot = load_robot(ROBOTS / "inchworm-3.toml")
    link = SimLink(_Idle())
    client = RobotClient(link)
    calls = []
    recv = client.recv

    def counting(timeout=0.0):
        calls.append(timeout)
        if len(calls) > 100:
            raise AssertionError("the rest does not end")
        return recv(timeout)

    client.recv = counting
    with TrialLog(tmp_path / "t.jsonl") as log:
        ex = Explorer(client, robot, log, None)
        for start_ns in (7_158_000_000, *range(1_000_000, 40_000_000, 1_000_000)):  # 7.158 + 2.25 > 9.408
            link._t_ns = start_ns
            calls.clear()
            ex._rest_on_link(2.25)
            assert link.clock() == pytest.approx(start_ns / 1e9 + 2.25, abs=1e-6)


class _Scripted:
    """A robot client that plays a script of (telemetry measured state | reached state) on a
    clock that moves 10 ms per read. A telemetry frame's ψ (0.01°) is 25° for a raised limb
    and 0° for a lowered one (inchworm-3: ψ* 20°, band ±1°), unless the script gives it as a
    third item."""

    def __init__(self, script, levels=(2, 2, 2)):
        self.levels = levels
        self.script = list(script)
        self.t = 0.0
        self.link = SimpleNamespace(clock=lambda: self.t)
        self.info = None

    def load_gait(self, states):
        pass

    def start(self, gait, direction):
        pass

    def request(self, name, **kw):  # STOP at the piece's end
        pass

    def recv(self, timeout=0.0):
        self.t += 0.01
        if not self.script:
            return None
        kind, state, *psi = self.script.pop(0)
        ms = int(self.t * 1000)
        if kind == "tel":
            from proleg.states import limb_levels

            psi = psi[0] if psi else [2500 * level for level in limb_levels(state, self.levels)]
            return SimpleNamespace(name="TELEMETRY", flags=0, measured=state, time_ms=ms, psi=psi)
        return SimpleNamespace(name="EVENT", kind=int(EventKind.STATE_REACHED), detail=state, time_ms=ms, code=0)


def test_a_transition_that_passes_through_a_state_outside_it_says_so_in_its_trial(tmp_path):
    """100 → 110 raises the middle limb; telemetry that shows 111 on the way means the head
    limb, which should have held, crossed too: the trial is kept (it is what the robot did
    when asked for 100 → 110) and names 111, so that the report can say how often."""
    from proleg.learn.measure import Trial
    from proleg.learn.pieces import Piece

    robot = load_robot(ROBOTS / "inchworm-3.toml")
    t = robot.transitions
    s = {label: t.index(label) for label in ("000", "100", "110", "111")}

    def reached(label):  # each reached state is held a while: its pose is taken 50 ms after the event
        return [("tel", s[label]), ("reached", s[label])] + [("tel", s[label])] * 8

    script = reached("000") + reached("100") + [("tel", s["111"])] + reached("110")
    with TrialLog(tmp_path / "t.jsonl") as log:
        ex = Explorer(_Scripted(script), robot, log, None, rest=lambda s: None)
        made = ex.run_piece(Piece((s["000"], s["100"], s["110"]), True, 0.0, 1.6))
    assert [(tr.src, tr.dst, tr.passed) for tr in made] == [("000", "100", ()), ("100", "110", ("111",))]
    lines = (tmp_path / "t.jsonl").read_text().splitlines()
    assert '"passed"' not in lines[-2] and Trial.from_json(lines[-1]).passed == ("111",)


def test_a_held_limb_that_sags_across_psi_star_inside_the_band_is_seen(tmp_path):
    """100 → 110: the rear limb should hold. Its ψ sags to 19.5°, past ψ* = 20° (the contact's
    friction changes there) but inside the band 19–21°, so the measured state stays 100; ψ read
    against the bare ψ* shows 000, outside the transition, and the trial names it."""
    from proleg.learn.pieces import Piece

    robot = load_robot(ROBOTS / "inchworm-3.toml")
    t = robot.transitions
    s = {label: t.index(label) for label in ("000", "100", "110")}

    def reached(label):
        return [("tel", s[label]), ("reached", s[label])] + [("tel", s[label])] * 8

    sag = [("tel", s["100"], [1950, 0, 0]), ("tel", s["100"], [1950, 1500, 0])]
    noise = [("tel", s["100"], [2020, 900, 0])]  # inside the band, above ψ*: nothing crossed
    with TrialLog(tmp_path / "t.jsonl") as log:
        made = Explorer(_Scripted(reached("000") + reached("100") + sag + reached("110")), robot, log, None,
                        rest=lambda s: None).run_piece(Piece((s["000"], s["100"], s["110"]), True, 0.0, 1.6))
        held = Explorer(_Scripted(reached("000") + reached("100") + noise + reached("110")), robot, log, None,
                        rest=lambda s: None).run_piece(Piece((s["000"], s["100"], s["110"]), True, 0.0, 1.6))
    assert [(tr.src, tr.dst, tr.passed) for tr in made] == [("000", "100", ()), ("100", "110", ("000",))]
    assert [tr.passed for tr in held] == [(), ()]


def test_psi_state_counts_the_psi_stars_each_limb_is_at_or_past():
    from proleg.learn.runner import psi_state
    from proleg.states import index

    robot = load_robot(ROBOTS / "inchworm-3.toml")
    assert psi_state(robot, [2000, 1999, -4000]) == index("100", robot.levels)
    assert psi_state(robot, [8000, 2001, 2000]) == index("111", robot.levels)


def test_between_is_every_state_on_a_monotone_way_from_a_to_b():
    """The oracle walks: from a, one limb one level at a time, each only towards its level in
    b; the states met on any such way are the ones a transition a → b may pass through."""
    from itertools import product

    from proleg.learn.measure import between_levels as _between
    from proleg.states import DIGITS, index, limb_levels

    levels = (2, 3, 2)
    n = 12

    def walk(a: int, b: int) -> set[int]:
        lb = limb_levels(b, levels)
        seen, todo = {a}, [a]
        while todo:
            cur = list(limb_levels(todo.pop(), levels))
            for i in range(len(levels)):
                if cur[i] != lb[i]:
                    nxt = cur.copy()
                    nxt[i] += 1 if lb[i] > cur[i] else -1
                    s = index("".join(DIGITS[v] for v in nxt), levels)
                    if s not in seen:
                        seen.add(s)
                        todo.append(s)
        assert b in seen
        return seen

    for a, b in product(range(n), repeat=2):
        way = walk(a, b)
        assert {x for x in range(n) if _between(levels, a, b, x)} == way
    assert _between(levels, 0, 0, 0) and not _between(levels, 0, 0, 1)


class _RateBoard:
    """A client whose board takes telemetry rates up to ``limit`` Hz and sends frames from a
    script of (flags, measured)."""

    def __init__(self, limit, frames=()):
        from proleg.link.client import CommandRefused

        self.limit, self.frames, self.rates, self.refused = limit, list(frames), [], CommandRefused
        self.info, self.link = None, SimpleNamespace(clock=lambda: 0.0)

    def set_telemetry_rate(self, hz):
        if hz > self.limit:
            raise self.refused("SET_TELEMETRY_RATE", 3, 0, "fake")
        self.rates.append(hz)

    def telemetry(self, timeout=1.0, count=None):
        for k, (flags, measured) in enumerate(self.frames):
            if count is not None and k >= count:
                return
            yield SimpleNamespace(flags=flags, measured=measured)


def test_an_exploration_watches_at_the_fastest_rate_the_board_takes_and_gives_the_old_one_back(tmp_path):
    robot = load_robot(ROBOTS / "inchworm-3.toml")
    with TrialLog(tmp_path / "t.jsonl") as log:
        board = _RateBoard(limit=160)
        ex = Explorer(board, robot, log, None, rest=lambda s: None, repeats=0)
        ex.run()
    assert board.rates == [150, robot.control.telemetry_hz]  # 250 and 200 refused; restored after
    with TrialLog(tmp_path / "u.jsonl") as log:
        board = _RateBoard(limit=robot.control.telemetry_hz)  # the board takes nothing faster
        Explorer(board, robot, log, None, rest=lambda s: None, repeats=0).run()
    assert board.rates == []


def test_the_measured_state_skips_frames_whose_state_is_unknown(tmp_path):
    from proleg.protocol.definition import Flag

    robot = load_robot(ROBOTS / "inchworm-3.toml")
    unknown = int(Flag.STATE_UNKNOWN)
    with TrialLog(tmp_path / "t.jsonl") as log:
        board = _RateBoard(0, [(unknown, 0xFFFF), (0, 5), (unknown, 0xFFFF), (0, 5), (0, 5), (0, 1)])
        assert Explorer(board, robot, log, None).measured_state() == 5
        board.frames = [(unknown, 0xFFFF)] * 300
        with pytest.raises(ExplorationError, match="state stayed unknown over 200 telemetry frames"):
            Explorer(board, robot, log, None).measured_state()


def test_a_piece_whose_stop_gets_no_answer_e_stops_and_keeps_why_it_ended(tmp_path, caplog):
    """A piece ends with STOP; unanswered, ESTOP follows (as run and console leave a robot),
    and the piece's own error is what the caller sees. It used to be client.stop() alone: its
    LinkError replaced the piece's error and no ESTOP was sent."""
    import logging

    from proleg.errors import LinkError

    sent: list[str] = []
    clock = iter(range(0, 10**6, 5))  # 5 s a look: the piece's deadline passes at once

    def request(name, **kw):
        sent.append(name)
        if name == "STOP":
            raise LinkError("no ACK for STOP within 3 s")

    client = SimpleNamespace(info=None, link=SimpleNamespace(clock=lambda: float(next(clock))),
                             set_telemetry_rate=lambda hz: None, load_gait=lambda states: None,
                             start=lambda gait, direction: None, recv=lambda wait: None, request=request)
    robot = load_robot(ROBOTS / "paper-r1.toml")
    with TrialLog(tmp_path / "t.jsonl") as log:
        ex = Explorer(client, robot, log, None, rest=lambda s: None)
        piece = SimpleNamespace(states=(0, 2, 0), transitions=((0, 2), (2, 0)), loadable=True, gait=lambda: (0, 2))
        with caplog.at_level(logging.WARNING, logger="proleg"), \
                pytest.raises(ExplorationError, match="did not finish within"):
            ex.run_piece(piece)
    assert sent == ["STOP", "ESTOP"]
    assert any("STOP not acknowledged" in r.getMessage() and "E-stopped" in r.getMessage() for r in caplog.records)
