"""Counts in messages read as English: ``names.counted`` and a message that used to say
"reading 1 IMUs (0 channel switches)"."""

from __future__ import annotations

import pytest

from proleg.names import counted


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
