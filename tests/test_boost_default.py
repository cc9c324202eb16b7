"""Where the boost is on by default (``proleg.robot_reach.boost_ms_of``, docs/control.md "The
boost"): on a body where a worn coil may end short of a hold, a boosted coil that lags at the
end of its travel is heated at the duty ceiling through its transformation. Off there by
default, on with the coil's heat ceiling, which bounds it, and warned of when a file turns it
on without that ceiling."""

from __future__ import annotations

import json
import logging

from proleg.cli.main import main
from proleg.paths import robots_dir
from proleg.robot import load_robot
from proleg.robot_reach import boost_ms_of
from proleg.robot_settings import BOOST_DEFAULT_MS

CATERPILLAR = robots_dir() / "caterpillar-4.toml"
#: a worn caterpillar in cold air with its front coil overlapping more (bench_sweep.py --seed 7)
WORN = ["ambient_c=6", "overlap_mm=front:9", "fatigue_cycles=7220"]


def _variant(tmp_path, name: str, boost: bool, ceiling: bool):
    text = CATERPILLAR.read_text(encoding="utf-8")
    assert text.count("\n[control]\n") == 1 and text.count("\n[safety]\n") == 1
    if boost:
        text = text.replace("\n[control]\n", "\n[control]\nboost_ms = 700\n")
    if ceiling:
        text = text.replace("\n[safety]\n", "\n[safety]\ncoil_heat_ceiling = true\n")
    path = tmp_path / f"{name}.toml"
    path.write_text(text, encoding="utf-8")
    return path


def _hottest(capsys, path) -> tuple[int, float, int]:
    argv = ["sim", str(path), "--calibrated", "--duration", "50", "--json"]
    for c in WORN:
        argv += ["--condition", c]
    code = main(argv)
    got = json.loads(capsys.readouterr().out)
    return code, max(got["coil_peak_c"].values()), got["cycles"]


def test_a_boosted_worn_coil_overheats_unless_the_heat_ceiling_bounds_it(tmp_path, capsys):
    code, hottest, _ = _hottest(capsys, _variant(tmp_path, "boost", True, False))
    assert code != 0 and hottest > 120.0, (code, hottest)
    code, hottest, cycles = _hottest(capsys, _variant(tmp_path, "ceiling", True, True))
    assert code == 0 and hottest < 100.0 and cycles >= 2, (code, hottest, cycles)
    code, hottest, cycles = _hottest(capsys, CATERPILLAR)  # as shipped: no boost
    assert code == 0 and hottest < 120.0 and cycles >= 2, (code, hottest, cycles)


def test_the_default_follows_the_body_and_the_heat_ceiling(tmp_path, caplog):
    assert boost_ms_of(load_robot(CATERPILLAR)) == 0
    assert boost_ms_of(load_robot(_variant(tmp_path, "ceiling", False, True))) == BOOST_DEFAULT_MS
    assert boost_ms_of(load_robot(robots_dir() / "paper-r1.toml")) == BOOST_DEFAULT_MS
    with caplog.at_level(logging.WARNING, logger="proleg"):
        assert boost_ms_of(load_robot(_variant(tmp_path, "boost", True, False))) == 700
    said = [r.getMessage() for r in caplog.records if "control.boost_ms = 700" in r.getMessage()]
    assert len(said) == 1 and "coil_heat_ceiling = true" in said[0] and "'rear'" in said[0], said
    caplog.clear()
    with caplog.at_level(logging.WARNING, logger="proleg"):
        load_robot(_variant(tmp_path, "both", True, True))
        load_robot(robots_dir() / "paper-r1.toml")
    assert not [r for r in caplog.records if "boost_ms" in r.getMessage()]


def test_no_warning_of_a_boost_the_build_leaves_out(tmp_path, caplog):
    """drive_duty 0.79999 is max_duty 0.8 in the firmware's per-myriad units: the build leaves the
    boost out (boost_ms_of 0), so the load must not warn that a worn coil is boosted. The warning
    compared the floats and warned of a boost the firmware does not carry."""
    text = _variant(tmp_path, "boost", True, False).read_text(encoding="utf-8")
    assert text.count("\ndrive_duty = 0.6\n") == 1
    text = text.replace("\ndrive_duty = 0.6\n", "\ndrive_duty = 0.79999\n")
    path = tmp_path / "at-ceiling.toml"
    path.write_text(text, encoding="utf-8")
    with caplog.at_level(logging.WARNING, logger="proleg"):
        robot = load_robot(path)
    assert boost_ms_of(robot) == 0
    assert not [r for r in caplog.records if "boost_ms" in r.getMessage()]
