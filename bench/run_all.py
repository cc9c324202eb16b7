"""``make bench``: run every bench/bench_*.py in turn (some more than once: ``RUNS``); each
prints its table and writes bench/results/<name>.json. Exits non-zero if a benchmark script itself fails."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent

#: Scripts run more than once, with these arguments (default: once, without any).
RUNS = {"bench_claim.py": [[], ["--robot", "robots/paper-r1-stroke.toml"]]}


def main() -> int:
    failed = []
    for script in sorted(HERE.glob("bench_*.py")):
        for args in RUNS.get(script.name, [[]]):
            name = " ".join([script.name, *args])
            print(f"\n=== {name} ===", flush=True)
            if subprocess.run([sys.executable, str(script), *args], cwd=HERE.parent).returncode:
                failed.append(name)
    if failed:
        print(f"\nbenchmarks that failed to run: {', '.join(failed)}", file=sys.stderr)
        return 1
    print(f"\nresults in {HERE / 'results'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
