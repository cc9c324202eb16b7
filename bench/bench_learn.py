"""Learning benchmark: trials and time needed vs accuracy of the learned matrix.

Part 1 — sampling comparison, pure Python (no firmware, no plant): every transition a
scheme walks yields Δx = truth + N(0, σ_e²), σ_e per transition (heteroscedastic, uniform
0.3–2.5 mm; fixed seed). Time = Σ per-transition durations (uniform 0.6–1.2 s per
transition, fixed) + the rests between thermally limited pieces (``pieces.split`` with the
coil limits of a robot with one coil per limb, max_on 3 s, rest 1.5 s). Robots:
  paper-r1-mm  4 states: paper R1's matrix × 4 mm, each entry ±10 %;
  synth-8      8 states (3 binary limbs), synth-16 16 states (4 binary limbs): transitions
               changing one or two limbs, 15 % of them forbidden at random (kept strongly
               connected), rewards N(0, 4 mm).
Schemes: euler — rounds of one randomised Euler tour each (pMFC); adaptive — one tour with
R = 2, then rounds that make once more each of the 25 % of transitions with the widest
95 % interval (``plan.adaptive_demand``), as closed tours from where the robot is. Every
transition walked counts as a trial, also the ones added to balance or join a tour.
Metrics (mean of 5 seeds) at budgets of k × (number of transitions): RMSE of the means,
widest 95 % half-width, coverage (share of intervals holding the truth), sign agreement
(|truth| > 1 mm), and gait % = true rate of the rate-optimal gait of the learned matrix /
the true optimum's rate.

Part 2 — the proof in closed loop: ``learn.simulated.explore_simulated`` (host-sim firmware +
table plant) with R = 5 on paper-r1, paper-r3, inchworm-3 (8 states) and caterpillar-4 (36
states), seeds 1–8 (caterpillar-4: 1–3), each against a hidden truth from ``proleg.learn.truth`` (the robot's
matrix in mm, each entry ±10 %, noise 0.5 mm per plant transition, merged into the file's
own ``[plant]``). Accuracy is measured against what the plant did per firmware transition
(``learn.evaluate.effective_truth``: a transition that changes two limbs passes through an
intermediate state in the table plant, whose entries then add up; for the one-limb-per-step
robots that is the truth file), and against the truth file. ``claims_hold``: sign right
wherever the truth moves, ≥ 90 % of truths inside their 95 % intervals, learned gait ≥ 95 %
of the true optimum's speed. With honest 95 % intervals the ≥ 90 % coverage is itself a
random event for 12 or 24 entries (P(≥ 3 of 24 outside) ≈ 12 %), so the share of seeds
that meet it is reported, not only one seed.

Writes bench/results/learn.json and prints the tables.
"""

from __future__ import annotations

import json
import os
import platform
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "host" / "src"))

import numpy as np  # noqa: E402

from proleg.learn.estimate import estimate  # noqa: E402
from proleg.learn.evaluate import accuracy  # noqa: E402
from proleg.learn.measure import Trial  # noqa: E402
from proleg.learn.pieces import PieceLimits, split  # noqa: E402
from proleg.learn.plan import adaptive_demand  # noqa: E402
from proleg.learn.tours import exploration, strongly_connected_components  # noqa: E402
from proleg.robot import load_robot  # noqa: E402
from proleg.transitions import TransitionTable  # noqa: E402

SEEDS = 5
BUDGETS = (2, 3, 5, 8, 12, 20)


def r1_truth() -> TransitionTable:
    t = load_robot(ROOT / "robots" / "paper-r1.toml").transitions
    rng = np.random.default_rng(15)
    return TransitionTable(t.levels, t.src, t.dst, t.reward * 4.0 * (1 + 0.1 * rng.uniform(-1, 1, len(t.src))))


def synthetic(limbs: int, seed: int) -> TransitionTable:
    rng = np.random.default_rng(seed)
    n = 2 ** limbs
    while True:
        src, dst = [], []
        for a in range(n):
            for b in range(n):
                if a != b and bin(a ^ b).count("1") <= 2 and rng.random() > 0.15:
                    src.append(a)
                    dst.append(b)
        comp = strongly_connected_components(n, list(zip(src, dst)))
        if len(set(comp)) == 1:
            return TransitionTable.from_edges((2,) * limbs, src, dst, rng.normal(0, 4.0, len(src)))


class Sampler:
    def __init__(self, truth: TransitionTable, seed: int):
        rng = np.random.default_rng(1000 + seed)
        self.truth = truth
        self.sigma = rng.uniform(0.3, 2.5, truth.n_transitions)
        self.duration = rng.uniform(0.6, 1.2, truth.n_transitions)
        self.table = TransitionTable(truth.levels, truth.src, truth.dst, truth.reward, self.duration)
        limbs = len(truth.levels)
        self.limits = PieceLimits(max_transitions=23, max_on_s=3.0 * limbs, rest_s=1.5,
                                  coil_of_limb=tuple(range(limbs)), max_coil_on_s=2.4)
        self.rng = rng
        self.trials: list[Trial] = []
        self.time_s = 0.0

    def walk(self, states) -> None:
        t = self.truth
        pieces = split(self.table, states, self.limits)
        for p in pieces:
            for a, b in p.transitions:
                e = t.lookup(a, b)
                self.trials.append(Trial(t.label(a), t.label(b), 0, 0,
                                         float(t.reward[e] + self.rng.normal(0, self.sigma[e]))))
                self.time_s += self.duration[e]
            self.time_s += p.rest_after_s
        self.time_s += self.limits.rest_s  # rest after each round

    def metrics(self) -> dict:
        acc = accuracy(self.truth, estimate(self.truth, self.trials))
        return {
            "transitions": len(self.trials),
            "time_s": self.time_s,
            "rmse_mm": acc.rmse_mm,
            "max_half_width_mm": acc.max_half_width_mm,
            "coverage": acc.coverage,
            "sign": acc.sign,
            "gait_ratio": acc.gait_ratio,
        }


def run_scheme(truth: TransitionTable, scheme: str, seed: int) -> list[dict]:
    s = Sampler(truth, seed)
    m = truth.n_transitions
    out = []
    rnd = 0
    if scheme == "adaptive":
        s.walk(exploration(truth, 2, seed=seed).tours[0].states)
        out.append(s.metrics())
    while len(s.trials) < BUDGETS[-1] * m:
        rnd += 1
        if scheme == "euler":
            tour = exploration(truth, 1, seed=seed * 1000 + rnd).tours[0]
        else:
            demand = adaptive_demand(estimate(truth, s.trials), 0.25)
            tour = exploration(truth, demand=demand, start=0, seed=seed * 1000 + rnd).tours[0]
        s.walk(tour.states)
        out.append(s.metrics())
    return out


def at_budget(runs: list[list[dict]], k: int, edges: list[int]) -> dict:
    rows = [next(r for r in run if r["transitions"] >= k * m) for run, m in zip(runs, edges)]
    return {k: float(np.mean([r[k] for r in rows])) for k in rows[0]}


def first_reaching(runs, key, ok) -> float:
    vals = []
    for run in runs:
        hit = next((r for r in run if ok(r[key])), None)
        vals.append(np.nan if hit is None else hit["transitions"])
    return float(np.nanmean(vals)) if not all(np.isnan(vals)) else float("nan")


def part1() -> list[dict]:
    robots = {"paper-r1-mm": lambda s: r1_truth(), "synth-8": lambda s: synthetic(3, 80 + s),
              "synth-16": lambda s: synthetic(4, 160 + s)}
    rows = []
    for name, make in robots.items():
        for scheme in ("euler", "adaptive"):
            runs, edges = [], []
            for seed in range(SEEDS):
                truth = make(seed)
                runs.append(run_scheme(truth, scheme, seed))
                edges.append(truth.n_transitions)
            for k in BUDGETS:
                row = {"robot": name, "states": make(0).n_states, "edges": float(np.mean(edges)), "scheme": scheme,
                       "budget_x": k}
                row.update(at_budget(runs, k, edges))
                rows.append(row)
            rows.append({"robot": name, "scheme": scheme, "summary": True,
                         "transitions_to_half_width_1mm": first_reaching(runs, "max_half_width_mm", lambda v: v <= 1.0),
                         "transitions_to_gait_95": first_reaching(runs, "gait_ratio", lambda v: v >= 0.95)})
    return rows


CLOSED_LOOP_ROBOTS = ("paper-r1", "paper-r3", "inchworm-3", "caterpillar-4")
#: seeds per robot: eight for the small ones (about a CPU-second each), three for the
#: 36-state caterpillar (about ten)
CLOSED_LOOP_SEEDS = {"caterpillar-4": (1, 2, 3)}
DEFAULT_SEEDS = tuple(range(1, 9))


def closed_loop_run(name: str, seed: int, repeats: int = 5) -> dict:
    """One proof run: learn ``name`` against its hidden truth (``proleg.learn.truth``) with
    R = ``repeats``; accuracy against the plant's effective truth and the truth file."""
    from proleg.learn.evaluate import accuracy, effective_truth
    from proleg.learn.measure import TrialLog
    from proleg.learn.simulated import explore_simulated
    from proleg.learn.truth import write_truth

    robot = load_robot(ROOT / "robots" / f"{name}.toml")
    with tempfile.TemporaryDirectory() as tmp:
        truth = load_robot(write_truth(robot, Path(tmp) / "truth.toml"))
        w, c = time.perf_counter(), time.process_time()
        with TrialLog(Path(tmp) / "trials.jsonl") as log:
            _added, sim = explore_simulated(robot, truth, log, repeats=repeats, seed=seed)
            trials = list(log.trials)
        wall, cpu = time.perf_counter() - w, time.process_time() - c
    t = robot.transitions
    est = estimate(t, trials)
    eff = effective_truth(t, np.nan_to_num(truth.transitions.dense()[0]), trials, sim.plant.transitions)
    a_eff, a_file = accuracy(eff, est), accuracy(truth.transitions, est)
    return {
        "robot": name, "seed": seed, "repeats": repeats, "states": t.n_states, "transitions": t.n_transitions,
        "trials": len(trials), "virtual_s": round(sim.time_s, 1), "wall_s": round(wall, 2), "cpu_s": round(cpu, 2),
        "speedup": round(sim.time_s / max(wall, 1e-9), 1),
        "sign": a_eff.sign, "coverage": a_eff.coverage, "gait_ratio": a_eff.gait_ratio, "rmse_mm": a_eff.rmse_mm,
        "sign_vs_truth_file": a_file.sign, "coverage_vs_truth_file": a_file.coverage,
        "gait_ratio_vs_truth_file": a_file.gait_ratio,
        "entries_differing_from_file": int(np.sum(np.abs(eff.reward - truth.transitions.reward) > 0.5)),
        "claims_hold": bool(a_eff.sign == 1.0 and a_eff.coverage >= 0.9 and a_eff.gait_ratio >= 0.95),
    }


def part2() -> list[dict]:
    return [closed_loop_run(name, seed) for name in CLOSED_LOOP_ROBOTS
            for seed in CLOSED_LOOP_SEEDS.get(name, DEFAULT_SEEDS)]


def main() -> int:
    t0 = time.perf_counter()
    rows = part1()
    print("\nPart 1: sampling from the truth with noise (pure Python), mean of", SEEDS, "seeds")
    print(f"{'robot':12} {'scheme':9} {'budget':>6} {'trials':>7} {'time s':>8} {'RMSE mm':>8} {'max hw':>7} "
          f"{'cover':>6} {'sign':>5} {'gait %':>7}")
    for r in rows:
        if r.get("summary"):
            continue
        print(f"{r['robot']:12} {r['scheme']:9} {r['budget_x']:>5}x {r['transitions']:7.0f} {r['time_s']:8.0f} "
              f"{r['rmse_mm']:8.3f} {r['max_half_width_mm']:7.2f} {r['coverage']:6.2f} {r['sign']:5.2f} "
              f"{100 * r['gait_ratio']:7.1f}")
    print("\ntransitions needed (mean of seeds; nan = not within", BUDGETS[-1], "x edges)")
    for r in rows:
        if r.get("summary"):
            print(f"  {r['robot']:12} {r['scheme']:9} widest 95% half-width <= 1 mm: "
                  f"{r['transitions_to_half_width_1mm']:7.0f}   gait >= 95%: {r['transitions_to_gait_95']:6.0f}")
    cl = part2()
    print("\nPart 2: closed loop (host-sim firmware + table plant, hidden truth ±10 %, noise 0.5 mm), R = 5;")
    print("accuracy against what the plant did per firmware transition (learn.evaluate.effective_truth)")
    print(f"{'robot':14} {'seed':>4} {'states':>6} {'trans':>5} {'trials':>6} {'virt s':>7} {'cpu s':>6} "
          f"{'sign':>5} {'cover':>6} {'gait %':>7} {'claims':>6}")
    for r in cl:
        print(f"{r['robot']:14} {r['seed']:>4} {r['states']:>6} {r['transitions']:>5} {r['trials']:>6} "
              f"{r['virtual_s']:>7.0f} {r['cpu_s']:>6.1f} {r['sign']:>5.2f} {r['coverage']:>6.2f} "
              f"{100 * r['gait_ratio']:>7.1f} {'hold' if r['claims_hold'] else 'FAIL':>6}")
    result = {
        "benchmark": "learn",
        "machine": {"python": platform.python_version(), "platform": platform.platform(), "cpus": os.cpu_count()},
        "seeds": SEEDS, "budgets_x_edges": BUDGETS, "sampling": rows, "closed_loop": cl,
        "closed_loop_claims_hold": {name: f"{sum(r['claims_hold'] for r in cl if r['robot'] == name)}/"
                                          f"{sum(r['robot'] == name for r in cl)} seeds"
                                    for name in CLOSED_LOOP_ROBOTS},
        "bench_wall_s": round(time.perf_counter() - t0, 1),
    }
    out = ROOT / "bench" / "results" / "learn.json"
    out.write_text(json.dumps(result, indent=2, default=float) + "\n")
    print(f"\nwrote {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
