"""The simulated body's shape (proleg.body.Shape): properties that hold for any number of
contacts and any contractions, checked against the geometry itself rather than numbers.

- Locality: a contact's angle ψ is set by the two sections it stands between, so coils whose
  spans lie wholly outside them cannot change it, however far the rest of the body curls.
  (The angles were once a tangent angle accumulated along the body minus an atan2 chord
  angle, unwrapped: once the body had turned more than 180° in all, e.g. caterpillar-4 with
  both prolegs drawn, a contact read 389° or −137° instead of 29° or 43°.)
- Mirror symmetry: the body reversed end to end with its contractions reversed has its
  angles reversed.
- Range: every ψ lies in (−180°, 180°], and below 90° for these bodies (an arc's
  tangent-chord angle is half its turning, at most κ_max × section).
"""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from proleg.body import SECTION_MM, Shape, body_geometry


def _shape(n: int, overlap: float) -> Shape:
    return Shape(body_geometry(list(range(n)), n, SECTION_MM * (n - 1), [overlap] * n), tabulate=False)


bodies = st.tuples(st.integers(min_value=2, max_value=8), st.sampled_from([0.0, 4.0, 8.0, 12.0]))
contractions = st.lists(st.floats(min_value=0.0, max_value=1.0), min_size=8, max_size=8)


@settings(max_examples=150, deadline=None, derandomize=True)
@given(body=bodies, c=contractions, other=contractions, contact=st.integers(min_value=0, max_value=7))
def test_a_contacts_angle_depends_only_on_the_coils_over_its_own_sections(body, c, other, contact):
    n, overlap = body
    shape = _shape(n, overlap)
    i = contact % n
    lo = shape.geo.contacts_mm[max(0, i - 1)]
    hi = shape.geo.contacts_mm[min(n - 1, i + 1)]
    far = [j for j, (a, b) in enumerate(shape.geo.spans) if b <= lo or a >= hi]
    c1 = np.array(c[:n])
    c2 = c1.copy()
    c2[far] = np.array(other[:n])[far]
    psi = shape.compute(np.stack([c1, c2]))[0]
    assert abs(psi[0, i] - psi[1, i]) < 1e-6, (far, psi)


@settings(max_examples=100, deadline=None, derandomize=True)
@given(body=bodies, c=contractions)
def test_the_reversed_body_has_its_angles_reversed_and_every_angle_in_range(body, c):
    n, overlap = body
    shape = _shape(n, overlap)
    c1 = np.array(c[:n])
    psi, rev = shape.compute(np.stack([c1, c1[::-1]]))[0]
    assert np.allclose(psi, rev[::-1], atol=1e-6)
    assert np.all(np.abs(psi) < 90.0), psi


@settings(max_examples=150, deadline=None, derandomize=True)
@given(body=st.tuples(st.integers(min_value=1, max_value=8), st.sampled_from([0.0, 8.0, 12.0, 30.0])),
       strain=st.sampled_from([0.03, 0.06, 0.12]), c=contractions)
def test_the_tabulated_body_is_the_computed_one_within_a_hundredth(body, strain, c):
    """The plant's shape is interpolated in tables built once per body: the whole body's for one
    or two coils, each section's for more (its angles, chord and centre of mass depend only on
    the coils over it). At any contractions it reads what the direct computation gives, within
    0.01 (° for ψ, mm for gaps and the centre of mass, a fraction for loads): below the IMU's
    resolution and the plant's SHAPE_EPS. A section that three coils bend (30 mm of overlap
    reaches past the next contact) has no table: the body is computed directly."""
    n, overlap = body
    n_contacts = max(n, 2)  # one coil: the paper's one-actuator body, both ends on it
    geo = body_geometry([0] * n_contacts if n == 1 else list(range(n)), n, SECTION_MM * (n_contacts - 1),
                        [overlap] * n, working_strain=strain)
    tabulated, direct = Shape(geo), Shape(geo, tabulate=False)
    if n > 2:
        assert (tabulated._sec_tables is None) == (overlap > SECTION_MM / 2), "tables per section, unless 3 coils bend one"
    got, want = tabulated.evaluate(c[:n]), direct.evaluate(c[:n])
    assert np.allclose(got, want, rtol=0, atol=0.01), (np.array(got) - np.array(want)).round(4)


@settings(max_examples=60, deadline=None)
@given(st.integers(min_value=2, max_value=5), st.sampled_from([0.0, 8.0, 20.0]),
       st.floats(min_value=0.02, max_value=0.2), contractions)
def test_a_body_the_limit_check_passes_never_wraps_a_contact_angle(n, overlap, strain, c):
    """Past a half turn between two contacts a section may curl over itself, its ends pass each
    other and ψ = tangent − chord wraps. ``curl_problem`` checked each coil's span only: R1
    (two coils overlapping 16 mm) with working_strain 0.12 bends 165° per coil and 330° between
    its limbs, and read ψ = −16.7° at full stroke (the gait check said "'left' needs ψ ≥ 87.0° and
    gets at most −16.7°"). Wherever it passes a body, each section's end angles now add up to its
    turning, unwrapped."""
    from proleg.body import curl_problem

    geo = body_geometry(list(range(n)), n, 80.0 if n == 2 else SECTION_MM * (n - 1), [overlap] * n,
                        working_strain=strain)
    if curl_problem(geo):
        return
    shape = Shape(geo, tabulate=False)
    cc = np.array([c[:n]])
    sections = shape._sections(cc)
    kappa = (cc @ shape._w)[0]
    for (p, q), (psi_p, psi_q, _g, _u) in zip(zip(shape._cnode, shape._cnode[1:]), sections):
        turning = np.degrees(kappa[p:q].sum() * shape.ds)
        assert abs(psi_p[0] + psi_q[0] - turning) < 1e-6 and -1e-9 <= psi_p[0] <= 180.0


def test_the_limit_check_covers_the_body_between_two_limbs_and_names_the_key(tmp_path, caplog):
    import logging
    from pathlib import Path

    from proleg.body import curl_problem
    from proleg.gait.feasibility import gait_problems
    from proleg.robot import load_robot

    geo = body_geometry([0, 1], 2, 80.0, [8.0, 8.0], working_strain=0.12)
    assert curl_problem(geo).startswith(
        "with every coil at full stroke the body between limbs 1 and 2 (0–80 mm of the 80 mm body, bent by coils 1 "
        "and 2, which add where they overlap) turns by 330°, past the 180° the physical plant models")
    assert curl_problem(body_geometry([0, 1], 2, 80.0, [8.0, 8.0], working_strain=0.06)) == ""  # R1: 165°

    src = (Path(__file__).resolve().parents[1] / "robots" / "paper-r1.toml").read_text(encoding="utf-8")
    src = src.replace('name = "left"\npsi_star_deg = [20.0]', 'name = "left"\npsi_star_deg = [86]', 1)
    path = tmp_path / "r1.toml"
    path.write_text(src + "\n[plant]\nworking_strain = 0.12\n", encoding="utf-8")
    with caplog.at_level(logging.WARNING, logger="proleg"):
        robot = load_robot(path)
    said = [r.getMessage() for r in caplog.records]
    assert any(f"{path}: plant.working_strain: with every coil at full stroke the body between limbs 1 and 2" in m
               and "a smaller working_strain than 0.12" in m for m in said), said
    assert not [m for m in said if "-16.7" in m or "−16.7" in m]
    # no reach from a wrapped angle: the gait check does not claim 11 is out of reach
    assert robot.unreachable == {}
    assert not [p for p in gait_problems(robot, robot.transitions.sequence("00,10,11,01,00")) if "16.7" in p.message]
