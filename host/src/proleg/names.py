"""How a limb's or an actuator's name appears where only identifiers go: CAN signal names in
the DBC file (``protocol.dbc``) and column names of recordings (``record.fields``); and how
wide it prints in a table's column (``padded``).

``identifier("sma-left")`` → ``sma_left``. Two names that give the same identifier would
give one column or signal for two limbs, so the robot file refuses them (``robot_limbs._limbs``).
"""

from __future__ import annotations

import re
import unicodedata


def identifier(name: str) -> str:
    """``name`` as an identifier: ASCII letters, digits and ``_`` kept, every other ASCII
    character ``_`` (``sma-left`` → ``sma_left``), and every character beyond ASCII its code
    point (``前`` → ``u524d``, ``tête`` → ``tu00eate``). Making those ``_`` too gave any two
    names of one length in another script (前 and 后, é and è) the same identifier, and the
    robot file was refused."""
    return "".join(c if c.isascii() and (c.isalnum() or c == "_") else "_" if c.isascii() else f"u{ord(c):04x}"
                   for c in name)


def legacy_identifier(name: str) -> str:
    """What ``identifier`` gave before it kept other scripts' characters (every character
    other than ASCII letters, digits and ``_`` made ``_``): the column names of recordings
    made then, which ``record`` still reads."""
    return re.sub(r"[^0-9A-Za-z_]", "_", name)


def display_width(text: str) -> int:
    """The columns ``text`` takes on a terminal: two for a wide character (East Asian wide or
    fullwidth, ``前``), none for a combining mark, one for any other. ``len`` counts
    characters, and a table padded by it put the columns after ``前`` one place to the right."""
    return sum(0 if unicodedata.combining(c) else 2 if unicodedata.east_asian_width(c) in "WF" else 1
               for c in text)


def padded(text: str, width: int) -> str:
    """``text`` left-aligned in ``width`` terminal columns (``display_width``)."""
    return text + " " * max(0, width - display_width(text))


def counted(n: int, noun: str, plural: str | None = None, spec: str = "") -> str:
    """``n`` and ``noun``, plural but for one: "1 cycle", "0 cycles", "3 faults", "1 IMU",
    "2 channel switches", "3 entries". The plural is the English regular one (``-es`` after
    s, x, z, ch and sh; ``-ies`` for a consonant and y) unless ``plural`` gives it; ``spec``
    formats the number (``","``: "9,990 more ties")."""
    return f"{n:{spec}} {noun if n == 1 else plural or _plural(noun)}"


def _plural(noun: str) -> str:
    if noun.endswith(("s", "x", "z", "ch", "sh")):
        return noun + "es"
    if len(noun) > 1 and noun.endswith("y") and noun[-2].lower() not in "aeiou":
        return noun[:-1] + "ies"
    return noun + "s"
