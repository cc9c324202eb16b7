"""proleg against the published TerreSoRo synthesiser (Mahendran, Freeman, Chang, McDougall,
Vela & Vikas, IROS 2023, doi:10.1109/IROS55552.2023.10341926; data: github.com/clfreeman7/
Path_Planning, demos/data/experiment_2_motion_primitives.mat).

That repository carries no licence, so its data is not committed here. The tests read
tests/fixtures/terresoro-4.toml: per-transition means and sample variances derived from
the 5 trials (numerical summaries, with attribution in the file's header; no raw trial).
With PROLEG_TERRESORO_MAT naming a fetched copy of the .mat, one more test checks that the
converter still turns it into exactly that fixture.
"""

from __future__ import annotations

import math
import os
from pathlib import Path

import pytest

from proleg.gait.compose import gait_path, net_motion
from proleg.gait.planar import PlanarObjective, optimal_planar_gaits
from proleg.robot import load_robot

FIXTURE = Path(__file__).parent / "fixtures" / "terresoro-4.toml"
MAT = os.environ.get("PROLEG_TERRESORO_MAT", "")

#: Their cost per transition, 2·(−Δx) + 0.5·(σ²x + σ²y + σ²θ[rad²]) + 1 (minimised), is
#: −2 × proleg's score Δx − 0.25·(σ²x + σ²y) − 0.25·(π/180)²·σ²θ[deg²] − 0.5 (maximised).
THEIR_WEIGHTS = (0.25, 0.25, 0.25 * (math.pi / 180) ** 2)
THEIR_COST = 0.5
THEIR_CAP_DEG = 5.0


@pytest.fixture(scope="module")
def table():
    return load_robot(FIXTURE).transitions


@pytest.mark.skipif(not MAT or not os.path.isfile(MAT), reason="PROLEG_TERRESORO_MAT not set")
def test_the_fixture_is_what_the_converter_makes_of_the_published_file():
    pytest.importorskip("scipy.io")
    from proleg.convert.terresoro import read_terresoro, robot_toml

    made = robot_toml(read_terresoro(MAT), name="terresoro-4").splitlines()
    kept = FIXTURE.read_text().splitlines()
    # the header names the commit the fixture came from; everything else is identical
    assert [ln for ln in made if "(commit" not in ln and not ln.startswith("# demos/")] == \
        [ln for ln in kept if "(commit" not in ln and not ln.startswith("# demos/")]


@pytest.mark.parametrize("heading, states, cost", [(0.0, ("0001", "0011"), 0.9745), (180.0, ("0110", "1110"), 0.6804)])
def test_proleg_finds_their_optima(table, heading, states, cost):
    res = optimal_planar_gaits(table, PlanarObjective(heading, THEIR_WEIGHTS, THEIR_COST), "total",
                               rotation_cap_deg=THEIR_CAP_DEG, simple_cycles=True)
    assert [tuple(table.label(s) for s in g.states[:-1]) for g in res.gaits] == [states]
    assert -2 * res.value == pytest.approx(cost, abs=5e-5)
    assert res.below_zero  # every cycle costs something in their units


def test_the_capped_plus_x_gait_heads_along_plus_x_and_the_uncapped_one_circles(table):
    capped = optimal_planar_gaits(table, PlanarObjective(0.0, THEIR_WEIGHTS, THEIR_COST), "total",
                                  rotation_cap_deg=THEIR_CAP_DEG, simple_cycles=True).gaits[0]
    one = net_motion(table, capped.states)
    assert one.x > 0 and abs(one.y) < one.x and abs(one.theta_deg) <= THEIR_CAP_DEG
    # Δx alone (rate, no cap): 0001→1010→1101→0010→0110, turning −13.5° a pass
    plain = optimal_planar_gaits(table, PlanarObjective(0.0), "rate").gaits[0]
    assert [table.label(s) for s in plain.states] == ["0001", "1010", "1101", "0010", "0110", "0001"]
    assert net_motion(table, plain.states).theta_deg == pytest.approx(-13.5, abs=0.1)
    # over the same number of transitions (40), the capped gait ends further along +x
    far = gait_path(table, capped.states, 20)[-1]
    wandering = gait_path(table, plain.states, 8)[-1]
    assert far.x > 0 and abs(math.degrees(math.atan2(far.y, far.x))) < abs(math.degrees(math.atan2(wandering.y, wandering.x)))
