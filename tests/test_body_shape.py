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
