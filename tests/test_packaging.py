"""The wheel is a complete proleg: boards, templates and example robots travel with it.

Builds the wheel from this checkout, unpacks it into a fresh directory (no editable
install, no source tree on the path) and runs ``python -m proleg`` from an unrelated
working directory.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

import proleg
from proleg import paths

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def wheel(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("wheel")
    proc = subprocess.run(
        [sys.executable, "-m", "pip", "wheel", "--no-deps", "-q", "-w", str(out), str(ROOT)],
        capture_output=True, text=True,
    )
    if proc.returncode:
        pytest.fail(f"building the wheel failed:\n{proc.stdout}\n{proc.stderr}")
    (whl,) = out.glob("proleg-*.whl")
    return whl


@pytest.fixture(scope="module")
def installed(wheel, tmp_path_factory) -> Path:
    target = tmp_path_factory.mktemp("site")
    with zipfile.ZipFile(wheel) as z:
        z.extractall(target)
    return target


@pytest.fixture(scope="module")
def venv_python(wheel, tmp_path_factory) -> Path:
    """A fresh virtual environment with the wheel installed by pip (its dependencies come from
    this test environment's site-packages through a .pth file: no network, no source tree)."""
    import sysconfig
    import venv

    env_dir = tmp_path_factory.mktemp("venv") / "env"
    venv.create(env_dir, with_pip=False)
    python = env_dir / "bin" / "python"
    site = subprocess.run([str(python), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                          capture_output=True, text=True, check=True).stdout.strip()
    Path(site, "_test_deps.pth").write_text(sysconfig.get_paths()["purelib"] + "\n")
    proc = subprocess.run([sys.executable, "-m", "pip", "--python", str(python), "install", "-q", "--no-deps",
                           "--no-index", str(wheel)], capture_output=True, text=True)
    if proc.returncode:
        pytest.fail(f"installing the wheel failed:\n{proc.stdout}\n{proc.stderr}")
    return python


def _run(installed: Path, cwd: Path, *args: str) -> subprocess.CompletedProcess:
    env = {k: v for k, v in os.environ.items() if k != "PROLEG_HOME"}
    env["PYTHONPATH"] = str(installed)  # ahead of the editable install's finder
    return subprocess.run([sys.executable, "-m", "proleg", *args], cwd=cwd, env=env,
                          capture_output=True, text=True, timeout=300)


def test_the_wheel_carries_boards_templates_robots_and_the_license(wheel):
    names = set(zipfile.ZipFile(wheel).namelist())
    for rel in ("boards/arduino-nano.toml", "firmware_templates/core/hal.h", "robots/paper-r1.toml"):
        assert f"proleg/_data/{rel}" in names, rel
    assert any(n.endswith("licenses/LICENSE") for n in names)
    meta = next(n for n in names if n.endswith("METADATA"))
    text = zipfile.ZipFile(wheel).read(meta).decode()
    assert "License-Expression: MIT" in text
    assert f"Version: {proleg.__version__}" in text


def test_the_installed_wheel_finds_its_data_outside_the_source_tree(installed, tmp_path):
    probe = "import proleg.paths as p; print(p.home()); print(' '.join(p.bundled_robots()))"
    env = {k: v for k, v in os.environ.items() if k != "PROLEG_HOME"}
    env["PYTHONPATH"] = str(installed)
    proc = subprocess.run([sys.executable, "-c", probe], cwd=tmp_path, env=env, capture_output=True, text=True)
    home, robots = proc.stdout.splitlines()
    assert Path(home) == installed / "proleg" / "_data"
    assert "paper-r1" in robots.split()


def test_the_installed_wheel_computes_gaits_and_builds_firmware_from_another_directory(installed, tmp_path):
    robot = installed / "proleg" / "_data" / "robots" / "paper-r1.toml"
    gait = _run(installed, tmp_path, "gait", str(robot), "--max-transitions", "3")
    assert gait.returncode == 0, gait.stderr
    assert "00" in gait.stdout
    build = _run(installed, tmp_path, "build", str(robot), "--board", "host-sim", "-o", str(tmp_path / "fw"))
    assert build.returncode == 0, build.stderr
    assert (tmp_path / "fw" / "libfirmware.so").exists()


def test_a_bundled_robot_is_found_by_name():
    assert paths.resolve_robot("paper-r1") == paths.robots_dir() / "paper-r1.toml"
    assert paths.resolve_robot("no-such-robot") == Path("no-such-robot")
    assert paths.resolve_robot("x/paper-r1.toml") == Path("x/paper-r1.toml")


def test_the_wheel_in_a_fresh_venv_gives_version_build_and_sim_from_another_directory(venv_python, tmp_path):
    import proleg

    env = {k: v for k, v in os.environ.items() if k not in ("PROLEG_HOME", "PYTHONPATH")}
    env["PROLEG_CACHE"] = str(tmp_path / "cache")

    def run(*args: str) -> subprocess.CompletedProcess:
        return subprocess.run([str(venv_python.parent / "proleg"), *args], cwd=tmp_path, env=env,
                              capture_output=True, text=True, timeout=600)

    where = subprocess.run([str(venv_python), "-c", "import proleg; print(proleg.__file__)"], cwd=tmp_path,
                           env=env, capture_output=True, text=True, check=True).stdout
    assert str(ROOT) not in where  # the installed copy, not the source tree
    version = run("--version")
    assert version.returncode == 0 and proleg.__version__ in version.stdout, version
    build = run("build", "paper-r1", "--board", "host-sim", "-o", str(tmp_path / "fw"))
    assert build.returncode == 0, build.stderr
    sim = run("sim", "paper-r1", "--duration", "10", "--json")
    assert sim.returncode == 0, sim.stderr
    report = json.loads(sim.stdout)
    assert report["cycles"] >= 1 and not report["faults"], report
