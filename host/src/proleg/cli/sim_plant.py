"""``proleg sim``'s plant options: ``--plant``, ``--condition``, ``--measure-matrix``.

Kept apart from the rest of the sim subcommand (``cli/main.py``) so that other options can be
added there without touching these. The keys ``--condition`` takes are the physical keys of
the robot file's ``[plant]`` schema (``proleg.robot_plant.PLANT_KEYS``, docs/robot-file.md);
the values given here go on top of the robot file's.
"""

from __future__ import annotations

import argparse
import json
from typing import Any

PLANT_CHOICES = ("physical", "table")


def add_plant_options(s: argparse.ArgumentParser) -> None:
    s.add_argument("--plant", choices=PLANT_CHOICES, default="physical",
                   help="the simulated body: 'physical' (default; displacement from friction mechanics) or "
                        "'table' (the robot's reward matrix as a lookup, e.g. to test learning)")
    s.add_argument("--condition", action="append", default=[], metavar="KEY=VALUE",
                   help="a physical-plant condition, repeatable, on top of the robot file's [plant] "
                        "(e.g. power=0.8, ambient_c=30, imu_bias_deg=front:3, incline_deg=5); "
                        "--condition help lists every key with its unit and range")
    s.add_argument("--measure-matrix", action="store_true",
                   help="measure the robot's transition reward matrix (mm) on the physical plant and print it")


def plant_kwargs(args: argparse.Namespace) -> dict[str, Any]:
    """``SimulatedRobot`` keyword arguments for the chosen plant and conditions."""
    return {"plant": args.plant, "conditions": list(args.condition)}


def wants_help(args: argparse.Namespace) -> bool:
    if "help" in args.condition:
        from ..sim.physical import describe_keys

        print(describe_keys())
        return True
    return False


def cmd_measure_matrix(args: argparse.Namespace, robot: Any) -> int:
    """``proleg sim ROBOT --measure-matrix [--json]``."""
    from ..errors import SimError
    from ..sim.closed_loop import plant_conditions
    from ..sim.physical import measure_matrix

    if args.plant != "physical":
        raise SimError("--measure-matrix: the matrix is measured on the physical plant (the table plant is the matrix)")
    m = measure_matrix(robot, plant_conditions(robot, args.condition), seed=args.seed)
    if args.json:
        print(json.dumps({"robot": robot.name, "plant": "physical", "conditions": list(args.condition),
                          **m.to_json()}))
        return 0
    width = max(6, *(len(s) for s in m.states))
    print(f"{robot.name}: reward matrix measured on the physical plant (mm, row = from; "
          f"mechanisms {'/'.join(m.mechanisms)}, {m.mechanism_source})")
    print(" " * width + "".join(f"{s:>{width + 3}}" for s in m.states))
    for a, row in enumerate(m.matrix_mm):
        cells = []
        for b, x in enumerate(row):
            cells.append(f"{'-' if x != x else f'{x:+.2f}':>{width + 3}}" if a != b else f"{'.':>{width + 3}}")
        print(f"{m.states[a]:<{width}}" + "".join(cells))
    print(f"samples per entry: {int(m.samples.max()) if m.samples.size else 0} (entries without a sample: '-')")
    return 0
