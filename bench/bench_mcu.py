"""MCU tick budget on the emulated arduino-nano (avr-emu: the exact firmware.elf on simavr).

For every robots/*.toml that builds for the Nano: the robot walks its +x gait 0 in
closed loop with the plant for RUN_S emulated seconds at its configured tick rate
(after 0.2 s of boot, not measured). Per control tick the harness counts CPU cycles
from the end of the tick wait to the start of the next one (busy), and the cycles the
I2C bus was owned meanwhile. Reported: busy mean / p99 / max (µs and fraction of the
period), ticks that overran the period, I2C per tick and its share of busy time, the
stack peak and what is left above static data, the firmware's clock against emulated
real time (TELEMETRY time_ms over the run), gait cycles, emulation speed (emulated s per
wall s, and per CPU s of the process: the wall figure includes the machine's other load)
and flash size. One extra row runs paper-r1 at tick_hz = 2000, a rate the build
accepts today, to show what an overrun does to the firmware's clock.

Target (issue 11): p99 ≤ 70 % and max ≤ 90 % of the tick period for every example
robot at its configured rate. Prints a table, writes bench/results/mcu.json (machine,
inputs' hashes; no timestamps). Exit status 1 if a target is missed.
"""

from __future__ import annotations

import dataclasses
import json
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "host" / "src"))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_firmware import machine, sha256, tree_sha256  # noqa: E402

from proleg.emu.avr import AvrEmuRobot, nano_build_dir  # noqa: E402
from proleg.emu.avr.budget import MAX_LIMIT, P99_LIMIT  # noqa: E402
from proleg.errors import BuildError  # noqa: E402
from proleg.robot import load_robot  # noqa: E402
from proleg.link.listeners import Listener  # noqa: E402
from proleg.report import SimSession  # noqa: E402

RESULTS = ROOT / "bench" / "results" / "mcu.json"
RUN_S = 10.0
BOOT_S = 0.2
SEED = 1


def measure(robot) -> dict:
    build = nano_build_dir(robot)
    manifest = json.loads((build / "proleg-build.json").read_text())
    sim = AvrEmuRobot(robot, build / "firmware.elf", seed=SEED)
    clock: list[tuple[float, int]] = []

    class Clock(Listener):
        def on_message(self, received) -> None:
            if received.message.name == "TELEMETRY":
                clock.append((received.time, received.message.time_ms))

    session = SimSession(sim, listeners=[Clock()])
    session.advance(BOOT_S)
    sim.board.clear_ticks()
    clock.clear()
    run = session.run_gait("+x", 0, RUN_S)
    budget = sim.board.tick_budget()
    ratio = None
    if len(clock) >= 2:
        (t0, ms0), (t1, ms1) = clock[0], clock[-1]
        ratio = (ms1 - ms0) / 1000 / (t1 - t0)
    return {
        "tick_hz": robot.control.tick_hz,
        **budget.as_dict(),
        "firmware_clock_ratio": None if ratio is None else round(ratio, 4),
        "gait_cycles": run.cycles,
        "mean_cycle_mm": run.mean_cycle_mm,
        "faults": [f.code for f in run.faults],
        "flash_used": manifest["flash_used"],
        "ram_used": manifest["ram_used"],
        "markers": sim.board.markers.how if sim.board.markers else "GPIOR0",
    }


def main() -> int:
    t_start = time.perf_counter()
    rows: dict[str, dict] = {}
    robots = sorted((ROOT / "robots").glob("*.toml"))
    cases = [(p.stem, load_robot(p)) for p in robots]
    r1 = load_robot(ROOT / "robots" / "paper-r1.toml")
    cases.append(("paper-r1@2000Hz", dataclasses.replace(r1, control=dataclasses.replace(r1.control, tick_hz=2000))))
    for name, robot in cases:
        try:
            rows[name] = measure(robot)
        except BuildError as e:
            rows[name] = {"skipped": f"does not build for arduino-nano: {e}"}
        print(f"  {name}: done", flush=True)

    head = ("robot", "tick", "busy mean/p99/max µs", "p99/max % of tick", "overruns", "I2C µs (share)",
            "stack peak/left B", "fw clock", "cycles", "speed", "target")
    table = [head]
    ok = True
    for name, r in rows.items():
        if "skipped" in r:
            table.append((name, "", r["skipped"], "", "", "", "", "", "", "", ""))
            continue
        configured = "@" not in name
        meets = r["meets_target"]
        ok &= meets or not configured
        b = r["tick_busy_us"]
        table.append((
            name,
            f"{r['tick_hz']} Hz",
            f"{b['mean']:.0f} / {b['p99']:.0f} / {b['max']:.0f}",
            f"{100 * r['busy_p99_fraction']:.0f} / {100 * r['busy_max_fraction']:.0f}",
            f"{r['overruns']:,}/{r['ticks']:,}",
            f"{r['i2c_us']['mean']:.0f} ({100 * r['i2c_us']['share_of_busy']:.0f} %)",
            f"{r['stack_peak_bytes']} / {r['stack_margin_bytes']}",
            f"{r['firmware_clock_ratio']:.3f}×" if r["firmware_clock_ratio"] else "-",
            str(r["gait_cycles"]),
            f"{r['emulation_speed']:.2f}× ({r['emulation_speed_cpu']:.2f}× cpu)",
            ("PASS" if meets else "FAIL") if configured else "(info)",
        ))
    w = [max(len(row[i]) for row in table) for i in range(len(head))]
    for row in table:
        print("  ".join(f"{c:<{w[i]}}" for i, c in enumerate(row)))
    print(f"target: busy p99 ≤ {100 * P99_LIMIT:.0f} % and max ≤ {100 * MAX_LIMIT:.0f} % of the tick period")

    results = {
        "machine": machine(),
        "inputs": {
            "robots_sha256": {p.stem: sha256(p) for p in robots},
            "firmware_templates_sha256": tree_sha256(ROOT / "firmware_templates"),
            "board_sha256": sha256(ROOT / "boards" / "arduino-nano.toml"),
            "emulator": "simavr 1.6 + proleg avr-emu harness",
            "run_s": RUN_S,
            "boot_s": BOOT_S,
            "gait": "+x 0",
            "seed": SEED,
        },
        "targets": {"busy_p99_fraction": P99_LIMIT, "busy_max_fraction": MAX_LIMIT},
        "robots": rows,
        "all_targets_met": ok,
        "bench_seconds": round(time.perf_counter() - t_start, 1),
    }
    RESULTS.parent.mkdir(parents=True, exist_ok=True)
    RESULTS.write_text(json.dumps(results, indent=1) + "\n")
    print(f"all targets {'met' if ok else 'NOT met'}; wrote {RESULTS.relative_to(ROOT)} in {results['bench_seconds']} s")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
