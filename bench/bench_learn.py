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

Part 2 — closed loop: ``learn.runner.explore_simulated`` (host-sim firmware + table plant,
truth = the robot's matrix × 4 mm ±10 %, noise 0.5 mm per plant transition) with R = 5 on
paper-r1 and paper-r3; virtual and wall time, and the accuracy against the truth file and
against the plant's effective truth (a transition that changes both limbs passes through an
intermediate state in the table plant, whose entries then add up).

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

from proleg.gait import optimal_gaits  # noqa: E402
from proleg.gait.evaluate import evaluate_sequence  # noqa: E402
from proleg.learn.estimate import estimate  # noqa: E402
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


def rate_ratio(truth: TransitionTable, learned_reward: np.ndarray) -> float:
    best = optimal_gaits(truth, "rate").value
    lt = TransitionTable(truth.levels, truth.src, truth.dst, np.nan_to_num(learned_reward))
    res = optimal_gaits(lt, "rate")
    if not res.gaits:
        return 0.0
    g = res.gaits[0].states
    walk = list(g) + ([] if g[-1] == g[0] else [g[0]])
    return float(evaluate_sequence(truth, walk).rate / best)


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
        t = self.truth
        est = estimate(t, self.trials)
        mean = est.dx.mean
        hw = est.dx.half_width
        moving = np.abs(t.reward) > 1.0
        return {
            "transitions": len(self.trials),
            "time_s": self.time_s,
            "rmse_mm": float(np.sqrt(np.nanmean((mean - t.reward) ** 2))),
            "max_half_width_mm": float(np.nanmax(hw)) if np.isfinite(hw).any() else float("inf"),
            "coverage": float(np.mean(np.abs(mean - t.reward) <= hw)),
            "sign": float(np.mean(np.sign(mean[moving]) == np.sign(t.reward[moving]))),
            "gait_ratio": rate_ratio(t, mean),
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


def part2() -> list[dict]:
    from proleg.learn.measure import TrialLog
    from proleg.learn.runner import explore_simulated

    out = []
    for name in ("paper-r1", "paper-r3"):
        path = ROOT / "robots" / f"{name}.toml"
        robot = load_robot(path)
        rng = np.random.default_rng(15)
        reward, allowed = robot.transitions.dense()
        mm = reward * 4.0 * (1 + 0.1 * rng.uniform(-1, 1, reward.shape))
        rows = ",\n".join("  [" + ", ".join(f"{v:.3f}" if allowed[a, b] or a == b else '"x"' for b, v in enumerate(row)) + "]"
                          for a, row in enumerate(mm))
        text = path.read_text().replace('units = "steps"', 'units = "mm"')
        i = text.index("matrix = [")
        j = text.index("\n]\n", i) + 2
        text = text[:i] + f"matrix = [\n{rows},\n]" + text[j:] + "\n[plant]\nstep_mm = 1.0\nnoise_mm = 0.5\n"
        with tempfile.TemporaryDirectory() as tmp:
            tp = Path(tmp) / "truth.toml"
            tp.write_text(text)
            truth = load_robot(tp)
            w = time.perf_counter()
            with TrialLog(Path(tmp) / "trials.jsonl") as log:
                _added, sim = explore_simulated(robot, truth, log, repeats=5, seed=3)
                trials = list(log.trials)
            wall = time.perf_counter() - w
        t = robot.transitions
        est = estimate(t, trials)
        tv = truth.transitions.reward
        mmx = np.nan_to_num(truth.transitions.dense()[0])
        plant = sim.plant.transitions
        sums = [[] for _ in range(t.n_transitions)]
        for tr in trials:
            e = t.lookup(t.index(tr.src), t.index(tr.dst))
            sums[e].append(sum(mmx[p.src, p.dst] for p in plant if tr.t_start + 0.05 < p.t_s <= tr.t_end + 0.05))
        eff = np.array([np.mean(s) for s in sums])
        moving = np.abs(tv) > 1.0
        eff_table = TransitionTable(t.levels, t.src, t.dst, eff)
        out.append({
            "robot": name, "repeats": 5, "trials": len(trials), "virtual_s": round(sim.time_s, 1),
            "wall_s": round(wall, 2), "speedup": round(sim.time_s / wall, 1),
            "sign_vs_truth_file": float(np.mean(np.sign(est.dx.mean[moving]) == np.sign(tv[moving]))),
            "coverage_vs_truth_file": float(np.mean(np.abs(est.dx.mean - tv) <= est.dx.half_width)),
            "coverage_vs_effective": float(np.mean(np.abs(est.dx.mean - eff) <= est.dx.half_width)),
            "gait_ratio_effective": rate_ratio(eff_table, est.dx.mean),
            "two_limb_entries_differ": int(np.sum(np.abs(eff - tv) > 0.5)),
        })
    return out


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
    print("\nPart 2: closed loop (host-sim firmware + table plant), R = 5")
    for r in cl:
        print("  " + ", ".join(f"{k}={v}" for k, v in r.items()))
    result = {
        "benchmark": "learn",
        "machine": {"python": platform.python_version(), "platform": platform.platform(), "cpus": os.cpu_count()},
        "seeds": SEEDS, "budgets_x_edges": BUDGETS, "sampling": rows, "closed_loop": cl,
        "bench_wall_s": round(time.perf_counter() - t0, 1),
    }
    out = ROOT / "bench" / "results" / "learn.json"
    out.write_text(json.dumps(result, indent=2, default=float) + "\n")
    print(f"\nwrote {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
