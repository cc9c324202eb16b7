"""evaluate_sequence: scoring a sequence a user typed, and the errors it reports."""

from __future__ import annotations

import numpy as np
import pytest

from proleg.errors import GaitError
from proleg.gait import Gait, evaluate_sequence
from proleg.gait.evaluate import canonical_rotation, is_primitive
from proleg.transitions import TransitionTable

R1_ONE_ACTUATOR_REWARD = [[0, 0, 1, 0], [0, 0, 0, 0], [-1, 0, 0, 1], [0, 0, 0, 0]]
R1_ONE_ACTUATOR_ALLOWED = [[0, 0, 1, 0], [0, 0, 0, 0], [1, 0, 0, 1], [0, 0, 1, 0]]


@pytest.fixture
def one_actuator() -> TransitionTable:
    dur = np.full((4, 4), 2.0)
    return TransitionTable.from_dense((2, 2), R1_ONE_ACTUATOR_REWARD, R1_ONE_ACTUATOR_ALLOWED, dur)


def test_valid_sequence_is_scored_and_rotated_to_its_canonical_start(one_actuator):
    g = evaluate_sequence(one_actuator, [2, 3, 2, 0, 2])
    assert g == Gait(states=(0, 2, 3, 2, 0), reward=1.0, transitions=4, rate=0.25, duration=8.0)
    assert g.speed == 0.125


def test_labels_are_accepted(one_actuator):
    assert evaluate_sequence(one_actuator, ["10", "11", "10"]).reward == 1.0


def test_forbidden_transition_is_named_with_labels(one_actuator):
    with pytest.raises(GaitError, match=r"transition 00 -> 11 is forbidden"):
        evaluate_sequence(one_actuator, ["00", "11", "10", "00"])


def test_first_bad_transition_is_the_one_reported(one_actuator):
    with pytest.raises(GaitError, match=r"transition 10 -> 01 is forbidden \(step 2"):
        evaluate_sequence(one_actuator, ["00", "10", "01", "11", "00"])


def test_staying_in_a_state_is_not_a_transition(one_actuator):
    with pytest.raises(GaitError, match=r"10 -> 10 does not change state"):
        evaluate_sequence(one_actuator, ["00", "10", "10", "00"])


def test_sequence_must_return_to_its_start(one_actuator):
    with pytest.raises(GaitError, match=r"sequence must return to its start: it starts at 00 and ends at 11"):
        evaluate_sequence(one_actuator, ["00", "10", "11"])


@pytest.mark.parametrize("seq", [[], [0], [0, 0]])
def test_too_short_sequence_is_rejected(one_actuator, seq):
    with pytest.raises(GaitError, match=r"at least 2 transitions"):
        evaluate_sequence(one_actuator, seq)


@pytest.mark.parametrize("bad", [4, -1, "12", "0", "abc", 1.5, None])
def test_unknown_state_is_rejected(one_actuator, bad):
    with pytest.raises(GaitError, match=r"state 2 of the sequence"):
        evaluate_sequence(one_actuator, [0, bad, 0])


def test_multi_level_labels():
    t = TransitionTable.from_dense((3, 2), np.arange(36).reshape(6, 6))
    g = evaluate_sequence(t, ["21", "00", "21"])  # index 5 -> 0 -> 5: T[5][0] + T[0][5] = 30 + 5
    assert (g.states, g.reward) == ((0, 5, 0), 35.0)


def test_canonical_rotation_starts_at_the_lowest_state_and_is_lexicographically_smallest():
    assert canonical_rotation((3, 1, 2, 1, 0)) == (0, 3, 1, 2, 1)
    assert canonical_rotation((1, 3, 1, 2)) == (1, 2, 1, 3)
    assert is_primitive((1, 2, 1, 3)) and not is_primitive((1, 2, 1, 2)) and not is_primitive((4, 4))
