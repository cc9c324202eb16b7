"""``make demo``: the paper's robots, their optimal gaits in both directions.

Later steps of the project extend this into the full closed-loop run on the simulated
board; for now it is the gait engine answering the paper's questions from the matrices.
"""

from __future__ import annotations

import sys
from pathlib import Path

from .cli import main as cli_main

ROBOTS = ("paper-r1", "paper-r2", "paper-r3", "paper-r1-one-actuator")


def robots_dir() -> Path:
    return Path(__file__).resolve().parents[3] / "robots"


def main() -> int:
    for name in ROBOTS:
        path = robots_dir() / f"{name}.toml"
        print(f"$ proleg gait {path.relative_to(Path.cwd()) if path.is_relative_to(Path.cwd()) else path}")
        status = cli_main(["gait", str(path)])
        if status:
            return status
        print()
    return 0


if __name__ == "__main__":
    sys.exit(main())
