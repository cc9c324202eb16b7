"""State labels and limb levels: which gait steps move limbs in opposite directions."""

from hypothesis import given, settings
from hypothesis import strategies as st

from proleg import states
from proleg.states import limb_levels, opposing_steps


def index(levels, limb_values):
    i = 0
    for k, v in zip(levels, limb_values):
        i = i * k + v
    return i


def test_a_step_is_opposing_only_when_one_limb_rises_and_another_falls():
    levels = (3, 2)  # a three-level left limb, a binary right limb
    walk = [(0, 0), (2, 1), (1, 1), (2, 0), (0, 1), (0, 0)]
    states = [index(levels, w) for w in walk]
    assert [limb_levels(s, levels) for s in states] == walk
    # (0,0)->(2,1) both up; (2,1)->(1,1) one down; (1,1)->(2,0) up and down;
    # (2,0)->(0,1) down and up; (0,1)->(0,0) one down
    assert opposing_steps(states, levels) == [2, 3]


def test_a_walk_of_single_limb_steps_has_no_opposing_step():
    levels = (2, 2)
    assert opposing_steps([0, 2, 3, 1, 0], levels) == []
    assert opposing_steps([0, 1, 2, 3, 0], levels) == [1]


def test_a_digit_out_of_its_limbs_range_says_which_digit_on_a_robot_of_mixed_levels():
    """'02' on a three-level limb and a binary one: the message said "digit '2' is not a level
    0..1", while the first limb does have a level 2; it names the place now."""
    import pytest

    from proleg.states import index as state_index

    assert state_index("21", (3, 2)) == 5
    with pytest.raises(ValueError, match=r"state label '02': digit 2 \('2'\) is not a level of limb #2, 0\.\.1$"):
        state_index("02", (3, 2))
    # the digit as typed (a letter O for a zero), not lower-cased
    with pytest.raises(ValueError, match=r"state label '1O': digit 2 \('O'\) is not a level of limb 'b', 0\.\.1$"):
        state_index("1O", (2, 2), ("a", "b"))


@st.composite
def _limbs_at(draw):
    """Limbs of 2..4 levels (ascending thresholds) and a ψ for each."""
    n = draw(st.integers(1, 5))
    thresholds = []
    for _ in range(n):
        k = draw(st.integers(2, 4))
        thresholds.append(sorted(draw(st.lists(st.floats(1.0, 80.0), min_size=k - 1, max_size=k - 1, unique=True))))
    psi = draw(st.lists(st.floats(-10.0, 90.0), min_size=n, max_size=n))
    return thresholds, psi


@settings(max_examples=200, deadline=None)
@given(_limbs_at())
def test_classify_reads_the_state_the_limbs_levels_spell(limbs):
    """The plants' state from ψ is the label whose digit for each limb counts the thresholds its ψ
    has reached (the brute force: write the label, read it back with ``states.index``)."""
    thresholds, psi = limbs
    levels = [len(t) + 1 for t in thresholds]
    digits = "".join(str(sum(p >= th for th in ths)) for p, ths in zip(psi, thresholds))
    assert states.classify(psi, thresholds, states.place_values(levels)) == states.index(digits, levels)
