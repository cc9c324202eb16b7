"""``--inject`` and ``--condition`` read a limb's or an actuator's name the same way (one helper,
``proleg.sim.physical.conditions.resolve_name``): ``--inject`` refused a limb named " a" as
``a`` and a name given with spaces at its ends, which ``--condition`` takes, and read
``drift:front@pad@0.1`` as the actuator ``front`` at the rate ``pad@0.1``."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from build_checks import cli
from proleg.errors import SimError
from proleg.robot import load_robot
from proleg.sim.closed_loop import SimulatedRobot, make_plant
from proleg.sim.physical.conditions import parse_conditions, resolve_name

ROBOTS = Path(__file__).resolve().parents[1] / "robots"


@pytest.fixture(scope="module")
def robot_file(tmp_path_factory) -> Path:
    """paper-r1 with its limbs named " a" (spaces at its end) and "front@pad"."""
    text = (ROBOTS / "paper-r1.toml").read_text(encoding="utf-8")
    path = tmp_path_factory.mktemp("names") / "names.toml"
    path.write_text(text.replace('name = "left"', 'name = " a"').replace('name = "right"', 'name = "front@pad"'),
                    encoding="utf-8")
    return path


@pytest.fixture(scope="module")
def sim(robot_file):
    robot = load_robot(robot_file)
    return SimulatedRobot(robot, seed=1, plant=make_plant(robot, "physical"))


def _coil_of(sim, condition: str) -> int:
    """The actuator index a per-actuator ``--condition`` sets (power_scale below 1)."""
    conditions = parse_conditions([condition])
    acts = [a.name for a in sim.robot.actuators]
    limbs = [lb.name for lb in sim.robot.limbs]
    by_limb = [acts.index(lb.actuator) for lb in sim.robot.limbs]
    return [i for i in range(len(acts))
            if conditions.for_index("power_scale", i, acts, by_limb, limbs) < 1][0]


@pytest.mark.parametrize("name, coil", [("a", 0), (" a ", 0), ("front@pad", 1), ("  front@pad", 1), ("front", 1),
                                        ("rear", 0), (" sma-right ", 1), ("1", 1)])
def test_inject_names_the_coil_condition_names(sim, monkeypatch, name, coil):
    drifted = []
    monkeypatch.setattr(sim.plant, "inject_drift", lambda ch, rate, *a: drifted.append((ch, rate)))
    killed = []
    monkeypatch.setattr(sim.plant, "kill_actuator", killed.append)
    channels = [a.channel for a in sim.robot.actuators]
    assert _coil_of(sim, f"power_scale={name}:0.5") == coil
    sim.check_fault(f"dead-actuator:{name}")
    sim.inject(f"dead-actuator:{name}")
    sim.inject(f"drift:{name}@0.25")
    sim.inject(f"drift:{name}")
    assert killed == [channels[coil]]
    assert drifted == [(channels[coil], 0.25), (channels[coil], 0.05)]


@pytest.mark.parametrize("name, limb", [("a", 0), (" a ", 0), ("front@pad", 1), (" front@pad ", 1), ("0", 0)])
def test_inject_names_the_limb_condition_names(sim, monkeypatch, name, limb):
    silenced = []
    monkeypatch.setattr(sim.board, "imu_fault", lambda addr, kind: silenced.append(addr))
    conditions = parse_conditions([f"imu_bias_deg={name}:3"])
    limbs = [lb.name for lb in sim.robot.limbs]
    assert [conditions.for_index("imu_bias_deg", i, limbs) for i in range(2)] == [3.0 if i == limb else 0.0
                                                                                  for i in range(2)]
    sim.check_fault(f"imu-silent:{name}")
    sim.inject(f"imu-silent:{name}")
    assert silenced == [sim.imu_addresses[limb]]


def test_a_name_neither_knows_is_refused_by_both_naming_it(sim):
    with pytest.raises(SimError, match=r"^condition imu_bias_deg: no limb 'b' \(expected one of:  a, front@pad"):
        parse_conditions(["imu_bias_deg= b :1"]).check_names([lb.name for lb in sim.robot.limbs], [])
    with pytest.raises(SimError, match=r"^--inject imu-silent: b : fault needs a limb \( a, front@pad, rear, front "
                                       r"or 0\.\.1\), got 'b'$"):
        sim.check_fault("imu-silent: b ")
    with pytest.raises(SimError, match=r"drift@RATE \(per second of on-time\): expected a number, got 'x'$"):
        sim.check_fault("drift:front@pad@x")


@pytest.mark.parametrize("spec, says", [
    ("drift@", "no rate after '@' (expected e.g. drift@0.05, or drift alone for 0.05)"),
    ("drift:front@pad@", "no rate after '@'"),
    ("drift:", "nothing after ':' (expected drift:ACTUATOR[@RATE], or drift alone for every coil)"),
    ("drift:@0.1", "no actuator between ':' and '@'"),
    ("link-drop:", "nothing after ':' (expected link-drop:P, or link-drop alone for P = 0.01)"),
    ("link-corrupt: ", "nothing after ':'"),
    ("imu-silent:", "nothing after ':' (expected imu-silent:LIMB)"),
])
def test_a_name_or_number_left_out_after_its_separator_is_refused(sim, spec, says):
    """Each was the fault's default, as if the ':' or '@' were not there: drift@ drifted at 0.05,
    drift: and drift:@0.1 every coil, link-drop: dropped 1 % of the bytes."""
    with pytest.raises(SimError) as e:
        sim.check_fault(spec)
    assert str(e.value).startswith(f"--inject {spec}: ") and says in str(e.value), str(e.value)


def test_names_alike_but_for_spaces_are_refused_alike():
    with pytest.raises(SimError, match=r"^'a' names ' a', 'a ' alike \(spaces at a name's ends do not count\): give "
                                       "the index instead$"):
        resolve_name("a", [" a", "a "])
    with pytest.raises(SimError, match="alike"):
        resolve_name(" a", [" a", "a "])  # given whole it is stripped too, as --condition strips it
    assert resolve_name("1", [" a", "a "]) == 1


def test_the_cli_takes_the_names_in_both(capsys, robot_file):
    """End to end: what --condition takes, --inject takes (it refused 'a' and 'drift:front@pad@0.1')."""
    code, out, err = cli(capsys, "sim", robot_file, "--duration", "2", "--json", "--condition", "imu_bias_deg=a:1",
                         "--inject", "imu-silent:a")
    assert code == 1 and [(f["code"], f["detail"]) for f in json.loads(out)["faults"]] == [("IMU_NO_ACK", 0)], err
    code, out, err = cli(capsys, "sim", robot_file, "--duration", "1", "--json", "--condition",
                         "power_scale=front@pad:0.9", "--inject", "drift:front@pad@0.1+0.5")
    assert code == 0, err
