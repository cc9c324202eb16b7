"""The table plant's planar pose: SE(2) composition of the file's (Δx, Δy, Δθ), seeded noise."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from proleg.errors import SimError
from proleg.gait.compose import compose_path
from proleg.sim.plant import PlanarMotion, Plant, PlantParams

X = np.nan
R1_LEFT_ONLY = np.array([[0, X, 1, X], [X, X, X, X], [-1, X, 0, 1], [X, X, 0, 0]], float)
DY = np.array([[0, 0, 0.5, 0], [0, 0, 0, 0], [0.2, 0, 0, -0.3], [0, 0, 0.1, 0]])
DTH = np.array([[0, 0, 10.0, 0], [0, 0, 0, 0], [-4.0, 0, 0, 30.0], [0, 0, 5.0, 0]])
ZERO = np.zeros((4, 4))


def motion(var=0.0) -> PlanarMotion:
    v = np.full((4, 4), var)
    return PlanarMotion(DY, DTH, v, v, v)


def run_left_limb(plant: Plant) -> Plant:
    """00 → 10 → 11 → 10 → 00 with the right actuator dead (as in test_sim_plant)."""
    plant.kill_actuator(1)
    for _ in range(3000):
        plant.step(0.002, [0.6, 0.6])
    for _ in range(3000):
        plant.step(0.002, [0.0, 0.6])
    return plant


def test_without_noise_the_pose_is_the_se2_composition_of_the_steps():
    p = run_left_limb(Plant(PlantParams(), R1_LEFT_ONLY, planar=motion()))
    steps = [(a, b) for _, a, b, _ in p.transitions]
    assert steps == [(0, 2), (2, 3), (3, 2), (2, 0)]
    k = p.params.step_mm
    body = np.array([[R1_LEFT_ONLY[a, b] * k, DY[a, b] * k, DTH[a, b]] for a, b in steps])
    want = compose_path(body)
    assert p.pose == pytest.approx((want[-1].x, want[-1].y, want[-1].theta_deg), abs=1e-9)
    assert [q[1:] for q in p.poses] == [pytest.approx((w.x, w.y, w.theta_deg), abs=1e-9) for w in want]
    assert p.displacement_mm == pytest.approx(1 * k)  # Δx alone, as without planar statistics


def test_without_planar_statistics_nothing_changes():
    plain = run_left_limb(Plant(PlantParams(noise_mm=0.3), R1_LEFT_ONLY, seed=4))
    planar = run_left_limb(Plant(PlantParams(noise_mm=0.3), R1_LEFT_ONLY, seed=4, planar=motion()))
    assert plain.pose is None and plain.poses == []
    assert plain.transitions == planar.transitions  # the same draws for the x noise
    assert plain.displacement_mm == planar.displacement_mm


def test_noise_is_seeded_and_has_the_files_variance():
    a = run_left_limb(Plant(PlantParams(), R1_LEFT_ONLY, seed=1, planar=motion(0.04)))
    b = run_left_limb(Plant(PlantParams(), R1_LEFT_ONLY, seed=1, planar=motion(0.04)))
    c = run_left_limb(Plant(PlantParams(), R1_LEFT_ONLY, seed=2, planar=motion(0.04)))
    assert a.pose == b.pose and a.pose != c.pose
    # one transition many times from the origin: sample means and variances of the step
    p = Plant(PlantParams(), R1_LEFT_ONLY, seed=3, planar=motion(0.04))
    k = p.params.step_mm
    draws = []
    for _ in range(4000):
        p._poses[:] = [(0.0, 0.0, 0.0, 0.0)]
        dx = p._move_pose(0, 2, 1.0 * k)
        draws.append((dx, p.pose[1], p.pose[2]))
    d = np.array(draws)
    assert d[:, 0].mean() == pytest.approx(k, abs=4 * 0.2 * k / math.sqrt(4000))
    assert d[:, 0].var() == pytest.approx(0.04 * k * k, rel=0.1)
    assert d[:, 2].mean() == pytest.approx(10.0, abs=4 * 0.2 / math.sqrt(4000))
    assert d[:, 2].var() == pytest.approx(0.04, rel=0.1)


def test_bad_planar_statistics_are_refused():
    with pytest.raises(SimError, match="planar statistics"):
        Plant(PlantParams(), R1_LEFT_ONLY, planar=PlanarMotion(DY, DTH, ZERO - 1, ZERO, ZERO))
    with pytest.raises(SimError, match="planar statistics: dy"):
        Plant(PlantParams(), R1_LEFT_ONLY, planar=PlanarMotion(np.zeros((3, 3)), DTH, ZERO, ZERO, ZERO))


def test_the_robot_files_statistics_reach_the_plant(tmp_path):
    from proleg.robot import load_robot
    from proleg.sim.plant import planar_motion_from_robot
    from test_planar_cli import PLANAR

    path = tmp_path / "planar.toml"
    path.write_text(PLANAR)
    m = planar_motion_from_robot(load_robot(path))
    assert m is not None and m.dtheta_deg[0, 2] == 10.0 and m.var_dx[2, 3] == 1.0 and m.var_dy.sum() == 0.0
    assert planar_motion_from_robot(load_robot(Path(__file__).resolve().parents[1] / "robots" / "paper-r1.toml")) is None
