"""The table plant books the state changes the firmware's classifier makes: levels counted with
the limbs' hysteresis bands (psi.h), each level a multi-level limb passes on its way booked in
turn, changes the window joins into a transition the matrix forbids booked leg by leg
(docs/plant.md, "The table plant")."""

from __future__ import annotations

import math
import random
from pathlib import Path

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from proleg.report.gait_run import SimSession
from proleg.robot import load_robot
from proleg.sim.closed_loop import SimulatedRobot
from proleg.sim.plant import LimbParams, Plant, PlantParams
from proleg.sim.sma import SmaParams
from proleg.states import label, limb_levels

FIXTURES = Path(__file__).parent / "fixtures"
X = np.nan


# -- brute-force oracle ------------------------------------------------------------------------------
def firmware_level(prev: int | None, psi: float, stars: list[float], h: float) -> int:
    """psi.c's psi_classify, written out: no history counts the upper edges reached; from a level,
    up past ψ* + h/2, down below ψ* − h/2."""
    level = 0 if prev is None else prev
    while level < len(stars) and psi >= stars[level] + h / 2:
        level += 1
    while level > 0 and psi < stars[level - 1] - h / 2:
        level -= 1
    return level


def firmware_states(psi_log: list[list[float]], limbs: list[tuple[list[float], float]], levels) -> list[int]:
    """The state after each sample, each limb classified as the firmware does."""
    prev: list[int | None] = [None] * len(limbs)
    out = []
    for psi in psi_log:
        prev = [firmware_level(p, x, stars, h) for p, x, (stars, h) in zip(prev, psi, limbs)]
        idx = 0
        for lvl, k in zip(prev, levels):
            idx = idx * k + lvl
        out.append(idx)
    return out


def along(states: list[int], matrix: np.ndarray) -> float:
    """The sum of the matrix's entries over the state changes of ``states``."""
    return sum(float(matrix[a, b]) for a, b in zip(states, states[1:]) if a != b)


# -- property: random multi-level bodies, random drives -------------------------------------------------
@st.composite
def bodies(draw):
    n = draw(st.integers(1, 3))
    limbs = []
    for i in range(n):
        k = draw(st.integers(2, 4)) if i else draw(st.integers(3, 4))  # at least one multi-level limb
        first = draw(st.floats(4.0, 15.0))
        gaps = [draw(st.floats(4.0, 12.0)) for _ in range(k - 2)]
        stars = [first]
        for g in gaps:
            stars.append(stars[-1] + g)
        h = draw(st.floats(0.0, min([3.0] + [g * 0.9 for g in gaps])))
        limbs.append(LimbParams(name=f"l{i}", psi_star_deg=tuple(stars), hysteresis_deg=h, actuator=i))
    acts = tuple(SmaParams(name=f"c{i}", channel=i) for i in range(n))
    params = PlantParams(actuators=acts, limbs=tuple(limbs), simultaneous_s=0.0, noise_mm=0.0,
                         cross_gain_deg=draw(st.floats(0.0, 30.0)))
    ns = math.prod(params.levels)
    matrix = np.array(draw(st.lists(st.floats(-1.0, 1.0), min_size=ns * ns, max_size=ns * ns))).reshape(ns, ns)
    # a gait: each coil's duty held for a random time, again and again
    steps = draw(st.lists(st.tuples(st.lists(st.sampled_from([0.0, 0.3, 0.6, 0.9]), min_size=n, max_size=n),
                                    st.floats(0.05, 1.5)), min_size=2, max_size=12))
    return params, matrix, steps


@settings(max_examples=60, deadline=None)
@given(bodies())
def test_the_table_plant_moves_by_the_matrix_along_the_firmwares_state_sequence(body):
    """Every change of state as the firmware counts it (hysteresis bands, a multi-level limb's
    levels one by one as it passes them) earns its entry, and nothing else moves the robot: a
    held limb sagging past ψ* but not out of its band changes nothing (before, the plant counted
    bare ψ*: a flicker the firmware never saw, booked as two transitions)."""
    params, matrix, steps = body
    plant = Plant(params, matrix)
    limbs = [(list(lb.psi_star_deg), lb.hysteresis_deg) for lb in params.limbs]
    psi_log = [list(plant.psi_deg)]
    for duties, seconds in steps:
        for _ in range(round(seconds / 0.005)):
            plant.step(0.005, duties)
            psi_log.append(list(plant.psi_deg))
    states = firmware_states(psi_log, limbs, params.levels)
    assert plant.true_state == states[-1]
    assert math.isclose(plant.displacement_mm, along(states, matrix) * params.step_mm, abs_tol=1e-9)
    assert [(t.src, t.dst) for t in plant.transitions] == [(a, b) for a, b in zip(states, states[1:]) if a != b]


# -- the window's joins -----------------------------------------------------------------------------
class ScriptedPlant(Plant):
    """The table plant with its true state given as (from time s, state) instead of from ψ."""

    def __init__(self, script, rewards, levels):
        self.script = script
        limbs = tuple(LimbParams(name=f"l{i}", psi_star_deg=tuple(10.0 * (j + 1) for j in range(k - 1)),
                                 actuator=i) for i, k in enumerate(levels))
        acts = tuple(SmaParams(name=f"c{i}", channel=i) for i in range(len(levels)))
        super().__init__(PlantParams(actuators=acts, limbs=limbs, noise_mm=0.0, step_mm=1.0), rewards)

    def _classify(self) -> int:
        return [s for t, s in self.script if getattr(self, "_t", 0.0) >= t - 1e-9][-1]


def one_level(levels) -> np.ndarray:
    """A matrix allowing exactly the one-level steps, each its own value (1 + index)."""
    n = math.prod(levels)
    m = np.full((n, n), X)
    for a in range(n):
        m[a, a] = 0.0
        for b in range(n):
            if sum(abs(x - y) for x, y in zip(limb_levels(a, levels), limb_levels(b, levels))) == 1:
                m[a, b] = 1.0 + a * n + b
    return m


def test_two_limbs_crossing_a_few_ms_apart_book_each_step_the_firmware_saw():
    """crab-3 on the table plant: 110 -> 120 and 120 -> 220 5 ms apart, joined by the 30 ms window
    into 110 -> 220, which a one-level matrix forbids: it earned nothing and counted as
    unexpected, where the firmware saw two allowed steps."""
    levels = (4, 3, 2)
    m = one_level(levels)
    s = {lab: int(lab[0]) * 6 + int(lab[1]) * 2 + int(lab[2]) for lab in ("110", "120", "220")}
    p = ScriptedPlant([(0.0, s["110"]), (1.0, s["120"]), (1.005, s["220"])], m, levels)
    for _ in range(200):
        p.step(0.01, [0.0, 0.0, 0.0])
    assert [(label(t.src, levels), label(t.dst, levels)) for t in p.transitions] == [("110", "120"), ("120", "220")]
    assert p.unexpected_transitions == 0
    assert p.displacement_mm == m[s["110"], s["120"]] + m[s["120"], s["220"]]


def test_a_joined_change_the_matrix_allows_is_still_one_transition():
    # R1's 00 -> 11 with both ends crossing 5 ms apart: the matrix's own two-limb entry
    m = np.array([[0, 1, 2, 7.0], [X, 0, X, X], [X, X, 0, X], [X, X, X, 0]])
    p = ScriptedPlant([(0.0, 0), (1.0, 2), (1.005, 3)], m, (2, 2))
    for _ in range(200):
        p.step(0.01, [0.0, 0.0])
    assert [(t.src, t.dst) for t in p.transitions] == [(0, 3)] and p.displacement_mm == 7.0


# -- the fixture, with its firmware -------------------------------------------------------------------
def crab3_with_matrix(tmp_path: Path, seed: int = 0, simultaneous_s: float | None = None) -> Path:
    """tests/fixtures/crab-3-entry.toml with a seeded one-level matrix in mm (its own is unmeasured)."""
    robot = load_robot(FIXTURES / "crab-3-entry.toml")
    levels = robot.levels
    n = math.prod(levels)
    rng = random.Random(seed)
    rows = []
    for a in range(n):
        row = []
        for b in range(n):
            d = sum(abs(x - y) for x, y in zip(limb_levels(a, levels), limb_levels(b, levels)))
            row.append(f"{rng.uniform(-0.2, 0.2):.4f}" if d == 1 else "0" if d == 0 else '"x"')
        rows.append("[" + ", ".join(row) + "]")
    text = (FIXTURES / "crab-3-entry.toml").read_text()
    head, _, _ = text.partition("[transitions]")
    tail = text[text.index("[control]"):]
    states = ", ".join(f'"{label(s, levels)}"' for s in range(n))
    out = tmp_path / "crab-3.toml"
    if simultaneous_s is not None:
        tail += f"\n[plant]\nsimultaneous_s = {simultaneous_s}\n"
    out.write_text(f'{head}[transitions]\nunits = "mm"\nstates = [{states}]\nmatrix = [\n' + ",\n".join(rows)
                   + "]\n\n" + tail)
    return out


def test_crab3_on_the_table_plant_books_the_state_changes_its_firmware_counts(tmp_path):
    """crab-3 (4, 3 and 2 levels) walking gait 0 for 10 s with its firmware: the plant books the
    changes of state the firmware's classifier makes of the body's ψ, sample by sample, and moves
    by their entries. Before, a limb held or lifted near ψ* inside its band flickered across bare
    ψ* (crab-3 with its measured matrix: 121 -> 111 -> 121 while the firmware held 121), booked as
    two transitions the firmware never saw. (The firmware's own telemetry reads ψ through its IMU
    model, a few tenths of a degree off at times, so it is not the oracle.)"""
    robot = load_robot(crab3_with_matrix(tmp_path, simultaneous_s=0.0))
    sim = SimulatedRobot(robot, plant="table")
    plant = sim.plant
    psi_log = [list(plant.psi_deg)]
    step = plant.step

    def logged(dt_s, duties):
        step(dt_s, duties)
        psi_log.append(list(plant.psi_deg))

    plant.step = logged
    run = SimSession(sim).run_gait("+x", 0, 10.0)
    assert run.ok and len(run.states_reached) >= 5
    limbs = [(list(lb.psi_star_deg), lb.hysteresis_deg) for lb in robot.limbs]
    states = firmware_states(psi_log, limbs, robot.levels)
    changes = [(a, b) for a, b in zip(states, states[1:]) if a != b]
    assert [(t.src, t.dst) for t in plant.transitions] == changes
    reward, allowed = robot.transitions.dense()
    assert all(allowed[a, b] for a, b in changes) and run.unexpected_transitions == 0
    assert math.isclose(run.displacement_mm, sum(reward[a, b] for a, b in changes), abs_tol=1e-9)
