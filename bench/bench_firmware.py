"""Firmware benchmark.

1. Size: flash (text + data) and static RAM (data + bss) of every example robot's
   firmware (robots/*.toml) on every board, each built by ``proleg.firmware.build`` exactly
   as ``proleg build`` does (a robot a board cannot host is listed with the build's reason).
   Targets (the paper's R1): arduino-nano ≤ 14 KB (14,336 B) flash (issue 11: with the
   non-blocking TWI, watchdog, clock and overrun handling) and ≤ 1 KB (1,024 B) static
   RAM; bluepill-f103 ≤ 16 KB (16,384 B) flash.
2. Control-tick cost on the host-sim build (R1 walking +x in closed loop for 20 simulated
   s): wall time per tick inside the firmware (two MPU-6050 reads over the simulated I2C,
   ψ classify, sequencer, SMA safety, telemetry at 50 Hz) and per tick of the whole loop.
   Not an MCU timing: the MCUs' tick budgets are bench/bench_mcu.py's (emulated MCUs).
3. Host decode rate of TELEMETRY frames through ``proleg.protocol.FrameDecoder``
   (bench_protocol.decode_rate: 200,000 frames in 4 KiB reads, best of 3).
   Target ≥ 100,000 frames/s.

Prints a table and writes bench/results/firmware.json (machine information and the
inputs' hashes; no timestamps). Exit status 1 if a target is missed.
"""

from __future__ import annotations

import hashlib
import json
import platform
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "host" / "src"))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_protocol import decode_rate  # noqa: E402

from proleg.errors import ProlegError  # noqa: E402
from proleg.firmware.boards import load_board  # noqa: E402
from proleg.firmware.build import build  # noqa: E402
from proleg.protocol import Message, encode  # noqa: E402
from proleg.protocol.definition import Direction  # noqa: E402
from proleg.robot import load_robot  # noqa: E402
from proleg.sim.closed_loop import SimulatedRobot  # noqa: E402

RESULTS = ROOT / "bench" / "results" / "firmware.json"
ROBOTS = sorted(p.stem for p in (ROOT / "robots").glob("*.toml"))
BOARDS = ["arduino-nano", "bluepill-f103", "host-sim"]
# (robot file stem, board) -> (flash target B, static RAM target B); None = no target
TARGETS = {
    ("paper-r1", "arduino-nano"): (14336, 1024),
    ("paper-r1", "bluepill-f103"): (16384, None),
}
DECODE_TARGET = 100_000
LOOP_S = 20.0  # closed-loop tick measurement, simulated seconds


def sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def tree_sha256(root: Path) -> str:
    h = hashlib.sha256()
    for p in sorted(root.rglob("*")):
        if p.is_file():
            h.update(str(p.relative_to(root)).encode() + b"\0" + p.read_bytes() + b"\0")
    return h.hexdigest()


def first_line(cmd: list[str]) -> str | None:
    if shutil.which(cmd[0]) is None:
        return None
    out = subprocess.run(cmd, capture_output=True, text=True).stdout
    return out.splitlines()[0].strip() if out else None


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

    return {
        "platform": platform.platform(),
        "python": platform.python_version(),
        "cpu": cpu,
        "cpu_count": os.cpu_count(),
        "cc": first_line(["cc", "--version"]),
        "avr-gcc": first_line(["avr-gcc", "--version"]),
        "arm-none-eabi-gcc": first_line(["arm-none-eabi-gcc", "--version"]),
    }


def inputs() -> dict:
    git = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "HEAD"], capture_output=True, text=True)
    return {
        "git_head": git.stdout.strip() or None,
        "firmware_templates_sha256": tree_sha256(ROOT / "firmware_templates"),
        "robots": {r: sha256(ROOT / "robots" / f"{r}.toml") for r in ROBOTS},
        "boards": {b: sha256(ROOT / "boards" / f"{b}.toml") for b in BOARDS},
        "closed_loop_simulated_s": LOOP_S,
    }


def sizes(tmp: Path) -> tuple[list[dict], Path | None]:
    rows = []
    r1_sim = None
    for rname in ROBOTS:
        robot = load_robot(ROOT / "robots" / f"{rname}.toml")
        for bname in BOARDS:
            board = load_board(bname)
            row: dict = {"robot": rname, "board": bname}
            t0 = time.perf_counter()
            try:
                res = build(robot, board, tmp / f"{rname}-{bname}")
            except ProlegError as e:
                row.update(built=False, error=str(e).splitlines()[0])
                rows.append(row)
                continue
            row.update(built=True, flash_bytes=res.flash_used, ram_bytes=res.ram_used,
                       board_flash_bytes=board.flash_bytes, board_ram_bytes=board.ram_bytes,
                       build_s=round(time.perf_counter() - t0, 2))
            ft, rt = TARGETS.get((rname, bname), (None, None))
            row["flash_target_bytes"], row["ram_target_bytes"] = ft, rt
            if ft is not None or rt is not None:
                row["pass"] = (ft is None or res.flash_used <= ft) and (rt is None or res.ram_used <= rt)
            if (rname, bname) == ("paper-r1", "host-sim"):
                r1_sim = res.artifact
            rows.append(row)
    return rows, r1_sim


def tick_cost(lib: Path) -> dict:
    """R1 walking its +x gait in closed loop; the time spent inside the firmware's ticks
    (``SimBoard.run_ticks``) is timed apart from the plant and the Python glue."""
    robot = load_robot(ROOT / "robots" / "paper-r1.toml")
    sim = SimulatedRobot(robot, library=lib)
    board = sim.board
    inner = board.run_ticks
    fw = {"s": 0.0, "ticks": 0}

    def timed_run_ticks(n: int) -> None:
        t = time.perf_counter()
        inner(n)
        fw["s"] += time.perf_counter() - t
        fw["ticks"] += n

    board.run_ticks = timed_run_ticks  # type: ignore[method-assign]
    sim.advance(0.2)  # the IMUs read: the firmware refuses START before it knows the robot's state
    sim.write(encode(Message.new("START", token=1, gait=0, direction=int(Direction.PLUS_X))))
    sim.advance(1.0)
    sim.read()
    fw["s"], fw["ticks"] = 0.0, 0
    x0 = sim.plant.displacement_mm
    t0 = time.perf_counter()
    for _ in range(int(LOOP_S / 0.1)):
        sim.advance(0.1)
        sim.read()
    wall = time.perf_counter() - t0
    if sim.plant.displacement_mm - x0 <= 0.0:
        raise SystemExit(f"bench_firmware: R1 did not walk +x in {LOOP_S:.0f} s: the tick timed is not a walking one")
    ticks = round(LOOP_S * 1e6 / board.tick_us)
    assert fw["ticks"] == ticks, (fw, ticks)
    return {
        "tick_hz": robot.control.tick_hz,
        "ticks": ticks,
        "firmware_us_per_tick": fw["s"] / ticks * 1e6,
        "closed_loop_us_per_tick": wall / ticks * 1e6,
        "closed_loop_sim_s_per_wall_s": LOOP_S / wall,
        "plant_displacement_mm": sim.plant.displacement_mm - x0,
        "note": "host CPU, host-sim build (cc -O2): firmware tick incl. the simulated I2C/MPU-6050 models; "
                "not MCU cycles",
    }


def main() -> int:
    t_start = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="proleg-bench-fw-") as tmp:
        rows, r1_sim = sizes(Path(tmp))
        ticks = tick_cost(r1_sim) if r1_sim else None
    dec = decode_rate(2, 2)
    dec["target_frames_per_s"] = DECODE_TARGET
    dec["pass"] = dec["frames_per_s"] >= DECODE_TARGET

    # -- table ---------------------------------------------------------------------------
    print(f"{'robot':<22} {'board':<14} {'flash B':>8} {'/ board':>8} {'RAM B':>7} {'/ board':>8}  target (flash / RAM)  result")
    for r in rows:
        if not r["built"]:
            print(f"{r['robot']:<22} {r['board']:<14}  BUILD FAILED: {r['error']}")
            continue
        lim_f = f"{r['board_flash_bytes']:,}" if r["board_flash_bytes"] else "-"
        lim_r = f"{r['board_ram_bytes']:,}" if r["board_ram_bytes"] else "-"
        tgt, res = "", ""
        if "pass" in r:
            ft, rt = r["flash_target_bytes"], r["ram_target_bytes"]
            tgt = f"≤ {ft:,}" + (f" / ≤ {rt:,}" if rt else "")
            res = "PASS" if r["pass"] else "FAIL"
        print(f"{r['robot']:<22} {r['board']:<14} {r['flash_bytes']:>8,} {lim_f:>8} {r['ram_bytes']:>7,} {lim_r:>8}  {tgt:<20} {res}")
    print("(host-sim: flash = code+data of libfirmware.so, RAM = data+bss incl. the simulated IMU/UART models)")
    if ticks:
        print(f"control tick, R1 host-sim, firmware part : {ticks['firmware_us_per_tick']:.2f} µs/tick "
              f"(walking +x, {ticks['plant_displacement_mm']:.1f} mm in {LOOP_S:.0f} s)")
        print(f"control tick, R1 host-sim, closed loop   : {ticks['closed_loop_us_per_tick']:.2f} µs/tick "
              f"({ticks['closed_loop_sim_s_per_wall_s']:.0f}× real time at {ticks['tick_hz']} Hz)")
    print(f"TELEMETRY decode (2 limbs / 2 ch)        : {dec['frames_per_s']:,.0f} frames/s "
          f"(target ≥ {DECODE_TARGET:,}: {'PASS' if dec['pass'] else 'FAIL'})")

    target_rows = [r for r in rows if "pass" in r]
    ok = all(r["built"] for r in rows) and all(r["pass"] for r in target_rows) and len(target_rows) == len(TARGETS)
    ok = ok and dec["pass"]
    results = {
        "machine": machine(),
        "inputs": inputs(),
        "sizes": rows,
        "tick_cost_r1_host_sim": ticks,
        "telemetry_decode_2x2": dec,
        "all_targets_met": ok,
        "bench_seconds": round(time.perf_counter() - t_start, 1),
    }
    RESULTS.parent.mkdir(parents=True, exist_ok=True)
    RESULTS.write_text(json.dumps(results, indent=1) + "\n")
    print(f"all targets {'met' if ok else 'NOT met'}; wrote {RESULTS.relative_to(ROOT)} "
          f"in {results['bench_seconds']} s")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
