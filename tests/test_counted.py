"""Counts in messages read as English: ``names.counted`` and a message that used to say
"reading 1 IMUs (0 channel switches)"; names padded to a table's columns (``names.padded``)."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from proleg.names import counted, display_width, padded


@pytest.mark.parametrize("n, noun, text", [
    (1, "IMU", "1 IMU"), (2, "IMU", "2 IMUs"), (0, "IMU", "0 IMUs"),
    (1, "channel switch", "1 channel switch"), (0, "channel switch", "0 channel switches"),
    (3, "pass", "3 passes"), (2, "entry", "2 entries"), (2, "try", "2 tries"), (2, "day", "2 days"),
    (2, "duty", "2 duties"), (1, "duty", "1 duty"), (2, "box", "2 boxes"),
])
def test_counted_says_one_thing_and_many_things(n, noun, text):
    assert counted(n, noun) == text


def test_counted_takes_an_irregular_plural():
    assert counted(2, "datum", "data") == "2 data" and counted(1, "datum", "data") == "1 datum"


def test_the_tick_budget_refusal_counts_one_imu_as_one():
    from proleg.errors import BuildError
    from proleg.firmware.placement import ImuPlacement, check_tick_budget

    class _Control:
        tick_hz = 100_000

    class _Robot:
        where = "robot.toml"
        control = _Control()

    one = [ImuPlacement(limb="a", bus=0, bus_name="i2c0", mux=None, channel=None, address=0x68, automatic=True)]
    with pytest.raises(BuildError) as e:
        check_tick_budget(_Robot(), "host-sim", one, 400_000)
    assert "reading 1 IMU (0 channel switches)" in str(e.value)


def test_counted_formats_the_number_as_told():
    assert counted(9990, "more tie", spec=",") == "9,990 more ties" and counted(1, "more tie", spec=",") == "1 more tie"


@given(st.text(alphabet=st.sampled_from("ab前後é\u0301ｱＡ"), max_size=8), st.integers(0, 20))
def test_padded_fills_to_the_terminal_columns_a_character_takes(text, width):
    """Against a count by hand: two columns for the wide and fullwidth ones (前 後 Ａ), none
    for the combining acute, one for the rest (a b é and the halfwidth ｱ)."""
    columns = sum(2 if c in "前後Ａ" else 0 if c == "\u0301" else 1 for c in text)
    assert display_width(text) == columns
    out = padded(text, width)
    assert out.startswith(text) and set(out[len(text):]) <= {" "}
    assert display_width(out) == max(width, columns)
