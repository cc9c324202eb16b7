"""proleg's gait library against the TerreSoRo gait synthesiser, heading by heading.

Their synthesiser (github.com/clfreeman7/Path_Planning, +offlineanalysis/GaitSynthesizer.m,
goal 1 = translation): a binary integer programme over the 240 transitions x_e ∈ {0, 1},
minimising Σ f_e x_e with

    f_e = α_x·Δx_e + α_y·Δy_e + 0.5·(σ²x_e + σ²y_e + σ²θ_e) + 1      (Δθ, σ²θ in rad, rad²)

subject to in-degree = out-degree and in-degree ≤ 1 at every state, Σ x_e ≥ 2, the rotation
|Σ Δθ_e x_e| ≤ 5° (in rad), and one cycle only (they add a cutting plane whenever the
solver returns several). (α_x, α_y) is drawn by Latin hypercube sampling, so each draw asks
for a different heading; for the heading h we use α = −2·(cos h, sin h), the "2·(−Δx)" of
their +x gait rotated to h.

The oracle solves that programme exactly with scipy's MILP (HiGHS) — one solve per lowest
state r of the cycle, with Miller–Tucker–Zemlin ordering constraints so that every chosen
transition lies on the one cycle through r — and takes the cheapest. proleg answers the
same question as a maximisation (tests/test_planar_terresoro.py: THEIR_WEIGHTS, THEIR_COST,
−2 × score = their cost); the test asserts that for every heading of the library, the cost
of proleg's gait in their units is at most the oracle's optimum (it is equal: both are
exact), that it is a simple cycle, and that it turns by at most 5° per pass.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

optimize = pytest.importorskip("scipy.optimize")
from scipy.optimize import Bounds, LinearConstraint, milp  # noqa: E402

from proleg.gait.library import gait_library  # noqa: E402
from proleg.robot import load_robot  # noqa: E402

FIXTURE = Path(__file__).parent / "fixtures" / "terresoro-4.toml"
THEIR_WEIGHTS = (0.25, 0.25, 0.25 * (math.pi / 180) ** 2)
THEIR_COST = 0.5
CAP_DEG = 5.0
HEADINGS = [0, 45, 90, 135, 180, 225, 270, 315]  # the eight-way library a path planner would carry


@pytest.fixture(scope="module")
def table():
    return load_robot(FIXTURE).transitions


def their_cost(table, heading_deg: float) -> np.ndarray:
    """f_e per transition (aligned with table.src/dst), their units."""
    p = table.planar
    h = math.radians(heading_deg)
    rad2 = (math.pi / 180) ** 2
    motion = math.cos(h) * np.asarray(table.reward) + math.sin(h) * p.dy
    return -2.0 * motion + 0.5 * (p.var_dx + p.var_dy + p.var_dtheta_deg * rad2) + 1.0


def their_optimum(table, heading_deg: float) -> float:
    """The exact optimum of their programme (module doc), by MILP."""
    n, src, dst = table.n_states, np.asarray(table.src), np.asarray(table.dst)
    f = their_cost(table, heading_deg)
    turn = np.radians(np.asarray(table.planar.dtheta_deg))
    cap = math.radians(CAP_DEG)
    best = math.inf
    for r in range(n):
        edges = np.flatnonzero((src >= r) & (dst >= r))
        m = len(edges)
        if m < 2:
            continue
        nv = m + n  # x_e, then an order u_v per state (u_r unused)
        c = np.concatenate([f[edges], np.zeros(n)])
        rows, lo, hi = [], [], []

        def row():
            rows.append(np.zeros(nv))
            return rows[-1]

        for v in range(r, n):
            a = row()  # in − out = 0
            a[:m] += (dst[edges] == v).astype(float) - (src[edges] == v).astype(float)
            lo.append(0.0)
            hi.append(0.0)
            b = row()  # in ≤ 1 (= 1 at the root)
            b[:m] = (dst[edges] == v).astype(float)
            lo.append(1.0 if v == r else 0.0)
            hi.append(1.0)
        a = row()  # rotation within the cap
        a[:m] = turn[edges]
        lo.append(-cap)
        hi.append(cap)
        big = float(n)
        for k, e in enumerate(edges):  # MTZ: u_w ≥ u_v + 1 when v → w is chosen, v, w ≠ r
            v, w = int(src[e]), int(dst[e])
            if v == r or w == r:
                continue
            a = row()
            a[m + v], a[m + w], a[k] = 1.0, -1.0, big
            lo.append(-np.inf)
            hi.append(big - 1.0)
        integrality = np.concatenate([np.ones(m), np.zeros(n)])
        bounds = Bounds(np.zeros(nv), np.concatenate([np.ones(m), np.full(n, float(n))]))
        res = milp(c, constraints=LinearConstraint(np.array(rows), lo, hi), integrality=integrality, bounds=bounds)
        if res.status == 0:
            best = min(best, float(res.fun))
    return best


def test_the_oracle_reproduces_their_published_optima(table):
    assert their_optimum(table, 0) == pytest.approx(0.9745, abs=5e-5)    # 0001→0011
    assert their_optimum(table, 180) == pytest.approx(0.6804, abs=5e-5)  # 0110→1110


def test_for_every_heading_of_the_library_proleg_is_at_least_as_good_as_their_synthesiser(table):
    library = gait_library(table, ",".join(map(str, HEADINGS)), "total", variance_weight=THEIR_WEIGHTS,
                           transition_cost=THEIR_COST, rotation_cap_deg=CAP_DEG, simple_cycles=True)
    assert [e.heading.heading_deg for e in library] == HEADINGS
    for entry in library:
        h = entry.heading.heading_deg
        gait = entry.gait
        assert gait is not None, h
        open_cycle = gait.states[:-1]
        assert len(set(open_cycle)) == len(open_cycle) >= 2  # a simple cycle
        f = their_cost(table, h)
        index = {(int(a), int(b)): i for i, (a, b) in enumerate(zip(table.src, table.dst))}
        steps = [index[(a, b)] for a, b in zip(gait.states, gait.states[1:])]
        turn = float(np.sum(np.asarray(table.planar.dtheta_deg)[steps]))
        assert abs(turn) <= CAP_DEG + 1e-9, h
        ours = float(np.sum(f[steps]))
        theirs = their_optimum(table, h)
        assert ours <= theirs + 1e-9, (h, ours, theirs)
        assert -2 * entry.result.value == pytest.approx(ours, abs=1e-9)  # proleg's value is their cost, scaled
