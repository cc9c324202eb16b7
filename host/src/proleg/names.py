"""How a limb's or an actuator's name appears where only identifiers go: CAN signal names in
the DBC file (``protocol.dbc``) and column names of recordings (``record.fields``).

``identifier("sma-left")`` → ``sma_left``. Two names that give the same identifier would
give one column or signal for two limbs, so the robot file refuses them (``robot_limbs._limbs``).
"""

from __future__ import annotations

import re


def identifier(name: str) -> str:
    """``name`` with every character other than ASCII letters, digits and ``_`` made ``_``."""
    return re.sub(r"[^0-9A-Za-z_]", "_", name)


def counted(n: int, noun: str) -> str:
    """``n`` and ``noun``, plural but for one: "1 cycle", "0 cycles", "3 faults"."""
    return f"{n} {noun}" if n == 1 else f"{n} {noun}s"
