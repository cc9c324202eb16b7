"""Build and run the libFuzzer harnesses of the firmware core (issue 12).

    python tests/fuzz/run_fuzz.py --seconds 3                 # CI: a short run of each
    python tests/fuzz/run_fuzz.py --seconds 300 --json bench/results/fuzz.json --coverage

Harnesses (clang -fsanitize=fuzzer,address,undefined, Debian packages clang and
libclang-rt-14-dev): ``fuzz_proto`` (the link decoder: core/proto.c, core/cobs.c) and
``fuzz_app`` (the whole firmware on the host-sim HAL, the envelope checked after every
tick by envelope.h). Each starts from the checked-in seeds in tests/fuzz/corpus/<name>/;
new inputs go to a work directory (``--work``, default build/fuzz), never into the seeds.
The firmware is rendered for a small two-limb robot whose envelope is short (max_on 50 ms,
cool-down 20 ms, state timeout 200 ms, mean-duty window 400 ms) so that short inputs
reach every limit. ``--coverage`` replays the corpus through a clang source-coverage build
and reports line and branch coverage of the core files. Exit status 1 when a harness
finds a crash or an envelope violation (the reproducer is in the work directory).
"""

from __future__ import annotations

import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path
from types import SimpleNamespace

ROOT = Path(__file__).resolve().parents[2]
FUZZ = ROOT / "tests" / "fuzz"
CORE = ROOT / "firmware_templates" / "core"
SIM = ROOT / "firmware_templates" / "hal" / "sim"
LLVM_BIN = Path("/usr/lib/llvm-14/bin")

BOARD = {
    "name": "host-sim",
    "family": "sim",
    "pwm_channels": ["SIM0", "SIM1", "SIM2", "SIM3"],
    "i2c": {"hz": 400000, "imu_addresses": [0x68, 0x69]},
    "uart_baud": 115200,
    "clock_hz": 0,
}

ROBOT = {
    "robot": {"name": "fuzz-r1"},
    "limb": [
        {"name": "left", "psi_star_deg": [20.0], "hysteresis_deg": 2.0, "actuator": "a0"},
        {"name": "right", "psi_star_deg": [20.0], "hysteresis_deg": 2.0, "actuator": "a1"},
    ],
    "actuator": [{"name": "a0", "channel": 0}, {"name": "a1", "channel": 1}],
    "transitions": {"matrix": [[0, -1, 1, 0], [1, 0, 0, -1], [-1, 0, 0, 1], [0, 0, 0, 0]]},
    # the thermal budget's window short, so that a fuzz run reaches it (docs/safety.md)
    "safety": {"max_on_ms": 50, "min_cooldown_ms": 20, "max_duty": 0.8, "state_timeout_ms": 200,
               "duty_window_ms": 400, "max_mean_duty": 0.5, "on_limit_latch": 3},
    "control": {"tick_hz": 1000, "drive_duty": 0.6, "debounce_ticks": 3, "hold_ms": 10, "telemetry_hz": 50},
}

HARNESSES = {
    "fuzz_proto": ["proto.c", "cobs.c", "crc16.c", "gen:proto_gen.c"],
    "fuzz_app": ["*core", "*sim", "gen:proto_gen.c", "gen:gait_table.c"],
}


@dataclass
class Result:
    name: str
    seconds: float
    executions: int
    exec_per_s: int
    edges: int
    features: int
    corpus: int
    crashed: bool
    line_coverage: dict | None = None


def render(gen: Path) -> None:
    sys.path.insert(0, str(ROOT / "host" / "src"))
    from proleg.firmware.render import render_config
    from proleg.protocol.render import render_c
    from proleg.robot import robot_from_dict

    robot = robot_from_dict(ROBOT, Path("tests/fuzz/fuzz-r1.toml"))
    gaits = {"+x": [SimpleNamespace(states=(0, 2, 3, 1, 0)), SimpleNamespace(states=(0, 2, 0))], "-x": []}
    gen.mkdir(parents=True, exist_ok=True)
    for name, text in {**render_config(robot, gaits, BOARD), **render_c(2, 2)}.items():
        (gen / name).write_text(text)


def sources(spec: list[str], gen: Path) -> list[str]:
    out: list[Path] = []
    for s in spec:
        if s == "*core":
            out += sorted(p for p in CORE.glob("*.c") if p.name != "main.c"  # host-sim: no main loop
                          and not p.name.startswith("can"))  # the CAN link: CAN boards only
        elif s == "*sim":
            out += sorted(p for p in SIM.glob("*.c") if not p.name.startswith("can"))
        elif s.startswith("gen:"):
            out.append(gen / s[4:])
        else:
            out.append(CORE / s)
    return [str(p) for p in out]


def clang() -> str:
    cc = shutil.which("clang") or shutil.which("clang-14")
    if cc is None:
        raise SystemExit("clang is missing: install the Debian packages clang and libclang-rt-14-dev (make toolchains)")
    return cc


def build(name: str, gen: Path, out: Path, flags: list[str], extra: list[str] = ()) -> Path:
    exe = out / name
    cmd = [clang(), "-std=c99", "-g", "-O1", *flags, f"-I{CORE}", f"-I{SIM}", f"-I{gen}", f"-I{FUZZ}"]
    cmd += [str(FUZZ / f"{name}.c"), *extra, *sources(HARNESSES[name], gen), "-lm", "-o", str(exe)]
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        raise SystemExit(f"building {name} failed:\n{r.stderr}")
    return exe


def fuzz(name: str, exe: Path, work: Path, seconds: float) -> Result:
    corpus = work / "corpus" / name
    corpus.mkdir(parents=True, exist_ok=True)
    seeds = FUZZ / "corpus" / name.removeprefix("fuzz_")
    art = work / "artifacts" / name
    art.mkdir(parents=True, exist_ok=True)
    cmd = [str(exe), str(corpus), str(seeds), f"-max_total_time={max(1, round(seconds))}", "-print_final_stats=1",
           f"-artifact_prefix={art}/", "-max_len=4096", "-timeout=20", "-rss_limit_mb=2048"]
    r = subprocess.run(cmd, capture_output=True, text=True, env={**os.environ, "ASAN_OPTIONS": "detect_leaks=0"})
    log = r.stderr
    (work / f"{name}.log").write_text(log)

    def stat(key: str) -> int:
        m = re.findall(rf"{key}:\s*(\d+)", log)
        return int(m[-1]) if m else 0

    cov = re.findall(r"cov: (\d+) ft: (\d+)", log)
    edges, feats = (int(cov[-1][0]), int(cov[-1][1])) if cov else (0, 0)
    execs = stat("stat::number_of_executed_units")
    return Result(name, seconds, execs, stat("stat::average_exec_per_sec"), edges, feats,
                  len(list(corpus.iterdir())), r.returncode != 0)


def coverage(name: str, gen: Path, work: Path) -> dict:
    """Line and branch coverage of the core files from replaying the whole corpus."""
    (work / "cov").mkdir(parents=True, exist_ok=True)
    exe = build(name, gen, work / "cov", ["-fprofile-instr-generate", "-fcoverage-mapping"],
                [str(FUZZ / "replay_main.c")])
    raw = work / "cov" / f"{name}.profraw"
    files = [str(p) for d in (work / "corpus" / name, FUZZ / "corpus" / name.removeprefix("fuzz_")) for p in d.iterdir()]
    with tempfile.NamedTemporaryFile("w", delete=False) as lst:
        lst.write("\n".join(files))
    subprocess.run([str(exe), lst.name], env={**os.environ, "LLVM_PROFILE_FILE": str(raw)}, capture_output=True)
    os.unlink(lst.name)
    prof = work / "cov" / f"{name}.profdata"
    subprocess.run([str(LLVM_BIN / "llvm-profdata"), "merge", "-sparse", str(raw), "-o", str(prof)], check=True)
    r = subprocess.run([str(LLVM_BIN / "llvm-cov"), "export", "-summary-only", str(exe), f"-instr-profile={prof}"],
                       capture_output=True, text=True, check=True)
    out = {}
    for f in json.loads(r.stdout)["data"][0]["files"]:
        path = Path(f["filename"])
        if path.parent == CORE and path.suffix == ".c":
            s = f["summary"]
            out[path.name] = {"lines_pct": round(s["lines"]["percent"], 1),
                              "branches_pct": round(s["branches"]["percent"], 1)}
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=3.0, help="fuzzing time per harness")
    ap.add_argument("--only", choices=sorted(HARNESSES), action="append", help="run only these harnesses")
    ap.add_argument("--work", type=Path, default=ROOT / "build" / "fuzz")
    ap.add_argument("--json", type=Path, help="write the results here (bench/results/fuzz.json)")
    ap.add_argument("--coverage", action="store_true", help="measure line/branch coverage of the core")
    a = ap.parse_args(argv)
    gen = a.work / "gen"
    render(gen)
    results = []
    for name in a.only or sorted(HARNESSES):
        exe = build(name, gen, a.work, ["-fsanitize=fuzzer,address,undefined", "-fno-sanitize-recover=undefined"])
        res = fuzz(name, exe, a.work, a.seconds)
        if a.coverage:
            res.line_coverage = coverage(name, gen, a.work)
        results.append(res)
        status = "CRASH (see " + str(a.work / f"{name}.log") + ")" if res.crashed else "ok"
        print(f"{name:11s} {res.executions:>10,d} execs {res.exec_per_s:>7,d}/s  edges {res.edges:5d}  "
              f"features {res.features:6d}  corpus {res.corpus:5d}  {status}")
        for f, c in (res.line_coverage or {}).items():
            print(f"    {f:12s} lines {c['lines_pct']:5.1f} %  branches {c['branches_pct']:5.1f} %")
    if a.json:
        a.json.parent.mkdir(parents=True, exist_ok=True)
        a.json.write_text(json.dumps({"harnesses": [r.__dict__ for r in results]}, indent=2) + "\n")
    return 1 if any(r.crashed for r in results) else 0


if __name__ == "__main__":
    raise SystemExit(main())
