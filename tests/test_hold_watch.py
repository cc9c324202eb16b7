"""The hold watch (core/ctl.h, CFG_HOLD_WATCH): built in where the robot's body leaves a worn
coil short of a limb's hold top (proleg.robot_body.worn_holds), and on such a robot a worn
coil no longer heats on below a hold edge it cannot reach. Its C behaviour:
tests/c/test_ctl_hold.c."""

from __future__ import annotations

from pathlib import Path

import pytest
from core_configs import SIM_BOARD, robot_doc
from proleg.body import own_reach_deg
from proleg.firmware.render import control_part, render_config
from proleg.paths import robots_dir
from proleg.report import claim
from proleg.robot import load_robot, robot_from_dict
from proleg.robot_body import WORN_STROKE_LOSS, body_of, worn_holds, worn_holds_of
from proleg.physics.params import FatigueLaw


def _worn(name: str) -> list[int]:
    return worn_holds_of(load_robot(robots_dir() / f"{name}.toml"))


def test_a_hold_top_far_below_the_reach_needs_no_watch_and_one_near_it_does():
    # R1, R2, R3: ψ* 20° against a coil that bends its end to ~58°; strokes are not watched
    for name in ("paper-r1", "paper-r2", "paper-r3", "paper-r1-stroke"):
        assert _worn(name) == [], name
    # the one-actuator R1's far end bends to ~23.5° with its hold top at ~22°
    assert _worn("paper-r1-one-actuator") == [1]
    # caterpillar-4's prolegs: top level entered at 25°, the coil reaches ~31°
    assert {1, 2} <= set(_worn("caterpillar-4"))


def test_the_worn_stroke_is_the_plants_fatigue_law():
    assert WORN_STROKE_LOSS == FatigueLaw().stroke_loss


def test_the_watch_follows_the_stroke_a_worn_coil_keeps():
    """Raising ψ* moves a limb's hold top towards its reach: the watch comes in once the top
    passes what 75 % of the reach keeps, and stays in."""
    kept = 1.0 - FatigueLaw().stroke_loss
    seen = []
    for psi_star in range(20, 56, 5):
        doc = robot_doc()
        for limb in doc["limb"]:
            limb["psi_star_deg"] = [float(psi_star)]
        robot = robot_from_dict(doc, Path("tests/t.toml"))
        worn = worn_holds(list(robot.limbs), [a.name for a in robot.actuators], robot.plant, 1.0)
        seen.append(bool(worn))
        reach = own_reach_deg(body_of([0, 1], 2, robot.plant), [0, 1])
        top = psi_star + 1.0 + 1.0 + 1.0
        assert bool(worn) == (top > kept * min(reach)), (psi_star, reach)
    assert seen[0] is False and seen[-1] is True
    assert seen == sorted(seen)


@pytest.mark.parametrize("name, on", [("paper-r1", 0), ("paper-r1-one-actuator", 1), ("caterpillar-4", 1)])
def test_the_renderer_builds_the_watch_in_where_it_is_needed(name, on):
    assert control_part(load_robot(robots_dir() / f"{name}.toml")).hold_watch == on


def test_the_rendered_header_carries_the_choice():
    robot = robot_from_dict(robot_doc(), Path("tests/t.toml"))
    header = render_config(robot, {"+x": [], "-x": []}, SIM_BOARD)["robot_config.h"]
    assert "#define CFG_HOLD_WATCH 0\n" in header


def test_a_worn_caterpillar_walks_without_cooking_a_proleg():
    """caterpillar-4 at 30,000 cycles of fatigue (the claim bench's strong fatigue): its rear
    proleg's coil reaches its top level at ~25.4° but not its hold edge (27°); without the watch
    the bang-bang hold heated it on to 135 °C. Now it walks, every coil below 120 °C."""
    robot = load_robot(robots_dir() / "caterpillar-4.toml")
    out = claim.feedback_run(robot, claim.point("fatigue (strong)"), duration_s=30.0)
    assert out.fault == "", out
    assert out.coil_peak_c < claim.OVERHEAT_C, out
    assert out.completed and out.speed_mm_s > 0.0, out


def test_a_worn_far_end_that_stops_inside_its_band_lets_the_gait_go_on_cool():
    """The one-actuator R1, its coil worn by 13,906 cycles, behind 2.7 Ω of source resistance:
    its far end rises into level 1 and stops inside its band (19–21°), past ψ* (20°). An
    idealised drive (true ψ) walks it. Heated on there, the coil reached 151 °C and the step
    ran out (SMA_ON_LIMIT, STATE_TIMEOUT); held where it stopped and settled in its level, the
    gait goes on, every coil below 120 °C."""
    robot = load_robot(robots_dir() / "paper-r1-one-actuator.toml")
    point = claim.GridPoint("worn, weak supply", (), "random",
                            ("fatigue_cycles=13906", "imu_bias_deg=right:0.8", "supply_ohm=2.7"), ())
    assert claim.idealised_walk(robot, point).possible
    out = claim.feedback_run(robot, point, duration_s=30.0)
    assert out.fault == "", out
    assert out.coil_peak_c < claim.OVERHEAT_C, out
    assert out.completed and out.speed_mm_s > 0.2, out


def test_a_worn_one_actuator_r1_does_not_heat_its_coil_past_its_transformation():
    """`proleg check robots/paper-r1-one-actuator.toml --rows 30 --seed 4`, row 21: its one coil,
    worn by 14,758 cycles, bends its own (left) end to 50° and lifts the far end through the body
    only to its band's upper edge; the far end then creeps by tenths, so the hold watch (0.4° in
    320 ms) cut the coil only 0.75 s after its own end had stopped: 136 °C at the drive duty,
    then STATE_TIMEOUT. The coil-wide knee sees its own end stop: at most the hold duty from
    there. The far end's reach is still marginal (it reaches its level in some cycles, not in
    others), so the robot walks a few cycles and stops on the state timeout, its coil cool."""
    robot = load_robot(robots_dir() / "paper-r1-one-actuator.toml")
    point = claim.GridPoint("seed 4 row 21", (), "random",
                            ("fatigue_cycles=14758", "mass_g=4.1", "imu_offset_deg=right:-4.0"), ())
    assert claim.idealised_walk(robot, point).possible
    out = claim.feedback_run(robot, point, duration_s=40.0)
    assert out.coil_peak_c < claim.OVERHEAT_C - 10, out  # before: 136 °C
    assert out.displacement_mm > 5.0, out  # it walked (+12 mm) before it stopped
    if not out.completed:  # a clean stop: a fault of the firmware's, the coil cooling
        assert out.fault == "STATE_TIMEOUT", out
        assert out.coil_max_end_c < 60, out


def test_a_worn_limb_that_settles_by_the_margins_short_of_its_hold_edge_is_watched():
    """snake-8 (tests/fixtures: eight binary limbs on the default 280 mm body), `proleg check
    --rows 3` row 2, worn by 22,868 cycles: the tail's coil lifts it to 24.95°, just short of its
    25° hold edge. Settled by the margins, it counted as held, and a held limb is not watched: the
    bang-bang hold heated it on at the drive duty for 3 s at a time, to 140 °C. A limb counts as
    held once it got to its hold top; short of it, its rise is watched as before: held where it
    stopped, it walks, every coil below 120 °C."""
    robot = load_robot(Path(__file__).parent / "fixtures" / "snake-8.toml")
    point = claim.GridPoint("worn", (), "random", ("fatigue_cycles=22868",), ())
    out = claim.feedback_run(robot, point, duration_s=40.0)
    assert out.fault == "", out
    assert out.coil_peak_c < claim.OVERHEAT_C, out  # before: 140 °C
    assert out.completed and out.speed_mm_s > 0.0, out
