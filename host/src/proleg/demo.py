"""``make demo``: the main job, end to end on the simulated board.

1. The paper's four robots: their optimal gaits in both directions, from the matrices.
2. Robot R1's firmware, built for the host-sim board (the same C as on the MCUs).
3. That firmware in closed loop with the plant: R1's optimal +x gait, then its -x gait,
   each for a simulated minute, with the displacement per cycle and telemetry summary.
4. The same body with its limbs raised to full strokes (robots/paper-r1-stroke.toml): the
   whole-body ratchet the ψ-feedback firmware walks faster than the best timed drive.
5. R1's firmware under ten random operating conditions (``proleg check``), each against an
   idealised drive that says whether the coils can walk the gait there at all.
"""

from __future__ import annotations

import sys
import time

from .cli import main as cli_main
from .paths import robots_dir

ROBOTS = ("paper-r1", "paper-r2", "paper-r3", "paper-r1-one-actuator")


def _step(title: str) -> None:
    print(f"\n== {title}", flush=True)


def main() -> int:
    robots = robots_dir()
    _step("1. optimal gaits of the paper's robots (proleg gait ROBOT.toml)")
    for name in ROBOTS:
        print(flush=True)
        if cli_main(["gait", str(robots / f"{name}.toml")]):
            return 1

    r1 = str(robots / "paper-r1.toml")
    _step("2. R1's firmware for the simulated board (proleg build robots/paper-r1.toml --board host-sim)")
    if cli_main(["build", r1, "--board", "host-sim"]):
        return 1

    for direction in ("+x", "-x"):
        _step(f"3. R1 in closed loop, optimal {direction} gait, one simulated minute "
              f"(proleg sim robots/paper-r1.toml --direction {direction})")
        t0 = time.perf_counter()
        if cli_main(["sim", r1, "--direction", direction, "--duration", "60"]):
            return 1
        print(f"  ({60 / (time.perf_counter() - t0):.0f}x real time)")

    _step("4. R1's body held at full strokes, one simulated minute "
          "(proleg sim robots/paper-r1-stroke.toml; docs/control.md, \"Full strokes\")")
    if cli_main(["sim", str(robots / "paper-r1-stroke.toml"), "--duration", "60"]):
        return 1
    print("  (the transitions not in the matrix are 00 -> 10 -> 11 and back: the rise lead crosses psi* "
          "first, by design)")

    _step("5. R1 under ten random operating conditions (proleg check robots/paper-r1.toml --rows 10)")
    if cli_main(["check", r1, "--rows", "10", "-q"]):
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
