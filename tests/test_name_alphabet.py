"""Robot, limb, actuator and board names share one alphabet (robot_limbs.name_re): the
length limits differ, the characters do not, and ``too_long`` counts exactly the names that
are right but for their length (it spelled the alphabet a second time)."""

from __future__ import annotations

from hypothesis import given
from hypothesis import strategies as st

from proleg.firmware.boards import BOARD_NAME_RE
from proleg.robot import NAME_RE, ROBOT_NAME_RE
from proleg.robot_limbs import name_re, too_long


@given(st.text(alphabet="az09-_A \n", max_size=70), st.integers(1, 64))
def test_a_name_is_refused_for_its_length_with_a_count_only_when_its_characters_are_right(name, limit):
    fits = name_re(limit).fullmatch(name) is not None
    assert fits == (too_long(name) != "" and len(name) <= limit)
    if too_long(name):
        assert too_long(name) == f" ({len(name)} characters)"


def test_every_kind_of_name_uses_the_one_alphabet_with_its_own_limit():
    for pattern, limit in ((NAME_RE, 15), (BOARD_NAME_RE, 15), (ROBOT_NAME_RE, 63)):
        assert pattern.pattern == name_re(limit).pattern
        assert pattern.fullmatch("a" * limit) and not pattern.fullmatch("a" * (limit + 1))
        assert not pattern.fullmatch("-a") and not pattern.fullmatch("a_b") and not pattern.fullmatch("a\n")
