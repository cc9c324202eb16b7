"""Where proleg's data directories are: boards/, firmware_templates/, robots/.

They live at the top of the source tree (design-card layout). ``PROLEG_HOME`` points
elsewhere, e.g. at an unpacked source tree next to an installed wheel.
"""

from __future__ import annotations

import os
from pathlib import Path


def home() -> Path:
    env = os.environ.get("PROLEG_HOME")
    return Path(env) if env else Path(__file__).resolve().parents[3]


def boards_dir() -> Path:
    return home() / "boards"


def templates_dir() -> Path:
    return home() / "firmware_templates"


def robots_dir() -> Path:
    return home() / "robots"
