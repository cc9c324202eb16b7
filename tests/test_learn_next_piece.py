"""learn.next_piece: which piece an exploration runs next, without a link or an Explorer."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np

from proleg.learn.next_piece import plan_piece
from proleg.learn.pieces import limits_for
from proleg.learn.tours import _bfs_path, successors
from proleg.robot import load_robot

ROBOTS = Path(__file__).resolve().parent.parent / "robots"


def test_a_planned_piece_starts_where_the_robot_is_loads_and_makes_a_transition_still_to_do():
    """For every start and every single transition left to do on inchworm-3: a piece exactly
    when a walk from the start to it exists (every one fits R1-like limits here), and the
    same seed plans the same piece."""
    robot = load_robot(ROBOTS / "inchworm-3.toml")
    t = robot.transitions
    limits = limits_for(robot)
    succ = successors(t)
    for start in range(t.n_states):
        for k, (a, b) in enumerate(zip(t.src.tolist(), t.dst.tolist())):
            demand = np.zeros(t.n_transitions, dtype=np.int64)
            demand[k] = 3
            piece = plan_piece(t, start, demand, limits, seed=k)
            if _bfs_path(t.n_states, succ, start, a) is None:
                assert piece is None
                continue
            assert piece is not None and piece.loadable and piece.states[0] == start
            assert (a, b) in piece.transitions
            assert plan_piece(t, start, demand, limits, seed=k) == piece


def test_no_piece_within_the_limits_is_none_for_the_caller_to_name():
    robot = load_robot(ROBOTS / "inchworm-3.toml")
    t = robot.transitions
    demand = np.zeros(t.n_transitions, dtype=np.int64)
    demand[t.lookup(t.index("111"), t.index("110"))] = 1
    limits = replace(limits_for(robot), max_on_s=1.0)  # one 0.8 s transition per piece
    assert plan_piece(t, t.index("000"), demand, limits, seed=1) is None
    assert plan_piece(t, t.index("111"), demand, limits, seed=1).transitions == [(t.index("111"), t.index("110"))]
