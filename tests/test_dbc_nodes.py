"""The generated DBC names each node once, and each signal."""

from __future__ import annotations

from pathlib import Path

import pytest

from proleg.errors import UsageError
from proleg.protocol.dbc import build_database, dbc_text


def _nodes(text: str) -> list[str]:
    line = next(line for line in text.splitlines() if line.startswith("BU_:"))
    return line.split(":", 1)[1].split()


@pytest.mark.parametrize("nodes", [(0,), (0, 1), (3, 1, 2)])
def test_every_node_name_appears_once(nodes):
    names = _nodes(dbc_text(nodes))
    assert len(names) == len(set(names)) == len(nodes) + 1


def test_a_repeated_node_id_is_refused_in_one_line():
    with pytest.raises(UsageError, match=r"^dbc: node id 1 given more than once"):
        dbc_text((0, 1, 1))


def test_signal_names_stay_apart_whatever_the_limbs_are_called():
    """A limb called "5" is psi_5; the unused sixth ψ slot then becomes psi_slot5 (psi_slot5_2
    beside a limb called "slot5"), and a limb called "count" leaves psi_count_field for the
    count. Every telemetry signal name is used once."""
    from types import SimpleNamespace as NS

    robot = NS(limbs=[NS(name="5"), NS(name="count"), NS(name="slot5")], actuators=[NS(name="sma-a"), NS(name="2")])
    db = build_database(robot=robot)
    names = [s.name for m in db.messages if m.name.startswith("TELEMETRY") for s in m.signals]
    assert len(names) == len(set(names)), sorted(n for n in names if names.count(n) > 1)
    assert {"psi_5", "psi_count", "psi_slot5", "psi_slot5_2", "psi_count_field", "duty_sma_a", "duty_2",
            "duty_slot2"} <= set(names)
    psi1 = db.get_message_by_name("TELEMETRY_PSI_0")
    assert [s.name for s in sorted(psi1.signals, key=lambda s: s.start)][:2] == ["psi_5", "psi_count"]


def test_two_limbs_that_would_share_an_identifier_are_refused(tmp_path):
    from proleg.errors import RobotFileError
    from proleg.robot import load_robot

    r1 = (Path(__file__).resolve().parents[1] / "robots" / "paper-r1.toml").read_text()
    path = tmp_path / "r.toml"
    path.write_text(r1.replace('name = "left"', 'name = "a-1"').replace('name = "right"', 'name = "a_1"'))
    with pytest.raises(RobotFileError, match=r"limb 'a_1': name: .*stays apart from limb 'a-1' .*'a_1' in recordings"):
        load_robot(path)


def test_dbc_refuses_to_write_over_its_own_robot_file(tmp_path, capsys):
    """`dbc -o X --robot X` replaced the robot file with DBC text (exit 0)."""
    from proleg.cli import main

    robot = tmp_path / "self.toml"
    text = (Path(__file__).resolve().parents[1] / "robots" / "paper-r1.toml").read_text()
    robot.write_text(text)
    link = tmp_path / "link.toml"
    link.symlink_to(robot)
    code = main(["dbc", "-o", str(link), "--robot", str(robot)])
    err = capsys.readouterr().err
    assert code == 2 and robot.read_text() == text
    assert err == f"proleg: error: dbc: -o {link} is the --robot file this command reads; " \
                  "write the output to another path\n"


def test_limbs_named_in_another_script_stay_apart(tmp_path):
    """Every character outside ASCII was '_' in an identifier, so any two names of one length in
    another script (a lab's 前 and 后, or é and è) were one identifier and the robot file was
    refused, though the docs take "any printable text". Each such character is now its code
    point: the names load, and their CAN signals and recording columns stay apart."""
    from types import SimpleNamespace as NS

    from proleg.names import identifier
    from proleg.robot import load_robot

    assert identifier("sma-left") == "sma_left" and identifier("a-1") == identifier("a_1") == "a_1"
    assert identifier("前") == "u524d" and identifier("后") == "u540e" and identifier("tête avant") == "tu00eate_avant"
    r1 = (Path(__file__).resolve().parents[1] / "robots" / "paper-r1.toml").read_text()
    for a, b in (("前", "后"), ("é", "è"), ("Ψ 1", "Φ 1")):
        path = tmp_path / "r.toml"
        path.write_text(r1.replace('name = "left"', f'name = "{a}"').replace('name = "right"', f'name = "{b}"'))
        assert [lb.name for lb in load_robot(path).limbs] == [a, b]
    db = build_database(robot=NS(limbs=[NS(name="前"), NS(name="后")], actuators=[NS(name="sma-a")]))
    names = {s.name for m in db.messages if m.name.startswith("TELEMETRY") for s in m.signals}
    assert {"psi_u524d", "psi_u540e"} <= names
