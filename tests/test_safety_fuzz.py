"""libFuzzer in CI (issue 12): each harness runs a few seconds from the checked-in seeds.

``make fuzz`` runs them long and records bench/results/fuzz.json; this is the short run of
every ``make test``. A crash, a sanitizer report or an envelope violation (tests/fuzz/
envelope.h) fails the test and leaves its reproducer in the work directory.
"""

from __future__ import annotations

import importlib.util
import shutil
import sys
from pathlib import Path

import pytest

FUZZ = Path(__file__).resolve().parent / "fuzz"
SECONDS = 3

pytestmark = pytest.mark.skipif(
    shutil.which("clang") is None and shutil.which("clang-14") is None,
    reason="clang missing (make toolchains installs clang and libclang-rt-14-dev)",
)


def _runner():
    spec = importlib.util.spec_from_file_location("run_fuzz", FUZZ / "run_fuzz.py")
    mod = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = mod  # dataclasses look their module up
    spec.loader.exec_module(mod)
    return mod


@pytest.mark.parametrize("harness", ["fuzz_proto", "fuzz_app"])
def test_a_short_fuzz_run_finds_no_crash_and_no_envelope_violation(harness, tmp_path, capsys):
    rc = _runner().main(["--seconds", str(SECONDS), "--only", harness, "--work", str(tmp_path)])
    out = capsys.readouterr().out
    log = (tmp_path / f"{harness}.log").read_text()
    assert rc == 0, out + log[-3000:]
    assert "stat::number_of_executed_units" in log
    assert int(log.split("stat::number_of_executed_units:")[1].split()[0]) > 50


def test_the_seed_corpus_is_what_make_seeds_writes(tmp_path, monkeypatch):
    spec = importlib.util.spec_from_file_location("make_seeds", FUZZ / "make_seeds.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    for sub, seeds in (("app", mod.APP), ("proto", mod.PROTO)):
        names = {p.name for p in (FUZZ / "corpus" / sub).iterdir()}
        assert names == set(seeds)
        for name, data in seeds.items():
            assert (FUZZ / "corpus" / sub / name).read_bytes() == data
