"""The TerreSoRo converter on synthetic data written in their layout (no published data here)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from proleg.errors import RobotFileError
from proleg.robot import load_robot

sio = pytest.importorskip("scipy.io")
from proleg.convert.terresoro import PAIRS, main, read_terresoro  # noqa: E402


def synthetic(trials: int = 5, seed: int = 3) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return rng.normal(0.0, 1.0, (trials, 240, 3))


def test_transition_k_is_the_kth_ordered_pair_and_statistics_are_sample_ones(tmp_path):
    data = synthetic()
    mat = tmp_path / "prims.mat"
    sio.savemat(mat, {"motion_primitive_data": data})
    stats = read_terresoro(mat)
    assert PAIRS[0] == (0, 1) and PAIRS[14] == (0, 15) and PAIRS[15] == (1, 0) and PAIRS[239] == (15, 14)
    k = PAIRS.index((1, 3))  # their 2 → 4, proleg's 0001 → 0011
    assert stats.mean[1, 3, 0] == pytest.approx(data[:, k, 0].mean())
    assert stats.var[1, 3, 1] == pytest.approx(data[:, k, 1].var(ddof=1))
    assert stats.mean[1, 3, 2] == pytest.approx(math.degrees(data[:, k, 2].mean()))
    assert stats.var[1, 3, 2] == pytest.approx(data[:, k, 2].var(ddof=1) * (180 / math.pi) ** 2)


def test_the_robot_file_it_writes_loads_with_the_same_statistics(tmp_path):
    mat, out = tmp_path / "prims.mat", tmp_path / "terresoro.toml"
    data = synthetic()
    sio.savemat(mat, {"motion_primitive_data": data})
    assert main([str(mat), str(out)]) == 0
    robot = load_robot(out)
    t = robot.transitions
    assert t.n_states == 16 and t.n_transitions == 240 and t.labels()[1] == "0001"
    e = t.lookup(t.index("0001"), t.index("0011"))
    k = PAIRS.index((1, 3))
    assert t.reward[e] == pytest.approx(data[:, k, 0].mean(), abs=1e-6)
    assert t.planar.dtheta_deg[e] == pytest.approx(math.degrees(data[:, k, 2].mean()), abs=1e-6)
    assert t.planar.var_dx[e] == pytest.approx(data[:, k, 0].var(ddof=1), abs=1e-6)


def test_not_their_layout_is_one_clear_line(tmp_path):
    bad = tmp_path / "bad.mat"
    sio.savemat(bad, {"motion_primitive_data": np.zeros((5, 12, 3))})
    with pytest.raises(RobotFileError, match=r"bad\.mat: motion_primitive_data is \(5, 12, 3\), expected"):
        read_terresoro(bad)
    other = tmp_path / "other.mat"
    sio.savemat(other, {"something": np.zeros(3)})
    with pytest.raises(RobotFileError, match="no variable 'motion_primitive_data'"):
        read_terresoro(other)
    junk = tmp_path / "junk.mat"
    junk.write_bytes(b"not a mat file at all")
    with pytest.raises(RobotFileError, match="junk.mat: not a MATLAB .mat file"):
        read_terresoro(junk)
