"""``proleg gait`` on a learned file says which steps of a gait were never measured: a partial
``proleg learn`` keeps the file's own value where a transition had no trial (``n_trials`` 0,
docs/learning.md), and a gait ranked on such a guess promised +3.08 mm and walked −0.03."""

from __future__ import annotations

import json

from build_checks import cli

from proleg.paths import robots_dir

# R1's paper matrix, with the trials a partial learning left: 10 → 11 never tried
N_TRIALS = """n_trials = [
  [0, 4, 4, 4],
  [4, 0, 4, 4],
  [4, 4, 0, 0],
  [4, 4, 4, 0],
]
"""


def _learned(tmp_path, n_trials: str = N_TRIALS):
    text = (robots_dir() / "paper-r1.toml").read_text(encoding="utf-8")
    assert text.count("\n[safety]\n") == 1
    path = tmp_path / "r1-learned.toml"
    path.write_text(text.replace("\n[safety]\n", f"\n{n_trials}\n[safety]\n"), encoding="utf-8")
    return path


def test_a_gait_through_a_step_never_measured_is_noted(capsys, tmp_path):
    code, out, err = cli(capsys, "gait", str(_learned(tmp_path)), "--direction", "+x")
    assert code == 0, err
    assert "00 → 10 → 11 → 01 → 00" in out  # R1's +x gait 0 takes 10 → 11
    assert "takes 10 → 11 at the value the file had before learning (n_trials 0:" in out
    code, out, err = cli(capsys, "gait", str(_learned(tmp_path)), "--direction", "+x", "--json")
    gaits = json.loads(out)["results"][0]["gaits"]
    first = next(g for g in gaits if g["states"] == ["00", "10", "11", "01", "00"])
    assert first["unmeasured_steps"] == [["10", "11"]]


def test_a_gait_measured_throughout_has_no_note(capsys, tmp_path):
    every = N_TRIALS.replace("[4, 4, 0, 0]", "[4, 4, 0, 4]")
    code, out, err = cli(capsys, "gait", str(_learned(tmp_path, every)), "--direction", "+x")
    assert code == 0 and "n_trials 0" not in out, out
    code, out, err = cli(capsys, "gait", str(_learned(tmp_path, every)), "--direction", "+x", "--json")
    assert all(g["unmeasured_steps"] == [] for g in json.loads(out)["results"][0]["gaits"])


def test_a_hand_written_file_says_nothing_of_trials(capsys):
    code, out, err = cli(capsys, "gait", str(robots_dir() / "paper-r1.toml"), "--direction", "+x", "--json")
    assert code == 0
    assert all("unmeasured_steps" not in g for g in json.loads(out)["results"][0]["gaits"])
