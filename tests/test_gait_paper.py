"""The paper's robots (SPEC §1): answers from the definitions, some checked by hand.

State order 00, 01, 10, 11 (indices 0..3). T[a][b]: row = from, column = to.
The paper's l_max counts listed states including the return, so l_max = 4 means at most
3 transitions and "l_max <= 5" at most 4.
"""

from __future__ import annotations

import numpy as np
import pytest

from proleg.gait import evaluate_sequence, optimal_gaits
from proleg.gait.bruteforce import brute_force_gaits
from proleg.transitions import TransitionTable

X = None  # forbidden
R1 = [[0, -1, 1, 0], [1, 0, 0, -1], [-1, 0, 0, 1], [0, 0, 0, 0]]
R2 = [[0, 1, -1, 0], [-1, 0, 0, 1], [1, 0, 0, -1], [0, 0, 0, 0]]
R3 = [[0, -1, 1, 1], [1, 0, 0, -1], [-1, -1, 0, -1], [-1, 1, 0, 0]]
R1_ONE_ACTUATOR = [[0, X, 1, X], [X, X, X, X], [-1, X, 0, 1], [X, X, 0, 0]]


def table(matrix) -> TransitionTable:
    allowed = np.array([[v is not None for v in row] for row in matrix])
    reward = np.array([[0 if v is None else v for v in row] for row in matrix], dtype=float)
    return TransitionTable.from_dense((2, 2), reward, allowed)


def labels(t: TransitionTable, result) -> list[str]:
    return [" ".join(t.label(s) for s in g.states) for g in result.gaits]


ROBOTS = {"R1": R1, "R2": R2, "R3": R3, "R1-one-actuator": R1_ONE_ACTUATOR}


@pytest.mark.parametrize("robot", sorted(ROBOTS))
@pytest.mark.parametrize("objective", ["total", "rate"])
@pytest.mark.parametrize("direction", ["+x", "-x"])
@pytest.mark.parametrize("bound", [None, 2, 3, 4])
def test_paper_robots_match_the_oracle(robot, objective, direction, bound):
    t = table(ROBOTS[robot])
    result = optimal_gaits(t, objective, direction, bound)
    value, ties = brute_force_gaits(t, objective, direction, bound)
    assert result.value == value
    assert {g.states for g in result.gaits} == ties


def test_r1_forward_within_three_transitions_has_two_tied_gaits_worth_2():
    # 00->10->01->00 = T[00][10] + T[10][01] + T[01][00] = 1 + 0 + 1 = 2 (the paper's C_T1)
    # 00->10->11->00 = T[00][10] + T[10][11] + T[11][00] = 1 + 1 + 0 = 2 (a tie the prose omits)
    # The paper's prose reports +4 for C_T1; the matrix gives +2 per cycle, and we follow the matrix.
    t = table(R1)
    result = optimal_gaits(t, "total", "+x", max_transitions=3)
    assert result.value == 2.0
    assert labels(t, result) == ["00 10 01 00", "00 10 11 00"]


def test_r1_forward_within_four_transitions_visits_every_state_for_3():
    # 00->10->11->01->00 = 1 + 1 + 0 + 1 = 3; any 4-transition walk through a repeated
    # state splits into two 2-cycles, each worth T[a][b] + T[b][a] <= 0 in R1.
    t = table(R1)
    result = optimal_gaits(t, "total", "+x", max_transitions=4)
    assert result.value == 3.0
    assert labels(t, result) == ["00 10 11 01 00"]
    assert optimal_gaits(t, "rate", "+x").value == 0.75


def test_r2_is_r1_mirrored_so_its_backward_gait_is_r1s_forward_gait():
    # R2 = -R1 elementwise, so +x and -x swap: -x within 3 transitions is C_T1 and its tie.
    t = table(R2)
    result = optimal_gaits(t, "total", "-x", max_transitions=3)
    assert result.value == -2.0
    assert labels(t, result) == ["00 10 01 00", "00 10 11 00"]


def test_r3_matrix_disagrees_with_the_prose_about_its_best_sequences():
    # The prose: R3 goes forward with C_T1 (00 10 01 00) and backward with C_T2 (00 01 10 00).
    # By the matrix: C_T1 = 1 + (-1) + 1 = 1 and C_T2 = -1 + 0 + (-1) = -2, but
    # 00->11->01->00 = T[00][11] + T[11][01] + T[01][00] = 1 + 1 + 1 = 3 forward and
    # 00->01->11->00 = -1 + (-1) + (-1) = -3 backward are better. We follow the matrix.
    t = table(R3)
    assert evaluate_sequence(t, ["00", "10", "01", "00"]).reward == 1.0
    assert evaluate_sequence(t, ["00", "01", "10", "00"]).reward == -2.0
    fwd = optimal_gaits(t, "total", "+x", max_transitions=3)
    back = optimal_gaits(t, "total", "-x", max_transitions=3)
    assert (fwd.value, labels(t, fwd)) == (3.0, ["00 11 01 00"])
    assert (back.value, labels(t, back)) == (-3.0, ["00 01 11 00"])


def test_r1_with_one_actuator_moves_forward_by_2_repeating_its_short_cycle():
    # Allowed: 00<->10, 10<->11 (11->10 worth 0). 10->11->10 = 1 + 0 = 1;
    # 00->10->11->10->00 = 1 + 1 + 0 + (-1) = 1; 00->10->00 = 1 - 1 = 0. Every closed walk has
    # an even length. Within 4 transitions (the paper's l_max <= 5) the paper lists C_L1 and
    # C_L2, both worth 1; but the firmware runs a gait cyclically, and 10->11->10 run twice,
    # (10 11)^2, is a closed walk of 4 transitions worth 2: better than C_L2, so gait 0 is C_L1
    # with repeats = 2 (issue 14: repeated cycles are candidates, not separate gaits).
    t = table(R1_ONE_ACTUATOR)
    result = optimal_gaits(t, "total", "+x", max_transitions=4)
    assert result.value == 2.0
    assert labels(t, result) == ["10 11 10"]
    assert (result.gaits[0].reward, result.gaits[0].repeats, result.gaits[0].total) == (1.0, 2, 2.0)
    assert optimal_gaits(t, "total", "+x").gaits == result.gaits  # default bound: 4 states
    within_three = optimal_gaits(t, "total", "+x", max_transitions=3)
    assert (within_three.value, labels(t, within_three), within_three.gaits[0].repeats) == (1.0, ["10 11 10"], 1)
    rate = optimal_gaits(t, "rate", "+x")
    assert (rate.value, labels(t, rate)) == (0.5, ["10 11 10"])


def test_r1_with_one_actuator_cannot_move_backward():
    # The only simple cycles are 00 10 00 (J = 0) and 10 11 10 (J = 1), and every closed walk
    # is made of them, so no walk has J < 0.
    t = table(R1_ONE_ACTUATOR)
    for objective in ("total", "rate"):
        result = optimal_gaits(t, objective, "-x", max_transitions=4)
        assert result.value is None and result.gaits == ()
