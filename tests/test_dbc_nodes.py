"""The generated DBC names each node once."""

from __future__ import annotations

import pytest

from proleg.errors import UsageError
from proleg.protocol.dbc import dbc_text


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
