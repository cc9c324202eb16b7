"""Planar gait benchmark: the exact constrained search beside a plain enumeration.

Question (the TerreSoRo synthesiser's, Mahendran et al. IROS 2023): the best simple cycle of
at most K transitions for heading 0°, score per transition Δx − 0.25·(σ²x + σ²y) −
0.25·(π/180)²·σ²θ − 0.5 (every cycle scores below zero: the best is still wanted), rotation
capped at 5° per pass; plus a rotation gait (clockwise, translation capped at one mean step).

Tables (fixed seeds, every transition allowed): "dense16" = 4 binary limbs, 16 states, 240
transitions; "dense64" = 6 binary limbs, 64 states, 4,032 transitions. Per transition Δx, Δy
~ N(0, 0.5) cm, Δθ ~ N(0, 8)°, variances uniform in 0..0.2 cm² / 0..20 deg² (the spread of
the published TerreSoRo primitives).

  exact — optimal_planar_gaits(..., simple_cycles=True, rotation_cap_deg=5): the branch and
          bound of simple_search.py (simple-path bounds, best-so-far pruning);
  before — the same question through the threshold search that answered it before
          (constrained.py, ``levels=True``), run where it finishes in reasonable time;
  plain — every simple cycle of 2..K transitions listed (numpy, no pruning), scored, the best
          within the cap kept; stopped after PLAIN_LIMIT_S (then "> limit", with how many
          cycles it had listed). Where both finish, their values must agree.
Time = best of 3 runs when a run takes < 3 s, else one. Prints a table and writes
bench/results/planar.json with machine information.
Target: exact on 16 states with every simple cycle (K = 16) ≤ 1 s.
"""

from __future__ import annotations

import json
import math
import platform
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "host" / "src"))

import numpy as np  # noqa: E402

from proleg.gait.planar import PlanarObjective, default_translation_cap, optimal_planar_gaits, rotation_scores  # noqa: E402
from proleg.gait.planar import planar_scores  # noqa: E402
from proleg.transitions import PlanarRewards, TransitionTable  # noqa: E402

RESULTS = ROOT / "bench" / "results" / "planar.json"
PLAIN_LIMIT_S = 30.0
WEIGHTS = (0.25, 0.25, 0.25 * (math.pi / 180) ** 2)
COST = 0.5
CAP = 5.0

# (table, K, question, target s, run "before")
CASES = [
    ("dense16", 4, "heading", None, True), ("dense16", 6, "heading", None, True), ("dense16", 8, "heading", None, True),
    ("dense16", 16, "heading", 1.0, True), ("dense16", 4, "rot-cw", None, True), ("dense16", 6, "rot-cw", None, True),
    ("dense16", 16, "rot-cw", None, False),
    ("dense64", 3, "heading", None, True), ("dense64", 4, "heading", None, True), ("dense64", 5, "heading", None, True),
    ("dense64", 8, "heading", None, False), ("dense64", 16, "heading", None, False),
]


def table(name: str) -> TransitionTable:
    limbs = {"dense16": 4, "dense64": 6}[name]
    n = 1 << limbs
    rng = np.random.default_rng(17 + limbs)
    allowed = ~np.eye(n, dtype=bool)
    src, dst = np.nonzero(allowed)
    m = len(src)
    planar = PlanarRewards(dy=rng.normal(0, 0.5, m), dtheta_deg=rng.normal(0, 8, m), var_dx=rng.uniform(0, 0.2, m),
                           var_dy=rng.uniform(0, 0.2, m), var_dtheta_deg=rng.uniform(0, 20, m))
    return TransitionTable.from_edges((2,) * limbs, src, dst, rng.normal(0, 0.5, m), None, planar)


def exact(t: TransitionTable, K: int, question: str, levels: bool = False) -> float | None:
    import functools

    import proleg.gait.constrained as constrained
    import proleg.gait.planar as planar

    planar.best_constrained = functools.partial(constrained.best_constrained, levels=levels)
    try:
        return _exact(t, K, question)
    finally:
        planar.best_constrained = constrained.best_constrained


def _exact(t: TransitionTable, K: int, question: str) -> float | None:
    if question == "heading":
        r = optimal_planar_gaits(t, PlanarObjective(0.0, WEIGHTS, COST), "total", K, CAP, simple_cycles=True)
    else:
        r = optimal_planar_gaits(t, PlanarObjective(0.0, WEIGHTS, COST), "total", K, simple_cycles=True, rotate="cw")
    return r.value


def plain(t: TransitionTable, K: int, question: str) -> tuple[float | None, int, bool]:
    """(best value, cycles listed, finished) by listing every simple cycle, no pruning."""
    n = t.n_states
    objective = PlanarObjective(0.0, WEIGHTS, COST)
    score = np.full((n, n), -np.inf)
    score[t.src, t.dst] = planar_scores(t, objective) if question == "heading" else rotation_scores(t, objective, "cw")
    th = np.zeros((n, n))
    th[t.src, t.dst] = t.planar.dtheta_deg
    dx, dy = np.zeros((n, n)), np.zeros((n, n))
    dx[t.src, t.dst], dy[t.src, t.dst] = t.reward, t.planar.dy
    tcap = default_translation_cap(t)
    best, listed, t0 = None, 0, time.perf_counter()
    for start in range(n):
        frontier = np.array([[start]])
        for L in range(2, min(K, n) + 1):
            nxt = np.arange(start + 1, n)
            grown = np.hstack([np.repeat(frontier, len(nxt), axis=0), np.tile(nxt, len(frontier))[:, None]])
            grown = grown[~(grown[:, :-1] == grown[:, -1:]).any(axis=1)]
            cyc = np.hstack([grown, grown[:, :1]])
            a, b = cyc[:, :-1], cyc[:, 1:]
            s, turn = score[a, b].sum(axis=1), th[a, b].sum(axis=1)
            ok = np.abs(turn) <= CAP if question == "heading" else np.hypot(dx[a, b].sum(1), dy[a, b].sum(1)) <= tcap
            listed += len(grown)
            if ok.any():
                v = float(s[ok].max())
                best = v if best is None else max(best, v)
            frontier = grown
            if time.perf_counter() - t0 > PLAIN_LIMIT_S or len(frontier) * n > 20_000_000:
                return best, listed, False
    return best, listed, True


def timed(fn, *args):
    runs, out = [], None
    for _ in range(3):
        t0 = time.perf_counter()
        out = fn(*args)
        runs.append(time.perf_counter() - t0)
        if runs[-1] > 3.0:
            break
    return min(runs), out


def machine() -> dict:
    cpu = platform.processor()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    import os

    return {"platform": platform.platform(), "python": platform.python_version(), "numpy": np.__version__,
            "cpu": cpu, "load_average": os.getloadavg()[0]}


def main() -> int:
    rows = []
    print(f"{'table':<8} {'K':>3} {'question':<8} {'exact s':>9} {'before s':>9} {'value':>10}  {'plain s':>9} "
          f"{'listed':>12}  target")
    for name, K, question, target, run_before in CASES:
        t = table(name)
        te, ve = timed(exact, t, K, question)
        tb, vb = timed(exact, t, K, question, True) if run_before else (None, None)
        if run_before and ((vb is None) != (ve is None) or (ve is not None and abs(ve - vb) > 1e-9)):
            print(f"MISMATCH {name} K={K} {question}: exact {ve} before {vb}", file=sys.stderr)
            return 1
        tp, (vp, listed, done) = timed(plain, t, K, question)
        if done and (ve is None) != (vp is None) or (done and ve is not None and abs(ve - vp) > 1e-9):
            print(f"MISMATCH {name} K={K} {question}: exact {ve} plain {vp}", file=sys.stderr)
            return 1
        plain_s = f"{tp:9.3f}" if done else f"> {tp:6.1f}"
        mark = "" if target is None else ("ok" if te <= target else f"OVER {target} s")
        before_s = f"{tb:9.3f}" if tb is not None else f"{'-':>9}"
        print(f"{name:<8} {K:>3} {question:<8} {te:9.3f} {before_s} {ve if ve is not None else float('nan'):10.4f}  {plain_s:>9}"
              f" {listed:12,d}  {mark}", flush=True)
        rows.append({"table": name, "max_transitions": K, "question": question, "exact_s": te, "before_s": tb, "value": ve,
                     "plain_s": tp, "plain_finished": done, "plain_cycles_listed": listed, "target_s": target})
    RESULTS.write_text(json.dumps({"machine": machine(), "plain_limit_s": PLAIN_LIMIT_S, "cases": rows}, indent=1) + "\n")
    print(f"written {RESULTS}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
