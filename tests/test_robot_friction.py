"""The robot file says which friction mechanism each limb carries (issue 13): ``[[limb]]
friction = "D1" | "D2"`` or one material per level; the physical plant then uses it instead of
inferring the mechanisms from the matrix's signs."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from proleg.errors import RobotFileError
from proleg.paths import robots_dir
from proleg.robot import load_robot
from proleg.robot_plant import FRICTION_MATERIALS, FRICTION_MECHANISMS
from proleg.sim.physical import PhysicalPlant, measure_matrix
from proleg.physics import materials


def with_friction(tmp_path: Path, name: str, *values: str | None) -> Path:
    """``robots/<name>.toml`` with ``friction = value`` added to each [[limb]] (None: left out)."""
    text = (robots_dir() / f"{name}.toml").read_text()
    parts = text.split("[[limb]]")
    assert len(parts) == len(values) + 1
    out = parts[0]
    for part, value in zip(parts[1:], values):
        head, nl, rest = part.partition("\n")
        out += "[[limb]]" + head + nl + ("" if value is None else f"friction = {value}\n") + rest
    path = tmp_path / f"{name}.toml"
    path.write_text(out)
    return path


def test_the_robot_files_names_are_the_plants_materials():
    assert set(FRICTION_MATERIALS) == set(materials.MATERIALS)
    assert FRICTION_MECHANISMS == materials.MECHANISMS


def test_declared_mechanisms_reach_the_physical_plant(tmp_path):
    r = load_robot(with_friction(tmp_path, "paper-r1", '"D1"', '"D2"'))
    assert [limb.friction for limb in r.limbs] == ["D1", "D2"]
    plant = PhysicalPlant(r)
    assert plant.mechanisms == ("D1", "D2")
    assert plant.mechanism_source == "robot file"


def test_without_the_key_the_mechanisms_are_still_inferred():
    r = load_robot(robots_dir() / "paper-r1.toml")
    assert all(limb.friction is None for limb in r.limbs)
    assert PhysicalPlant(r).mechanism_source == "inferred from the matrix"


def test_a_robot_with_a_multi_level_limb_says_why_its_mechanisms_are_not_inferred():
    """caterpillar-4 without friction: its binary end pads take D1 and its three-level prolegs
    alternate soft/hard, not inferred; the source said only "default", and the docs had the
    two-level limbs of such a robot inferred."""
    plant = PhysicalPlant(load_robot(robots_dir() / "caterpillar-4.toml"))
    assert plant.mechanisms == ("D1", "custom", "custom", "D1")
    assert plant.mechanism_source == "default (not inferred: a limb has more than two levels)"


def test_declaring_d2_makes_r1_move_like_r2():
    """R1's matrix with D2 pads declared: the measured 00->10 and 00->01 take R2's signs
    (the paper: R1 00->10 = +1, R2 00->10 = -1), so the declaration is what moves the body."""
    import tempfile

    with tempfile.TemporaryDirectory() as d:
        r1_d2 = load_robot(with_friction(Path(d), "paper-r1", '"D2"', '"D2"'))
    r1 = load_robot(robots_dir() / "paper-r1.toml")
    as_d1 = measure_matrix(r1, repeats=1)
    as_d2 = measure_matrix(r1_d2, repeats=1)
    i00, i01, i10 = (as_d1.states.index(s) for s in ("00", "01", "10"))
    assert np.sign(as_d1.matrix_mm[i00, i10]) == +1 and np.sign(as_d2.matrix_mm[i00, i10]) == -1
    assert np.sign(as_d1.matrix_mm[i00, i01]) == -1 and np.sign(as_d2.matrix_mm[i00, i01]) == +1


def test_a_multi_level_limb_takes_one_material_per_level(tmp_path):
    levels = [limb.levels for limb in load_robot(robots_dir() / "caterpillar-4.toml").limbs]
    values = [str(["soft", "hard", "soft"][:k] if k <= 3 else ["soft"] * k).replace("'", '"') for k in levels]
    r = load_robot(with_friction(tmp_path, "caterpillar-4", *values))
    assert [len(limb.friction) for limb in r.limbs] == levels
    assert PhysicalPlant(r).mechanism_source == "robot file"


@pytest.mark.parametrize("values, words", [
    (('"D3"', '"D1"'), "limb 'left': friction: expected one of D1, D2 or a list of materials (soft, hard), got 'D3'"),
    (('["soft"]', '"D1"'), "limb 'left': friction: expected D1, D2 or a list of 2 materials (one per level, level 0 "
                           "first), each soft or hard or { mu_static = …, mu_kinetic = … }, got ['soft']"),
    (('["soft", "rubber"]', '"D1"'), "limb 'left': friction[2] (level 1): expected a material (soft, hard) or "
                                     "{ mu_static = …, mu_kinetic = … }, got 'rubber'"),
    (('1', '"D1"'), "limb 'left': friction: expected D1, D2 or a list of 2 materials"),
    (('"D1"', None), "limb 'right': friction: expected on every limb or on none"),
])
def test_a_bad_friction_is_one_line_naming_the_limb(tmp_path, values, words):
    with pytest.raises(RobotFileError, match=re.escape(words)) as e:
        load_robot(with_friction(tmp_path, "paper-r1", *values))
    assert "\n" not in str(e.value)


def test_d1_on_a_three_level_limb_says_to_list_the_materials(tmp_path):
    levels = [limb.levels for limb in load_robot(robots_dir() / "caterpillar-4.toml").limbs]
    assert 3 in levels
    values = ['"D1"' if k == 3 else '"D2"' for k in levels]
    with pytest.raises(RobotFileError, match="friction: D1 describes 2 levels, the limb has 3; give a list of 3"):
        load_robot(with_friction(tmp_path, "caterpillar-4", *values))


def _inchworm_with_plant(tmp_path: Path, plant: str) -> Path:
    """robots/inchworm-3.toml (no friction: its mechanisms are inferred) with a [plant] table."""
    text = (robots_dir() / "inchworm-3.toml").read_text()
    path = tmp_path / "inchworm-3.toml"
    path.write_text(text + "\n[plant]\n" + plant + "\n" if "[plant]" not in text else text.replace("[plant]", "[plant]\n" + plant, 1))
    return path


def test_the_mechanisms_are_inferred_on_the_robot_files_body(tmp_path):
    """The inference swept a body with the default overlap_mm, not the file's: a 200 mm
    three-limb body whose coils do not overlap (each coil's section bends 172°) loaded without
    a word, and `proleg sim` refused it, "coil 2 spans 116 mm … bends it by 199°" (the 100 mm
    section plus the default 8 mm each side), a body the file does not describe."""
    r = load_robot(_inchworm_with_plant(tmp_path, "length_mm = 200\noverlap_mm = 0"))
    plant = PhysicalPlant(r)
    assert plant.mechanism_source == "inferred from the matrix"
    assert [round(b - a) for a, b in plant.geometry.spans] == [50, 100, 50]


def test_the_inference_is_not_shared_by_robots_of_other_bodies(tmp_path):
    """The inference's cache took the matrix, limbs and coils as its key, not the body: a second
    robot of the same matrix on another body got the first one's answer in one process."""
    from proleg.sim.physical import mechanism
    from proleg.sim.physical.measure import kinematic_signs_all

    seen = []
    real = kinematic_signs_all

    def spy(robot, combos, **kw):
        seen.append(robot.plant.length_mm)
        return real(robot, combos, **kw)

    mechanism._CACHE.clear()
    import proleg.sim.physical.measure as measure
    old, measure.kinematic_signs_all = measure.kinematic_signs_all, spy
    try:
        for length in (90, 110):
            sub = tmp_path / str(length)
            sub.mkdir()
            PhysicalPlant(load_robot(_inchworm_with_plant(sub, f"length_mm = {length}")))
    finally:
        measure.kinematic_signs_all = old
    assert seen == [90, 110]


def test_the_mechanisms_are_inferred_on_the_body_the_run_simulates(tmp_path):
    """`proleg sim ROBOT --condition overlap_mm=0` on a 200 mm three-limb body: the run's body
    is one the model describes, but the inference swept the file's (overlap 8 mm: the middle coil
    over 116 mm, 199°) and the run was refused as curling over itself."""
    from proleg.sim.closed_loop import plant_conditions

    r = load_robot(_inchworm_with_plant(tmp_path, "length_mm = 200"))
    plant = PhysicalPlant(r, plant_conditions(r, ["overlap_mm=0"]))
    assert plant.mechanism_source == "inferred from the matrix"
    assert [round(b - a) for a, b in plant.geometry.spans] == [50, 100, 50]
