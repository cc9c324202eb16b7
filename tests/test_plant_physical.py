"""The physical plant (proleg.sim.physical): conditions, measured matrices, the paper's
experiments, closed loop with the host-sim firmware."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from proleg.errors import SimError
from proleg.robot import load_robot
from proleg.sim.physical import Conditions, PhysicalPlant, measure_matrix, parse_conditions
from proleg.sim.physical.friction import mu_at, solve_translation, solve_two
from proleg.sim.physical.measure import run_sequence
from proleg.physics.thermal import CoilGeometry

ROBOTS = Path(__file__).resolve().parents[1] / "robots"
PAPER = {
    "paper-r1": [[0, -1, 1, 0], [1, 0, 0, -1], [-1, 0, 0, 1], [0, 0, 0, 0]],
    "paper-r2": [[0, 1, -1, 0], [-1, 0, 0, 1], [1, 0, 0, -1], [0, 0, 0, 0]],
    "paper-r3": [[0, -1, 1, 1], [1, 0, 0, -1], [-1, -1, 0, -1], [-1, 1, 0, 0]],
}


def robot(name: str):
    return load_robot(ROBOTS / f"{name}.toml")


# -- conditions -------------------------------------------------------------------------------
def test_conditions_parse_scalars_and_per_limb_values():
    c = parse_conditions(["power=0.8", "ambient_c=30", "imu_bias_deg=front:3", "incline_deg=5"])
    assert c.get("power") == 0.8 and c.get("ambient_c") == 30.0 and c.get("incline_deg") == 5.0
    names = ["left", "right"]
    assert c.for_index("imu_bias_deg", 1, names) == 3.0
    assert c.for_index("imu_bias_deg", 0, names) == 0.0
    assert c.get("convection") == 1.0  # default


@pytest.mark.parametrize("item, words", [
    ("speed=3", "unknown key"),
    ("power=9", "outside"),
    ("power=abc", "expected a number"),
    ("power", "expected key=value"),
    ("power=left:1", "takes one number"),
    ("ambient_c=1_0", "expected a number"),  # float() reads it as 10
    ("imu_bias_deg=:3", "expected NAME:value with a limb name"),  # was every limb
    ("power_scale= :0.9", "with an actuator name"),
])
def test_a_bad_condition_is_one_clear_line(item, words):
    with pytest.raises(SimError) as e:
        parse_conditions([item])
    assert words in str(e.value) and "\n" not in str(e.value)


def test_a_condition_naming_an_unknown_limb_is_refused_when_the_plant_is_built():
    with pytest.raises(SimError, match="no limb 'middle'"):
        PhysicalPlant(robot("paper-r1"), parse_conditions(["imu_bias_deg=middle:2"]))


# -- physics pieces ---------------------------------------------------------------------------
def test_coil_numbers_follow_from_wire_geometry():
    g = CoilGeometry()
    # 0.1 mm wire, 0.3 mm mean diameter, 300 turns: ≈ 0.28 m, ρ = 0.8 µΩ·m → ≈ 29 Ω
    assert 0.27 < g.wire_length_m < 0.29
    assert 27 < g.resistance_ohm < 31
    assert g.latent_j > 0.5 * g.heat_capacity_j_k * (g.af_c - g.as_c)  # latent heat matters
    hA = g.convection_w_k()
    assert hA < g.convection_w_k(scale=2.0) and 2e-3 < hA < 2e-2


def test_latent_heat_delays_the_contraction():
    r = robot("paper-r1")
    def time_to_contract(lat_scale):
        p = PhysicalPlant(r)
        p._coils.lat = [x * lat_scale for x in p._coils.lat]
        while p.austenite[0] < 0.9:
            p.step(0.002, [0.6, 0.0])
        return p.time_s
    assert time_to_contract(1.0) > 1.2 * time_to_contract(0.0)


def test_weighted_median_against_brute_force():
    rng = np.random.default_rng(3)
    for _ in range(200):
        n = int(rng.integers(2, 5))
        offs = rng.normal(size=n)
        caps = rng.uniform(0.01, 1.0, size=n)
        push = float(rng.uniform(-0.5, 0.5)) * caps.sum()
        d = solve_translation(offs.tolist(), caps.tolist(), push)
        grid = np.linspace(-5, 5, 20001)
        cost = (caps[None, :] * np.abs(grid[:, None] + offs[None, :])).sum(axis=1) + push * grid
        best = cost.min()
        assert (caps * np.abs(d + offs)).sum() + push * d <= best + 1e-3


@given(dg=st.floats(-2, 2, allow_nan=False), c0=st.floats(0, 1), c1=st.floats(0, 1),
       push=st.floats(-2.5, 2.5), tie=st.booleans())
def test_two_contact_closed_form_against_brute_force(dg, c0, c1, push, tie):
    if tie:
        c1, push = c0, 0.0
    d = solve_two(dg, c0, c1, push)
    assert d == pytest.approx(solve_translation([0.0, dg], [c0, c1], push), abs=1e-9)
    if abs(push) >= c0 + c1:
        return   # the weight along the slope beats all friction: unbounded, the body slides away
    grid = np.linspace(-3, 3, 6001)
    cost = c0 * np.abs(grid) + c1 * np.abs(grid + dg) + push * grid
    assert c0 * abs(d) + c1 * abs(d + dg) + push * d <= cost.min() + 1e-2


def test_a_soft_pad_loses_grip_as_it_peels_towards_psi_star():
    soft, hard = 1.0, 0.3
    assert mu_at(0.0, [20.0], [soft, hard], 12.0) == soft
    assert hard < mu_at(15.0, [20.0], [soft, hard], 12.0) < soft
    assert mu_at(20.0, [20.0], [soft, hard], 12.0) == hard
    assert mu_at(19.9, [20.0], [hard, soft], 12.0) == hard  # D2: hard below ψ*


def test_a_dead_coil_neither_heats_nor_moves_the_robot():
    p = PhysicalPlant(robot("paper-r1"))
    p.kill_actuator(0)
    for _ in range(2000):
        p.step(0.002, [0.8, 0.0])
    assert p.temperature_c[0] < 26 and p.displacement_mm == 0.0 and p.true_state == 0


def test_the_imu_senses_incline_offset_and_bias_but_friction_uses_the_true_angle():
    p = PhysicalPlant(robot("paper-r1"), parse_conditions(["incline_deg=5", "imu_bias_deg=left:2"]))
    assert p.limb_truth(0)[0] == pytest.approx(7.0)
    assert p.limb_truth(1)[0] == pytest.approx(-5.0)
    assert p.psi_deg.tolist() == [0.0, 0.0]


def test_weak_supply_cannot_reach_a_raised_state():
    p = PhysicalPlant(robot("paper-r1"), parse_conditions(["supply_v=2"]))
    for _ in range(5000):
        p.step(0.002, [0.6, 0.0])
    assert p.true_state == 0


# -- measured matrices (the paper's signs) -------------------------------------------------------
def _sign_mismatches(name: str) -> list[str]:
    r = robot(name)
    m = measure_matrix(r, repeats=1)
    _, allowed = r.transitions.dense()
    bad = []
    for a in range(4):
        for b in range(4):
            want = PAPER[name][a][b]
            if a != b and allowed[a][b] and want != 0:
                got = m.matrix_mm[a, b]
                if not (m.samples[a, b] > 0 and np.sign(got) == want):
                    bad.append(f"{m.states[a]}->{m.states[b]}: {got:+.2f} mm, paper {want:+d}")
    return bad


@pytest.mark.parametrize("name", ["paper-r1", "paper-r2"])
def test_measured_matrix_has_the_papers_signs(name):
    assert _sign_mismatches(name) == []


R3_REASON = ("not realisable under Coulomb friction: with D1 left / D2 right the paper's 00->10 = +1 needs the "
             "left end to slide on a contact at least as grippy and at least as loaded as the right one; with "
             "D2 left / D1 right 00->01 = -1 needs the same of the right end (docs/plant.md, 'R3')")


@pytest.mark.xfail(strict=True, reason=R3_REASON)
def test_measured_matrix_of_r3_has_the_papers_signs():
    assert _sign_mismatches("paper-r3") == []


def test_mechanisms_are_inferred_from_the_matrix_when_the_robot_file_does_not_say():
    assert PhysicalPlant(robot("paper-r1")).mechanisms == ("D1", "D1")
    assert PhysicalPlant(robot("paper-r2")).mechanisms == ("D2", "D2")
    assert PhysicalPlant(robot("paper-r1")).mechanism_source == "inferred from the matrix"


# -- the paper's experiments (idealised state-tracking drive) -----------------------------------
def test_ct1_and_ct2_move_r1_and_r2_by_equal_amounts_in_opposite_directions():
    ct1, ct2 = [0, 2, 1, 0], [0, 1, 2, 0]
    r1a, _ = run_sequence(robot("paper-r1"), ct1, cycles=2)
    r1b, _ = run_sequence(robot("paper-r1"), ct2, cycles=2)
    r2a, _ = run_sequence(robot("paper-r2"), ct1, cycles=2)
    r2b, _ = run_sequence(robot("paper-r2"), ct2, cycles=2)
    assert r1a > 0.5 and r1b < -0.5 and r2a < -0.5 and r2b > 0.5
    assert r1a == pytest.approx(-r1b, rel=0.1)
    assert r2a == pytest.approx(-r2b, rel=0.1)


def test_one_actuator_r1_moves_plus_x_with_cl1_and_cl2():
    r = robot("paper-r1-one-actuator")
    assert run_sequence(r, [0, 2, 3, 2, 0], cycles=2)[0] > 0.5
    assert run_sequence(r, [2, 3, 2], cycles=2)[0] > 0.5


@pytest.mark.xfail(strict=True, reason="a D1/D2 robot is a friction ratchet: C_T1 and C_T2 move it the same way "
                   "(D1 left / D2 right: both -x; D2 left / D1 right: both +x); the paper's opposite directions "
                   "rest on the R3 entries that Coulomb friction forbids (docs/plant.md, 'R3')")
@pytest.mark.parametrize("mech", [("D1", "D2"), ("D2", "D1")])
def test_r3_ct1_moves_plus_x_more_slowly_than_ct2_moves_minus_x(mech):
    r = robot("paper-r3")
    a, _ = run_sequence(r, [0, 2, 1, 0], cycles=2, plant=PhysicalPlant(r, mechanisms=mech))
    b, _ = run_sequence(r, [0, 1, 2, 0], cycles=2, plant=PhysicalPlant(r, mechanisms=mech))
    assert 0 < a < -b


def test_the_bent_side_carries_at_least_half_the_weight():
    """The statics premise of the R3 argument: one coil bending moves the centre of mass
    towards its own end (its half shortens along the ground)."""
    shape = PhysicalPlant(robot("paper-r3"), mechanisms=("D1", "D2"))._shape
    for c in (0.1, 0.3, 0.5, 0.8, 1.0):
        left = shape.evaluate([c, 0.0])
        right = shape.evaluate([0.0, c])
        assert left[3] >= left[4] and right[4] >= right[3]


@pytest.mark.parametrize("mech, entry, sign", [(("D1", "D2"), (0, 2), -1), (("D2", "D1"), (0, 1), +1)])
def test_r3_entries_the_paper_reports_against_coulomb_friction(mech, entry, sign):
    """D1 left / D2 right: from 00 (left soft, right hard) contracting the left coil the left end
    anchors (grippier and more loaded), so 00->10 moves -x (paper: +1). Mirror for D2/D1, 00->01."""
    from proleg.sim.physical.measure import kinematic_signs

    k = kinematic_signs(robot("paper-r3"), mech)
    assert np.sign(k[entry]) == sign


# -- closed loop with the host-sim firmware ---------------------------------------------------
@pytest.fixture(scope="module")
def r1_runs():
    from proleg.sim.closed_loop import SimulatedRobot
    from proleg.report import SimSession

    r = robot("paper-r1")
    out = {}
    for d in ("+x", "-x"):
        sim = SimulatedRobot(r, plant=PhysicalPlant(r))
        out[d] = SimSession(sim).run_gait(d, 0, 40.0)
    return out


def test_r1_walks_plus_x_and_minus_x_with_the_firmware(r1_runs):
    assert r1_runs["+x"].displacement_mm > 5.0 and r1_runs["+x"].cycles >= 3
    assert r1_runs["-x"].displacement_mm < -5.0 and r1_runs["-x"].cycles >= 3


def test_r1_walks_without_faults_on_the_physical_plant(r1_runs):
    """The bang-bang hold on ψ has off phases (the fixed hold duty had none and ran into
    max_on_ms), so holding a state never trips the on-time limit."""
    assert not r1_runs["+x"].faults and not r1_runs["-x"].faults


def test_a_coil_that_cannot_reach_its_state_is_cold_soon_after_the_state_timeout():
    """power ×0.3: the coil never gets ψ past ψ*. Its rise lags, so it is boosted to the duty
    ceiling (ctl.h, CTL_BOOST_MS) and then creeps (one progress edge now and then, so the stall
    detector does not cut it); the 8 s state timeout stops it: from the fault on every coil
    is off, and 2 s later the coil is close to the ambient again (the claim's "cold coils")."""
    from proleg.sim.closed_loop import SimulatedRobot
    from proleg.report import SimSession

    r = robot("paper-r1")
    sim = SimulatedRobot(r, plant=PhysicalPlant(r, parse_conditions(["power=0.3"])))
    step, after = sim.step, []

    def watched():
        step()
        if sim.time_s >= 8.3:
            after.append((sim.board.pwm(0), sim.board.pwm(1), float(sim.plant.temperature_c[0])))

    sim.step = watched
    run = SimSession(sim).run_gait("+x", 0, 10.5)
    faults = [f for f in run.faults if f.code == "STATE_TIMEOUT"]
    assert faults and faults[0].time_s <= 8.3
    assert after and all(a == 0.0 and b == 0.0 for a, b, _ in after)
    assert after[-1][2] < 40.0   # ambient 25 °C; at the ceiling duty it sits near 68 °C


def _signs_by_sweeping(robot, mechanisms, margin_deg=4.0, rate_per_s=1.0, dt_s=0.005):
    """The oracle: the plant built with ``mechanisms`` swept pose by pose (what
    kinematic_signs did for each assignment before it replayed one sweep)."""
    from proleg.sim.physical.measure import IdealDrive

    plant = PhysicalPlant(robot, Conditions(), mechanisms=mechanisms)
    drive = IdealDrive(robot, plant, margin_deg)
    _, allowed = robot.transitions.dense()
    n = len(allowed)
    out = np.zeros((n, n))
    c = [0.0] * drive.n_act

    def go(target):
        for _ in range(int(4.0 / dt_s)):
            cmd = drive.command(plant.psi_deg.tolist(), target)
            for j, x in enumerate(cmd):
                c[j] = min(1.0, max(0.0, c[j] + x * rate_per_s * dt_s))
            plant.pose(c)
            if plant.true_state == target and all(x != 1 for x in cmd) and all(
                    x == 0 or c[j] == 0.0 for j, x in enumerate(cmd)):
                plant.pose(c)
                return True
        return False

    for a in range(n):
        for b in range(n):
            if a != b and allowed[a][b] and go(a):
                x0 = plant.displacement_mm
                if go(b):
                    out[a, b] = plant.displacement_mm - x0
    return out


@pytest.mark.parametrize("name", ["paper-r1", "paper-r2", "inchworm-3"])
def test_one_kinematic_sweep_replayed_per_assignment_is_the_sweep_of_each_assignment(name):
    """The D1/D2 inference scores every assignment from one sweep of the body (the poses do
    not depend on friction) with the anchor/slip solve replayed per assignment: it must give
    exactly what sweeping the plant built with each assignment gives."""
    import itertools

    from proleg.sim.physical.measure import kinematic_signs_all

    robot = load_robot(ROBOTS / f"{name}.toml")
    combos = list(itertools.product(("D1", "D2"), repeat=len(robot.limbs)))
    if len(combos) > 4:
        combos = [combos[0], combos[3], combos[5], combos[-1]]
    for combo, got in zip(combos, kinematic_signs_all(robot, combos)):
        assert np.array_equal(got, _signs_by_sweeping(robot, combo)), combo


@pytest.mark.parametrize("end", ["rear", "front"])
def test_a_limb_name_or_an_end_names_the_same_end_for_limb_and_coil_keys(end):
    """caterpillar-4's limbs are tail, rear, front, head on sma-tail … sma-head. `front` used to
    mean limb front for imu_bias_deg but the last coil, sma-head, for power_scale."""
    r = robot("caterpillar-4")
    p = PhysicalPlant(r, parse_conditions([f"power_scale={end}:0.5", f"imu_bias_deg={end}:3"]))
    limb = [lb.name for lb in r.limbs].index(end)
    coil = [a.name for a in r.actuators].index(r.limbs[limb].actuator)
    assert [i for i, s in enumerate(p._coils.pscale) if s != 1.0] == [coil]
    base = PhysicalPlant(r)
    assert [i for i, (a, b) in enumerate(zip(p._sense_off, base._sense_off)) if a != b] == [limb]


def test_rear_and_front_are_the_first_and_last_limbs_coils_where_no_limb_has_those_names():
    r = robot("paper-r1")  # limbs left, right on sma-left, sma-right
    p = PhysicalPlant(r, parse_conditions(["power_scale=front:0.5", "overlap_mm=rear:14"]))
    assert p._coils.pscale == [1.0, 0.5]
    with pytest.raises(SimError) as e:
        PhysicalPlant(r, parse_conditions(["power_scale=middle:0.5"]))
    assert "sma-left, sma-right, left (its limb), right (its limb), rear, front, or 0..1" in str(e.value)
