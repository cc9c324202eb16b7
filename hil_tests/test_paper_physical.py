"""The paper's experiments, run by the firmware on the physical plant (the default simulator):
its hand-written sequences loaded as the user gait. (tests/test_plant_physical.py runs the
same sequences with an idealised drive; R3's are strict xfails there, for the reason given in
docs/plant.md.)"""

from __future__ import annotations

import pytest

from proleg.link.direction import UNSTATED
from proleg.protocol.definition import EventKind

C_T1 = ("00", "10", "01")          # 00 → 10 → 01 → 00
C_T2 = ("00", "01", "10")          # 00 → 01 → 10 → 00
C_L1 = ("00", "10", "11", "10")    # 00 → 10 → 11 → 10 → 00
C_L2 = ("10", "11")                # 10 → 11 → 10


def _per_cycle(t, labels, seconds=36.0) -> list[float]:
    """Load ``labels`` as the user gait, run it, return the plant's true displacement per
    cycle (from one report of reaching step 0 to the next); no fault allowed."""
    table = t.robot.transitions
    t.client.load_gait([table.index(s) for s in labels])
    t.client.start("user", UNSTATED)  # which way it walks is what the experiment finds
    received = t.wait(seconds)
    t.client.stop()
    events = [r for r in received if r.message.name == "EVENT"]
    assert not [r.message for r in events if r.message.kind == EventKind.FAULT]
    marks = [r.truth["displacement_mm"] for r in events
             if r.message.kind == EventKind.STATE_REACHED and r.message.code == 0]
    assert len(marks) >= 4, f"{'-'.join(labels)}: only {len(marks) - 1} cycles"
    return [b - a for a, b in zip(marks, marks[1:])]


def _mean(xs: list[float]) -> float:
    return sum(xs) / len(xs)


@pytest.mark.plant
@pytest.mark.emu_long_on("arm-emu")  # 2 × 36 s of walking: ~2 min each on unicorn, `make emu` runs it there
@pytest.mark.robot("paper-r1", "paper-r2")
@pytest.mark.parametrize("name, ct1_sign", [("paper-r1", +1), ("paper-r2", -1)])
def test_ct1_and_ct2_move_r1_and_r2_by_equal_amounts_in_opposite_directions(open_target, name, ct1_sign):
    a = _per_cycle(open_target(name), C_T1)
    b = _per_cycle(open_target(name), C_T2)
    assert all(ct1_sign * x > 0 for x in a) and all(ct1_sign * x < 0 for x in b), (a, b)
    assert _mean(a) == pytest.approx(-_mean(b), rel=0.2), (a, b)


@pytest.mark.plant
@pytest.mark.emu_long_on("arm-emu")
@pytest.mark.robot("paper-r1-one-actuator")
@pytest.mark.parametrize("sequence", [C_L1, C_L2], ids=["C_L1", "C_L2"])
def test_one_actuator_r1_moves_only_plus_x(open_target, sequence):
    cycles = _per_cycle(open_target("paper-r1-one-actuator"), sequence)
    assert all(x > 0 for x in cycles), cycles
