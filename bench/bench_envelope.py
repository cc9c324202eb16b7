"""What the safety envelope lets a coil reach, whatever the host commands.

The envelope (docs/safety.md) bounds duty and on-time, not temperature: the firmware senses
neither. This bench asks the most of it: one coil of each example robot is requested at
``max_duty`` on every 2 ms step for 300 s, through the firmware's envelope as the idealised
drive models it (``proleg.sim.physical.envelope.Envelope``: on-time debt and cool-down, the
mean-duty window; sma.c's equal when stepped at the firmware's tick, cutting no later at 2 ms),
and any latched on-limit fault is cleared at once, as a host may (CLEAR refunds nothing;
``latches_cleared`` counts them). The firmware's state timeout and its stall and reach watches
are not modelled: a host reaching this would clear those too. The physical plant's coil temperature is recorded at the supply
powers ×0.7, ×1 and ×1.3. Also printed: where the coil settles held at the mean-duty ceiling
(what ``proleg sim`` warns about past 120 °C).

Writes bench/results/envelope.json and prints the table.
"""

from __future__ import annotations

import json
import logging
import platform
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "host" / "src"))

from proleg.robot import load_robot  # noqa: E402
from proleg.sim.closed_loop import make_plant  # noqa: E402
from proleg.sim.physical.envelope import Envelope, EnvelopeLatched  # noqa: E402
from proleg.physics.materials import NITI_OVERHEAT_C  # noqa: E402

ROBOTS = ("paper-r1", "paper-r1-stroke", "inchworm-3", "caterpillar-4")
POWERS = (0.7, 1.0, 1.3)
DURATION_S = 300.0
DT_S = 0.002


def worst_case(name: str, power: float) -> dict:
    robot = load_robot(ROOT / "robots" / f"{name}.toml")
    plant = make_plant(robot, "physical", [f"power={power}"])
    n = len(robot.actuators)
    env = Envelope(robot, n, DT_S)
    ask = [robot.safety.max_duty] + [0.0] * (n - 1)
    peak, hot_s, duty_s, cleared = plant.temperature_c[0], 0.0, 0.0, 0
    for _ in range(round(DURATION_S / DT_S)):
        try:
            duties = env.gate(ask)
        except EnvelopeLatched:
            env.acknowledge()  # CLEAR(FAULTS): nothing refunded
            cleared += 1
            duties = [0.0] * n
        plant.step(DT_S, duties)
        t = float(plant.temperature_c[0])
        peak = max(peak, t)
        hot_s += DT_S if t > NITI_OVERHEAT_C else 0.0
        duty_s += duties[0] * DT_S
    return {
        "robot": name, "power": power, "coil": robot.actuators[0].name, "max_duty": robot.safety.max_duty,
        "max_on_ms": robot.safety.max_on_ms, "max_mean_duty": robot.safety.max_mean_duty,
        "peak_c": round(peak, 1), "above_120c_s": round(hot_s, 1), "mean_duty": round(duty_s / DURATION_S, 3),
        "latches_cleared": cleared,
        "steady_at_mean_ceiling_c": round(float(plant.steady_coil_temperature_c(robot.safety.mean_ceiling)[0]), 1),
    }


def main() -> int:
    logging.disable(logging.WARNING)  # make_plant's overheat warnings: this bench's subject
    t0 = time.perf_counter()
    rows = [worst_case(name, p) for name in ROBOTS for p in POWERS]
    print(f"\nThe envelope asked for all it allows, {DURATION_S:.0f} s, one coil, latches cleared at once")
    print(f"{'robot':16} {'power':>5} {'max_duty':>8} {'max_on':>6} {'mean':>5} {'peak °C':>8} "
          f"{'>120 °C s':>9} {'mean duty':>9} {'latches':>7} {'held at mean °C':>15}")
    for r in rows:
        print(f"{r['robot']:16} {r['power']:5.1f} {r['max_duty']:8.2f} {r['max_on_ms']:6d} {r['max_mean_duty']:5.2f} "
              f"{r['peak_c']:8.1f} {r['above_120c_s']:9.1f} {r['mean_duty']:9.3f} {r['latches_cleared']:7d} "
              f"{r['steady_at_mean_ceiling_c']:15.1f}")
    out = {
        "benchmark": "envelope",
        "machine": {"python": platform.python_version(), "platform": platform.platform()},
        "duration_s": DURATION_S, "overheat_c": NITI_OVERHEAT_C, "rows": rows,
        "bench_wall_s": round(time.perf_counter() - t0, 1),
    }
    path = ROOT / "bench" / "results" / "envelope.json"
    path.write_text(json.dumps(out, indent=1) + "\n", encoding="utf-8")
    print(f"\nwrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
