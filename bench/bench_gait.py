"""Gait engine benchmark.

Graph families (2^N states, fixed seeds):
  hypercube N — a transition changes exactly one limb (both directions allowed): N·2^N edges;
  dense N     — every transition allowed: 2^N·(2^N − 1) edges.
Rewards are mostly antisymmetric integers: T[a][b] = s(a,b)·B{a,b} + e(a,b) with B uniform in
−1000..1000 per unordered pair, s = ±1 by direction, e uniform in −10..10 per ordered pair;
"-small" cases use B in −3..3 and e in −1..1 instead (many equal walks: the tie-heavy case);
"-flat" cases give every transition reward 1 (every cycle ties: the listing is truncated).

Measured, each case in its own subprocess (so the peak RSS is that case's alone):
  rate   — optimal_gaits(table, "rate"): Howard + critical subgraph + every tie;
  howard — max_cycle_ratio alone;
  karp   — Karp's max cycle mean (O(n·m) time, O(n²) memory), where feasible;
  brute  — the brute-force oracle (all simple cycles / all closed walks), tiny N only;
  speed  — optimal_gaits(table, "speed") with durations uniform in 0.5..2 s (cycle ratio);
  total  — optimal_gaits(table, "total", max_transitions=6), every tie (totalK: bound K);
  plainK — a plain enumeration of every closed walk of at most K transitions (numpy, no
           pruning, stopped after PLAIN_LIMIT_S): the baseline for totalK;
  brute-total — the oracle for the same question.
Time = best of 3 runs (fewer when the runs so far took 3 s). Prints a table and writes
bench/results/gait.json with machine information.
Targets: rate dense 10 ≤ 0.3 s; rate hypercube 16 ≤ 1 s; total 64 states / 6 transitions
≤ 1 s; total 65,536 states / 4 transitions ≤ 1 s; total 16 states / 8 transitions with many
ties (flat: every walk ties, listing capped) ≤ 1 s; peak memory ≤ 1 GB for every case.
"""

from __future__ import annotations

import json
import os
import platform
import resource
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "host" / "src"))

import numpy as np  # noqa: E402

from proleg.transitions import TransitionTable  # noqa: E402

RESULTS = ROOT / "bench" / "results" / "gait.json"
PEAK_LIMIT_MB = 1024.0

# (family, N, algorithm, time target in s or None)
CASES: list[tuple[str, int, str, float | None]] = (
    [("hypercube", n, "rate", 1.0 if n == 16 else None) for n in (4, 6, 8, 10, 12, 14, 16)]
    + [("hypercube", n, "howard", None) for n in (10, 12, 14, 16)]
    + [("hypercube", n, "karp", None) for n in (4, 6, 8, 10, 12)]
    + [("hypercube", n, "brute", None) for n in (2, 3)]
    + [("dense", n, "rate", 0.3 if n == 10 else None) for n in (2, 4, 6, 8, 10)]
    + [("dense", n, "howard", None) for n in (8, 10)]
    + [("dense", n, "karp", None) for n in (2, 4, 6, 8)]
    + [("dense", n, "brute", None) for n in (2, 3)]
    + [("dense", 6, "total", 1.0), ("dense", 6, "total-small", 1.0), ("hypercube", 6, "total", None)]
    + [("dense", 3, "brute-total", None), ("hypercube", 16, "rate-small", None), ("dense", 8, "rate-small", None)]
    + [("hypercube", 16, "rate-flat", None), ("hypercube", 16, "speed", None)]
    + [("hypercube", n, "total2", None) for n in (12, 14, 16)] + [("hypercube", 16, "total4", 1.0)]
    + [("hypercube", 16, "total4-small", None), ("dense", 4, "total8-flat", 1.0), ("dense", 4, "total8-small", 1.0)]
    + [("hypercube", 12, "plain2", None), ("hypercube", 16, "plain2", None), ("hypercube", 16, "plain4", None)]
    + [("dense", 4, "plain8-flat", None), ("dense", 4, "plain6-flat", None)]
)
#: The plain enumeration gives up after this long (its row then says "> limit").
PLAIN_LIMIT_S = 60.0


def plain_total(table: TransitionTable, max_transitions: int, limit_s: float = PLAIN_LIMIT_S) -> float | None:
    """The best closed walk of at most K transitions by listing every walk from every start
    over states >= start, level by level in blocks (no bounds): the baseline. Returns
    None when it runs out of time (NaN: no closed walk)."""
    n, src, dst, w = table.n_states, table.src, table.dst, table.reward
    ptr = np.searchsorted(src, np.arange(n + 1))
    best = -np.inf
    started = time.perf_counter()
    stack = [(np.arange(n), np.arange(n), np.zeros(n), 0)]
    while stack:
        if time.perf_counter() - started > limit_s:
            return None
        start, cur, rew, depth = stack.pop()
        if len(cur) > 1 << 16:
            stack.append((start[1 << 16:], cur[1 << 16:], rew[1 << 16:], depth))
            start, cur, rew = start[: 1 << 16], cur[: 1 << 16], rew[: 1 << 16]
        deg = ptr[cur + 1] - ptr[cur]
        rows = np.repeat(np.arange(len(cur)), deg)
        edge = ptr[cur][rows] + np.arange(len(rows)) - (np.cumsum(deg) - deg)[rows]
        nxt, nrew, nstart = dst[edge], rew[rows] + w[edge], start[rows]
        keep = nxt >= nstart
        closed = keep & (nxt == nstart)
        if closed.any():
            best = max(best, float(nrew[closed].max()))
        if depth + 1 < max_transitions:  # walks may pass their start again: keep those too
            stack.append((nstart[keep], nxt[keep], nrew[keep], depth + 1))
    return best if np.isfinite(best) else float("nan")


def rewards(src: np.ndarray, dst: np.ndarray, n: int, seed: int, base: int = 1000, noise: int = 10) -> np.ndarray:
    rng = np.random.default_rng(seed)
    lo, hi = np.minimum(src, dst), np.maximum(src, dst)
    pair = lo * n + hi
    uniq, inv = np.unique(pair, return_inverse=True)
    b = rng.integers(-base, base + 1, len(uniq))[inv]
    return (np.where(src < dst, b, -b) + rng.integers(-noise, noise + 1, len(src))).astype(np.float64)


def make_table(family: str, bits: int, variant: str = "", seed: int = 2024) -> TransitionTable:
    n = 1 << bits
    if family == "hypercube":
        src = np.repeat(np.arange(n, dtype=np.int64), bits)
        dst = src ^ (1 << np.tile(np.arange(bits, dtype=np.int64), n))
    else:
        src, dst = np.nonzero(~np.eye(n, dtype=bool))
    scale = (3, 1) if variant == "small" else (1000, 10)
    reward = rewards(src, dst, n, seed + bits, *scale)
    if variant == "flat":
        reward = np.ones(len(src))
    duration = np.random.default_rng(seed).uniform(0.5, 2.0, len(src))
    return TransitionTable.from_edges((2,) * bits, src, dst, reward, duration)


def run_case(family: str, bits: int, algorithm: str) -> dict:
    from proleg.gait import optimal_gaits
    from proleg.gait.bruteforce import brute_force_gaits, brute_force_max_cycle_mean
    from proleg.gait.howard import max_cycle_ratio
    from proleg.gait.karp import max_cycle_mean

    name = algorithm
    algorithm, _, variant = algorithm.partition("-")
    if algorithm == "brute" and variant == "total":
        algorithm, variant = "brute-total", ""
    bound = 6
    if algorithm[:5] in ("total", "plain") and algorithm[5:].isdigit():
        algorithm, bound = algorithm[:5], int(algorithm[5:])
    table = make_table(family, bits, variant)
    n, src, dst, w = table.n_states, table.src, table.dst, table.reward
    jobs = {
        "rate": lambda: optimal_gaits(table, "rate"),
        "speed": lambda: optimal_gaits(table, "speed"),
        "howard": lambda: max_cycle_ratio(n, src, dst, w),
        "karp": lambda: max_cycle_mean(n, src, dst, w),
        "brute": lambda: brute_force_max_cycle_mean(n, src, dst, w),
        "total": lambda: optimal_gaits(table, "total", max_transitions=bound),
        "plain": lambda: plain_total(table, bound),
        "brute-total": lambda: brute_force_gaits(table, "total", max_transitions=6),
    }
    times = []
    out = None
    while len(times) < 3 and sum(times) < 3.0 and not (algorithm == "plain" and out is None and times):
        t0 = time.perf_counter()
        out = jobs[algorithm]()
        times.append(time.perf_counter() - t0)
    truncated = None
    if algorithm in ("rate", "speed", "total"):
        value, ties, truncated = out.value, len(out.gaits), out.truncated
    elif algorithm == "howard":
        value, ties = out.value, None
    elif algorithm == "plain":
        value, ties = out, None
        if out is None:
            times = [float("inf")]
    elif algorithm == "brute-total":
        value, ties = out[0], len(out[1])
    else:
        value, ties = out, None
    return {
        "family": family,
        "N": bits,
        "states": n,
        "transitions": int(table.n_transitions),
        "algorithm": name,
        "time_s": min(times),
        "runs": len(times),
        "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0,
        "value": value,
        "ties": ties,
        "truncated": truncated,
    }


def machine() -> dict:
    cpu = platform.processor()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return {
        "platform": platform.platform(),
        "python": platform.python_version(),
        "numpy": np.__version__,
        "cpu": cpu,
        "cpu_count": os.cpu_count(),
        "date": time.strftime("%Y-%m-%d %H:%M:%S %z"),
    }


def main() -> int:
    rows = []
    started = time.perf_counter()
    header = f"{'family':<10} {'N':>2} {'states':>6} {'edges':>9} {'algorithm':<12} {'time s':>9} {'peak MB':>8} {'value':>10} {'ties':>6}  target"
    print(header)
    print("-" * len(header))
    for family, bits, algorithm, target in CASES:
        proc = subprocess.run(
            [sys.executable, __file__, "--case", family, str(bits), algorithm],
            capture_output=True,
            text=True,
        )
        if proc.returncode:
            print(proc.stderr, file=sys.stderr)
            return 1
        row = json.loads(proc.stdout)
        checks = []
        if target is not None:
            checks.append(row["time_s"] <= target)
        checks.append(row["peak_rss_mb"] <= PEAK_LIMIT_MB)
        row["target_s"] = target
        row["peak_limit_mb"] = PEAK_LIMIT_MB
        row["pass"] = all(checks)
        rows.append(row)
        tgt = (f"≤ {target:g} s, " if target is not None else "") + f"≤ {PEAK_LIMIT_MB:g} MB"
        value = "-" if row["value"] is None else f"{row['value']:.6g}"
        ties = "" if row["ties"] is None else str(row["ties"]) + ("+" if row["truncated"] else "")
        print(
            f"{family:<10} {bits:>2} {row['states']:>6} {row['transitions']:>9} {row['algorithm']:<12} "
            f"{row['time_s']:>9.4f} {row['peak_rss_mb']:>8.1f} {value:>10} {ties:>6}  "
            f"{tgt}: {'PASS' if row['pass'] else 'FAIL'}",
            flush=True,
        )
    total = time.perf_counter() - started
    RESULTS.parent.mkdir(parents=True, exist_ok=True)
    RESULTS.write_text(json.dumps({"machine": machine(), "bench_seconds": total, "cases": rows}, indent=1) + "\n")
    print(f"\n{sum(r['pass'] for r in rows)}/{len(rows)} cases pass; {total:.1f} s; wrote {RESULTS.relative_to(ROOT)}")
    return 0


if __name__ == "__main__":
    if len(sys.argv) == 5 and sys.argv[1] == "--case":
        print(json.dumps(run_case(sys.argv[2], int(sys.argv[3]), sys.argv[4])))
        sys.exit(0)
    sys.exit(main())
