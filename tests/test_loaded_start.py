"""Where a loaded gait starts (gait/feasibility.py: loaded_start, rest_start_warning).

The firmware starts a LOAD_GAIT sequence at the step whose state the robot stands in, else at
its first step, straight from where it stands: a loaded gait has no entry path. ``loaded_start``
rotates such a gait to begin at its first state the robot can step into; checked here against a
brute-force oracle over every example robot, and the warning ``proleg load-gait`` prints for a
gait whose first step from rest is one the robot cannot make.
"""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from proleg.cli.main import main
from proleg.errors import GaitError
from proleg.gait.feasibility import loaded_start, rest_start_warning, step_problems
from proleg.paths import robots_dir
from proleg.robot import load_robot

ROBOTS = {p.stem: load_robot(p) for p in sorted(robots_dir().glob("*.toml"))
          if load_robot(p).transitions.n_states <= 64}


def _steppable(robot, a: int, b: int) -> bool:
    """The oracle's own reading of a step the robot can make: an entry of the matrix, and no
    error among the step's problems."""
    if robot.transitions.lookup(a, b) is None:
        return False
    return all(severity != "error" for _, severity, _ in step_problems(robot, a, b))


@st.composite
def cases(draw):
    name = draw(st.sampled_from(sorted(ROBOTS)))
    n = ROBOTS[name].transitions.n_states
    states = draw(st.lists(st.integers(0, n - 1), min_size=2, max_size=6)
                  .filter(lambda s: all(a != b for a, b in zip(s, s[1:] + s[:1]))))  # a gait never repeats a state
    return name, states, draw(st.integers(0, n - 1))


@settings(max_examples=300, deadline=None)
@given(cases())
def test_loaded_start_is_the_first_phase_the_robot_can_step_into(case):
    name, states, standing = case
    robot = ROBOTS[name]
    first_ok = [k for k, s in enumerate(states) if _steppable(robot, standing, s)]
    if standing in states:
        assert loaded_start(robot, states, standing) == states
    elif not first_ok:
        with pytest.raises(GaitError, match=f"stands in {robot.transitions.label(standing)}"):
            loaded_start(robot, states, standing)
    else:
        k = first_ok[0]
        assert loaded_start(robot, states, standing) == states[k:] + states[:k]


def test_a_closed_walk_is_opened_first():
    robot = ROBOTS["paper-r1-one-actuator"]
    assert loaded_start(robot, [3, 2, 3], 0) == [2, 3]  # 11 → 10 → 11 from rest: into 10 first


def test_a_gait_through_rest_or_stepped_into_from_rest_gets_no_warning():
    r1, one = ROBOTS["paper-r1"], ROBOTS["paper-r1-one-actuator"]
    assert rest_start_warning(r1, [0, 2, 3, 1]) is None
    assert rest_start_warning(one, [2, 3]) is None  # C_L2 = 10 → 11 → 10: 00 → 10 is allowed
    line = rest_start_warning(one, [3, 2])
    assert line is not None and "steps straight into 11, forbidden in the robot file" in line
    assert line.endswith("load it from 10: 10 11 10")
    line = rest_start_warning(one, [1, 3])
    assert line is not None and line.endswith("start it from one of its states")


def test_load_gait_warns_of_a_first_step_from_rest_the_robot_cannot_make(capsys):
    code = main(["load-gait", "paper-r1-one-actuator", "--sim", "11,10"])
    out, err = capsys.readouterr()
    assert code == 0, err
    assert "loaded 11 → 10 → 11" in out
    warned = [ln for ln in err.splitlines() if "steps straight into 11" in ln]
    assert len(warned) == 1 and "load it from 10: 10 11 10" in warned[0]
    main(["load-gait", "paper-r1-one-actuator", "--sim", "10,11"])
    assert "steps straight into" not in capsys.readouterr().err
