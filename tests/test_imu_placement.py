"""IMU topology: where each limb's IMU sits (bus, multiplexer channel, address), whether
a board can host a robot, and the host-sim board's TCA9548A model routing the transfers."""

from __future__ import annotations

import itertools
from pathlib import Path
from types import SimpleNamespace

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from proleg.errors import BoardError, BuildError, RobotFileError
from proleg.firmware.boards import I2cBus, i2c_buses, load_board
from proleg.firmware.fit import check_fit
from proleg.firmware.placement import (
    capacity,
    check_tick_budget,
    i2c_tick_us,
    mux_selects_per_tick,
    place_imus,
    sim_imu_keys,
)
from proleg.robot import ImuSpec, robot_from_dict

ROOT = Path(__file__).resolve().parents[1]


def robot(n: int, specs: dict[int, ImuSpec] | None = None, tick_hz: int = 250):
    specs = specs or {}
    limbs = tuple(SimpleNamespace(name=f"l{i + 1}", imu=specs.get(i)) for i in range(n))
    return SimpleNamespace(name="toy", where="toy.toml", limbs=limbs, control=SimpleNamespace(tick_hz=tick_hz))


def test_bluepill_puts_a_third_imu_on_its_second_bus():
    p = place_imus(robot(3), load_board("bluepill-f103"))
    assert [(x.bus_name, x.mux, x.address) for x in p] == [("I2C1", None, 0x68), ("I2C1", None, 0x69), ("I2C2", None, 0x68)]
    assert all(x.automatic for x in p)


def test_nano_puts_three_imus_behind_a_multiplexer_two_per_channel():
    p = place_imus(robot(3), load_board("arduino-nano"))
    assert [(x.bus_name, x.mux, x.channel, x.address) for x in p] == [
        ("TWI", 0x70, 0, 0x68), ("TWI", 0x70, 0, 0x69), ("TWI", 0x70, 1, 0x68)]
    assert mux_selects_per_tick(p) == 2  # channel 0, then 1, then 0 again next tick


def test_eight_limbs_fit_the_bluepill_and_the_nano():
    for board in ("bluepill-f103", "arduino-nano", "host-sim"):
        p = place_imus(robot(8), load_board(board))
        assert len({(x.bus, x.mux, x.channel, x.address) for x in p}) == 8


def test_a_given_placement_is_kept_and_a_partial_one_completed():
    specs = {0: ImuSpec(bus="I2C2", address=0x69), 1: ImuSpec(channel=3)}
    p = place_imus(robot(3, specs), load_board("bluepill-f103"))
    assert (p[0].bus_name, p[0].mux, p[0].address, p[0].automatic) == ("I2C2", None, 0x69, False)
    assert (p[1].bus_name, p[1].mux, p[1].channel, p[1].address) == ("I2C1", 0x70, 3, 0x68)
    # the automatic third limb avoids both: a direct 0x68 on I2C1 would collide with channel 3's 0x68
    assert p[2].automatic and not (p[2].bus == 0 and p[2].mux is None and p[2].address == 0x68)


@pytest.mark.parametrize("specs, message", [
    ({0: ImuSpec(bus="I2C3")}, r"limb l1: imu.bus: board bluepill-f103 has no I2C bus 'I2C3' \(it has: I2C1, I2C2\)"),
    ({0: ImuSpec(address=0x68), 1: ImuSpec(address=0x68)}, r"limb l2: imu: no free place as given \(limb l1: IMU at 0x68 on bus I2C1 is there"),
    ({0: ImuSpec(address=0x50)}, r"limb l1: imu.address: 0x50 is not an IMU address of bus I2C1 \(0x68, 0x69\)"),
    ({0: ImuSpec(mux=0x70, channel=1), 1: ImuSpec(mux=0x71, channel=2)}, r"limb l2: imu.mux: bus I2C1 already has the multiplexer at 0x70 \(one per bus\)"),
    ({0: ImuSpec(address=0x68), 1: ImuSpec(channel=0, address=0x68)}, r"limb l2: imu: no free place"),
])
def test_impossible_placements_are_refused_naming_the_limb(specs, message):
    with pytest.raises(BuildError, match=message):
        place_imus(robot(2, specs), load_board("bluepill-f103"))


def test_a_board_without_a_multiplexer_says_how_many_imus_it_can_host():
    board = {"name": "tiny", "i2c": {"bus": "TWI", "imu_addresses": [0x68, 0x69]}}
    with pytest.raises(BuildError, match=r"3 limbs, each with an IMU, but board tiny can host at most 2 IMUs \(bus TWI: 0x68/0x69, no multiplexer\)"):
        place_imus(robot(3), board)
    with pytest.raises(BuildError, match=r"a multiplexer channel is named, but no bus of board tiny can carry a multiplexer"):
        place_imus(robot(1, {0: ImuSpec(channel=2)}), board)


def test_the_i2c_time_per_tick_counts_reads_and_channel_switches():
    p = place_imus(robot(8), load_board("arduino-nano"))
    # 8 reads of 84 bits and 4 channel switches of 20 bits at 400 kHz
    assert i2c_tick_us(p, 400_000) == pytest.approx((8 * 84 + 4 * 20) / 0.4)
    with pytest.raises(BuildError, match=r"reading 8 IMUs \(4 channel switches\) takes about 1880 us .* set control.tick_hz to at most 398"):
        check_tick_budget(robot(8, tick_hz=1000), "arduino-nano", p, 400_000)
    check_tick_budget(robot(8, tick_hz=250), "arduino-nano", p, 400_000)


def test_sim_keys_are_addresses_on_bus_zero_and_limb_tags_elsewhere():
    p = place_imus(robot(4), load_board("host-sim"))
    assert sim_imu_keys(p) == (0x68, 0x69, 0x82, 0x83)


def test_board_bus_tables_are_checked(tmp_path):
    with pytest.raises(BoardError, match=r"i2c.bus\[2\].name: 'A' names another bus too"):
        i2c_buses(tmp_path / "b.toml", {"bus": [{"name": "A"}, {"name": "A"}]})
    with pytest.raises(BoardError, match=r"i2c.bus\[1\].mux_addresses: expected a list of 7-bit addresses in 0x70..0x77"):
        i2c_buses(tmp_path / "b.toml", {"bus": [{"name": "A", "mux_addresses": [0x60]}]})
    with pytest.raises(BoardError, match=r"unknown key 'speed'"):
        i2c_buses(tmp_path / "b.toml", {"bus": [{"name": "A", "speed": 1}]})


def test_robot_file_imu_fields_are_checked():
    doc = {
        "robot": {"name": "r"},
        "actuator": [{"name": "a", "channel": 0}],
        "limb": [{"name": "l", "psi_star_deg": [20.0], "actuator": "a", "imu": {"mux": 0x69}}],
        "transitions": {"matrix": [[0, 1], [1, 0]]},
    }
    with pytest.raises(RobotFileError, match=r"limb 'l': imu.mux: expected an address in 0x70..0x77 \(a number, "
                                             r"written like 0x70 without quotes\), got 0x69$"):
        robot_from_dict(doc, Path("r.toml"))  # in hex, as the file writes it: "in 112..119, got 105" before
    doc["limb"][0]["imu"] = {"address": "0x68"}
    with pytest.raises(RobotFileError, match=r"imu.address: expected an address in 0x08..0x77 \(a number, "
                                             r"written like 0x68 without quotes\), got '0x68'$"):
        robot_from_dict(doc, Path("r.toml"))
    doc["limb"][0]["imu"] = {"address": 0x71}
    with pytest.raises(RobotFileError, match=r"imu.address: expected an IMU address outside the multiplexer range "
                                             r"0x70..0x77, got 0x71$"):
        robot_from_dict(doc, Path("r.toml"))
    doc["limb"][0]["imu"] = {"bus": "I2C1", "channel": 3, "address": 0x69}
    assert robot_from_dict(doc, Path("r.toml")).limbs[0].imu == ImuSpec("I2C1", None, 3, 0x69)


buses_strategy = st.lists(
    st.tuples(st.integers(1, 2), st.booleans()), min_size=1, max_size=3,
).map(lambda spec: tuple(
    I2cBus(i, f"b{i}", "", "", tuple(range(0x68, 0x68 + n)), (0x70,) if mux else ()) for i, (n, mux) in enumerate(spec)
))


def _brute_capacity(buses) -> int:
    """The most IMUs with no two the firmware can see at one address: try every subset of
    slots, largest first (small boards only)."""
    slots = []
    for b in buses:
        slots += [(b.index, None, None, a) for a in b.addresses]
        if b.mux_addresses:
            slots += [(b.index, 0x70, c, a) for c in range(8) for a in b.addresses]

    def clash(x, y):
        return x[0] == y[0] and x[3] == y[3] and not (x[1] and y[1] and x[2] != y[2])

    def fits(k: int, start: int = 0, chosen: tuple = ()) -> bool:  # depth-first search
        if len(chosen) == k:
            return True
        return any(
            fits(k, i + 1, chosen + (slots[i],))
            for i in range(start, len(slots))
            if all(not clash(slots[i], c) for c in chosen)
        )

    return max(k for k in range(0, 9) if fits(k))


@settings(max_examples=40, deadline=None)
@given(buses=buses_strategy, n=st.integers(1, 8))
def test_automatic_placement_fits_exactly_when_the_board_has_room(buses, n):
    board = SimpleNamespace(name="b", i2c_buses=buses, i2c={})
    room = _brute_capacity(buses)
    assert capacity(buses) == room
    if n <= room:
        p = place_imus(robot(n), board)
        for x, y in itertools.combinations(p, 2):
            assert not (x.bus == y.bus and x.address == y.address and not (x.mux and y.mux and x.channel != y.channel))
    else:
        with pytest.raises(BuildError, match=f"can host at most {room} IMUs"):
            place_imus(robot(n), board)


def test_a_gait_table_too_big_for_the_board_is_refused_before_compiling():
    from proleg.robot import load_robot

    r1 = load_robot(ROOT / "robots" / "paper-r1.toml")
    big = {"+x": [SimpleNamespace(states=tuple([0, 1] * 12000 + [0]))], "-x": []}
    with pytest.raises(BuildError, match=r"does not fit board arduino-nano .*tables take 24,\d\d\d bytes .* needs [34]\d,\d\d\d bytes of flash, board arduino-nano has 30,720$"):
        check_fit(r1, load_board("arduino-nano"), big)
    check_fit(r1, load_board("bluepill-f103"), big)  # 64 KB: fits


def test_a_placement_wired_for_a_real_board_is_simulated_on_the_sim_buses_of_the_same_index():
    """proleg sim, run --sim and learn build for host-sim: a robot file placed for the bluepill
    (bus = "I2C1" / "I2C2") was refused by every simulator command ("board host-sim has no I2C
    bus 'I2C1'"), though arm-emu ran it. Its buses map to sim0 / sim1 by index; a name no
    shipped board has is still refused, naming it."""
    specs = {0: ImuSpec(bus="I2C1", mux=0x70, channel=1, address=0x68), 1: ImuSpec(bus="I2C2"),
             2: ImuSpec(bus="I2C1", address=0x69)}
    real = place_imus(robot(3, specs), load_board("bluepill-f103"))
    for board in ("host-sim", "host-sim-can"):
        sim = place_imus(robot(3, specs), load_board(board))
        assert [x.bus_name for x in sim] == ["sim0", "sim1", "sim0"]
        assert [(x.bus, x.mux, x.channel, x.address, x.automatic) for x in sim] == \
            [(x.bus, x.mux, x.channel, x.address, x.automatic) for x in real]
    nano = place_imus(robot(2, {0: ImuSpec(bus="TWI", channel=2)}), load_board("host-sim"))
    assert (nano[0].bus_name, nano[0].mux, nano[0].channel) == ("sim0", 0x70, 2)
    with pytest.raises(BuildError, match=r"limb l2: imu.bus: board host-sim has no I2C bus 'I2C9'"):
        place_imus(robot(2, {0: ImuSpec(bus="I2C1"), 1: ImuSpec(bus="I2C9")}), load_board("host-sim"))
    with pytest.raises(BuildError, match=r"board bluepill-f103 has no I2C bus 'sim0'"):
        place_imus(robot(1, {0: ImuSpec(bus="sim0")}), load_board("bluepill-f103"))
