"""proleg.link.direction: START's direction byte from what a caller says, and back."""

from __future__ import annotations

import pytest
from proleg.errors import LinkError
from proleg.link.direction import UNSTATED, direction_code, direction_text, parse_direction
from proleg.protocol.definition import DIR_UNSTATED, GAIT_USER, Direction


@pytest.mark.parametrize("said, way", [
    ("+x", Direction.PLUS_X), (" X ", Direction.PLUS_X), ("plus_x", Direction.PLUS_X), ("+", Direction.PLUS_X),
    ("-x", Direction.MINUS_X), ("MINUS_X", Direction.MINUS_X), ("-", Direction.MINUS_X),
    (0, Direction.PLUS_X), (1, Direction.MINUS_X), (Direction.MINUS_X, Direction.MINUS_X),
])
def test_every_spelling_of_a_way_is_its_direction_and_reads_back_as_text(said, way):
    assert parse_direction(said) is way
    assert direction_code(said, 0) == int(way)
    assert direction_text(direction_code(said, 0)) == ("+x" if way is Direction.PLUS_X else "-x")


@pytest.mark.parametrize("said, text", [("up", "expected +x or -x"), (7, "expected 0 (+x) or 1 (-x)")])
def test_an_unknown_way_is_a_link_error_saying_what_is_expected(said, text):
    with pytest.raises(LinkError) as e:
        parse_direction(said)
    assert f"unknown direction {said!r}; {text}" in str(e.value)


def test_only_the_loaded_sequence_may_leave_its_way_unstated():
    assert direction_code(UNSTATED, GAIT_USER) == DIR_UNSTATED == direction_code(DIR_UNSTATED, GAIT_USER)
    assert direction_text(DIR_UNSTATED) == UNSTATED
    with pytest.raises(LinkError, match="only the loaded sequence"):
        direction_code(UNSTATED, 0)
    assert direction_text(9) == "?9"
