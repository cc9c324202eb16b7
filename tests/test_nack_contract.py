"""Every refusal the firmware sends is the one the protocol documents (definition.py's command
texts, enums.ErrorCode, link/replies.py), whichever refusals apply at once, and no interleaving
of the host's commands gets a coil around the safety envelope (docs/safety.md).

The whole firmware core on the simulated board (``test_firmware_on_sim_board.Rig``, r1-fast:
max_on 50 ms, min_cooldown 20 ms, max_duty 0.8, hold ceiling 0.3, state timeout 200 ms),
stepped one control tick at a time and talked to through the one client.
"""

from __future__ import annotations

import pytest
import test_firmware_on_sim_board as on_sim_board
from test_firmware_on_sim_board import CC, Rig

from proleg.protocol import definition as d

pytestmark = pytest.mark.skipif(CC is None, reason="no host C compiler")
rendered, sim_so = on_sim_board.rendered, on_sim_board.sim_so  # its fixtures: the firmware on the sim board

E = d.ErrorCode


def _rig(sim_so, config="r1-fast", limbs=2, channels=2) -> Rig:
    b = Rig(sim_so(config), limbs, channels)
    for limb in range(limbs):
        b.set_psi(limb, 0.0)
    b.reset()
    assert b.client.wait_known_state()
    b.run(0)
    return b


@pytest.fixture
def board(sim_so):
    return _rig(sim_so)


def _refusal(board: Rig, name: str, **fields) -> tuple[E, int] | tuple[E, int, str]:
    """The NACK's (error, detail); with a third item, the refusal the host has no words for
    (replies.py explains every refusal the firmware sends)."""
    r = board.refused(name, **fields)
    return (r.error, r.detail) if r.why else (r.error, r.detail, "no words for it")


def _events(board: Rig, kind) -> list:
    return [m for m in board.log if m.spec.name == "EVENT" and m.kind == kind]


# ---------------------------------------------------------------- LOAD_GAIT


@pytest.mark.parametrize(
    "states, step",
    [
        ((2, 2), 0),  # 10 → 10: a self-transition, closed or not
        ((2,), 0),  # one state: it follows itself
        ((2, 2, 2), 0),
        ((0, 2, 2, 1), 1),
        ((0, 2, 3, 3), 2),
    ],
)
def test_a_step_that_is_not_an_allowed_transition_is_forbidden_transition_naming_the_step(board, states, step):
    """definition.py: LOAD_GAIT "NACK FORBIDDEN_TRANSITION, detail = step index"; replies.py
    names "a state that follows itself". (2, 2) and (2,) used to be OUT_OF_RANGE (detail 2, 1):
    seq_load closed (2, 2) to the single state 2 and refused it as too short."""
    assert _refusal(board, "LOAD_GAIT", states=states) == (E.FORBIDDEN_TRANSITION, step)
    assert not d.Flag.USER_GAIT & board.run(25)[-1].flags  # nothing stored


# ---------------------------------------------------------------- START


def test_start_of_no_such_gait_while_the_fallback_has_given_up_a_coil_is_no_gait(sim_so):
    """The fallback gave up the right coil (its limb never rose): START of a built-in gait is
    NOT_ALLOWED detail 3 (definition.py), but a gait the board does not have is NO_GAIT, as at
    any other time; it used to be NOT_ALLOWED 3, which sent the operator to take a coil back
    only to be told then that there is no such gait."""
    board = _rig(sim_so)
    board.client.start(0, "+x")  # 00 → 10 → 11 ...
    board.run(20)
    board.set_psi(0, 25.0)  # the left limb rises; the right never does
    for _ in range(100):
        board.run(10)
        if _events(board, d.EventKind.FALLBACK):
            break
    assert [m.code for m in _events(board, d.EventKind.FALLBACK)] == [1]
    board.client.stop()
    assert board.client.request("GET_ACTUATOR_MAP").lost == 1
    assert _refusal(board, "START", gait=0, direction=0) == (E.NOT_ALLOWED, 3)
    assert _refusal(board, "START", gait=77, direction=0) == (E.NO_GAIT, 77)
    assert _refusal(board, "START", gait=1, direction=1) == (E.NO_GAIT, 1)
    r = board.refused("START", gait=77, direction=9)
    assert (r.error, r.detail) == (E.OUT_OF_RANGE, 2)
    tel = board.run(25)[-1]
    assert not d.Flag.RUNNING & tel.flags and not any(tel.duty)  # a refused START runs nothing
    board.client.start("user", "+x")  # the fallback gait still runs
    board.client.stop()
