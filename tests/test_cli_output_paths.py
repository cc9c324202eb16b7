"""Every option naming a file proleg writes refuses a directory in the file's place the same
way: one line naming the path, exit 1 (an output that cannot be written where it is named, as
a full disk or a folder without write permission: README's and --help's exit statuses), before
anything runs. ``plot -o DIR`` and ``gait --plot DIR`` said exit 2 while ``dbc -o``,
``--record`` and ``--out`` said 1. A folder that does not exist stays a usage mistake (exit 2)."""

from __future__ import annotations

from pathlib import Path

import pytest

from proleg.cli.main import main

R1 = str(Path(__file__).resolve().parents[1] / "robots" / "paper-r1.toml")
LEARN = ["learn", R1, "--sim", "--plant", "table", "--repeats", "1"]

OUTPUTS = {  # option: (the command with {out} where the output goes, the output's name)
    "plot -o": (["plot", "-o", "{out}", "{recording}"], "out.png"),
    "gait --plot": (["gait", R1, "--plot", "{out}"], "out.png"),
    "dbc -o": (["dbc", "--robot", R1, "-o", "{out}"], "out.dbc"),
    "sim --record": (["sim", R1, "--duration", "0.5", "--record", "{out}"], "out.jsonl"),
    "console --record": (["console", "--sim", R1, "--plain", "--duration", "0.5", "--record", "{out}"], "out.csv"),
    "run --record": (["run", "--sim", R1, "--duration", "0.5", "--record", "{out}"], "out.mcap"),
    "learn --out": ([*LEARN, "--log", "{tmp}/t.jsonl", "--out", "{out}"], "out.toml"),
    "learn --log": ([*LEARN, "--log", "{out}"], "out.jsonl"),
    "sim --measure-matrix --out": (["sim", R1, "--measure-matrix", "--out", "{out}"], "out.toml"),
}


@pytest.fixture(scope="module")
def recording(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("rec") / "run.jsonl"
    assert main(["sim", R1, "--duration", "0.5", "--record", str(path)]) == 0
    return path


@pytest.mark.parametrize("option", list(OUTPUTS))
def test_every_output_option_refuses_a_directory_in_the_files_place_with_exit_1(option, tmp_path, capsys, monkeypatch,
                                                                               recording):
    import proleg.learn.runner
    import proleg.sim.physical

    def ran(*_a, **_k):
        raise AssertionError("ran before the output was checked")

    monkeypatch.setattr(proleg.sim.physical, "measure_matrix", ran)
    monkeypatch.setattr(proleg.learn.runner.Explorer, "run", ran)
    argv, name = OUTPUTS[option]
    out = tmp_path / name
    out.mkdir()
    capsys.readouterr()
    code = main([a.format(out=out, tmp=tmp_path, recording=recording) for a in argv])
    err = capsys.readouterr().err
    assert code == 1, (code, err)
    assert err.count("\n") == 1 and err.startswith("proleg: error: ") and f"{out}: Is a directory" in err, err
    assert "robot stopped" not in err and sorted(p.name for p in tmp_path.iterdir()) == [name]  # nothing run


@pytest.mark.parametrize("option", list(OUTPUTS))
def test_every_output_option_in_a_folder_that_does_not_exist_is_a_usage_mistake_exit_2(option, tmp_path, capsys,
                                                                                       recording):
    argv, name = OUTPUTS[option]
    out = tmp_path / "missing" / name
    code = main([a.format(out=out, tmp=tmp_path, recording=recording) for a in argv])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1, (code, err)
    assert "does not exist" in err or "No such file or directory" in err, err
