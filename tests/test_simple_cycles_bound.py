"""``--simple-cycles`` (and ``[gaits] simple_cycles = true``) on a robot of more than 16
states takes the bound every other question takes there, the firmware build's whole-body
wave (2 · Σ(levels − 1) transitions): it was refused, "objective total on 32 states needs an
explicit max_transitions", by `proleg gait` and by `proleg build` alike."""

from __future__ import annotations

import itertools

import numpy as np
from build_checks import cli

from proleg.gait.library import gait_library
from proleg.gait.optimal import whole_body_bound
from proleg.transitions import TransitionTable

LEVELS = (2, 2, 2, 2, 2)


def _one_level_table(seed: int = 3) -> TransitionTable:
    rng = np.random.default_rng(seed)
    labels = list(itertools.product(range(2), repeat=len(LEVELS)))
    n = len(labels)
    allowed = np.array([[sum(x != y for x, y in zip(a, b)) == 1 for b in labels] for a in labels])
    return TransitionTable.from_dense(LEVELS, rng.uniform(-1, 1, (n, n)), allowed)


def test_a_simple_cycle_library_past_16_states_is_bounded_by_the_whole_body_wave():
    table = _one_level_table()
    entries = gait_library(table, "0,180", "total", simple_cycles=True)
    bound = whole_body_bound(LEVELS, "total")
    assert bound == 10
    for e in entries:
        assert e.gait is not None
        assert e.gait.transitions <= bound
        states = e.gait.states[:-1]
        assert len(set(states)) == len(states)  # each state once a pass


def _robot(tmp_path, extra: str = ""):
    parts = ['[robot]\nname = "five"\n']
    for i in range(len(LEVELS)):
        parts.append(f'[[limb]]\nname = "l{i}"\npsi_star_deg = [20.0]\nactuator = "a{i}"\nfriction = "D1"\n')
    parts += [f'[[actuator]]\nname = "a{i}"\n' for i in range(len(LEVELS))]
    labels = ["".join(p) for p in itertools.product("01", repeat=len(LEVELS))]
    rng = np.random.default_rng(5)
    rows = ["from,to,reward"] + [f"{a},{b},{rng.uniform(-1, 1):.3f}" for a in labels for b in labels
                                 if sum(x != y for x, y in zip(a, b)) == 1]
    (tmp_path / "five.csv").write_text("\n".join(rows) + "\n")
    parts.append('[transitions]\nfile = "five.csv"\nunits = "mm"\n[control]\ntick_hz = 500\n' + extra)
    path = tmp_path / "five.toml"
    path.write_text("\n".join(parts))
    return path


def test_gait_simple_cycles_on_32_states_answers_within_the_build_bound(tmp_path, capsys):
    code, out, err = cli(capsys, "gait", _robot(tmp_path), "--simple-cycles")
    assert code == 0, err
    assert out.count("at most 10 transitions") == 2


def test_a_gait_library_of_simple_cycles_on_32_states_builds(tmp_path, capsys):
    path = _robot(tmp_path, "[gaits]\nlibrary = [0, 180]\nsimple_cycles = true\n")
    code, out, err = cli(capsys, "build", path, "--board", "host-sim", "-o", tmp_path / "out")
    assert code == 0, err
    assert "library heading 0 deg" in out and "library heading 180 deg" in out
