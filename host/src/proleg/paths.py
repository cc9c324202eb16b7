"""Where proleg's data directories are: boards/, firmware_templates/, robots/.

An installed wheel carries them inside the package (``proleg/_data/``, copied there by
``setup.py`` when the wheel is built) and finds them with ``importlib.resources``; a
source checkout (or an editable install) uses the directories at the top of the tree.
``PROLEG_HOME`` points elsewhere, e.g. at a lab's own tree of boards and templates.
``cache_dir`` is where builds proleg makes for itself (host-sim firmware, emulator helpers)
are kept: ``$PROLEG_CACHE``, else ``$XDG_CACHE_HOME/proleg`` (default ``~/.cache/proleg``).
"""

from __future__ import annotations

import os
import stat
from importlib import resources
from pathlib import Path

#: The data directories a home holds; a wheel carries exactly these.
DATA_DIRS = ("boards", "firmware_templates", "robots")


def _packaged() -> Path | None:
    data = resources.files("proleg") / "_data"
    # a wheel installs as plain files, so the traversable is a real directory
    if isinstance(data, Path) and (data / "boards").is_dir():
        return data
    return None


def home() -> Path:
    """The directory holding ``boards/``, ``firmware_templates/`` and ``robots/``."""
    env = os.environ.get("PROLEG_HOME")
    if env:
        return Path(env)
    return _packaged() or Path(__file__).resolve().parents[3]


def not_a_regular_file(path: str | Path) -> str | None:
    """Why ``path`` cannot be read whole as an input file: "not a regular file (a device, pipe or
    socket)" when it is neither a file nor a directory, else None (a directory or a missing
    file is said by the read itself, in its words). A device is read to an end that never comes:
    a board file, transition CSV, recording or track named /dev/zero (or a link to it) filled
    the memory until the kernel killed the process."""
    try:
        mode = os.stat(path).st_mode
    except OSError:
        return None
    if stat.S_ISREG(mode) or stat.S_ISDIR(mode):
        return None
    return "not a regular file (a device, pipe or socket)"


def boards_dir() -> Path:
    return home() / "boards"


def templates_dir() -> Path:
    return home() / "firmware_templates"


def robots_dir() -> Path:
    return home() / "robots"


def display_path(path: str | Path) -> str:
    """A path as generated files and build records show it: relative to ``home()`` when it is
    inside it (``robots/paper-r1.toml``), else absolute. Keeps renders byte-identical across
    checkouts."""
    p = Path(path).resolve()
    try:
        return str(p.relative_to(home()))
    except ValueError:
        return str(p)


def cache_dir(name: str = "") -> Path:
    """``$PROLEG_CACHE/<name>`` (else ``$XDG_CACHE_HOME/proleg/<name>``, ``~/.cache`` when unset):
    where the simulator and the emulators cache what they build (``sim``, ``avr-emu``...)."""
    root = os.environ.get("PROLEG_CACHE") or os.path.join(
        os.environ.get("XDG_CACHE_HOME", os.path.expanduser("~/.cache")), "proleg"
    )
    return Path(root) / name


def bundled_robots() -> list[str]:
    """Names of the example robot files that come with proleg (``paper-r1``, ...)."""
    return sorted(p.stem for p in robots_dir().glob("*.toml"))


def resolve_robot(text: str) -> Path:
    """A robot file path as given, or the bundled example of that name.

    ``paper-r1`` (no such file in the working directory) means ``robots/paper-r1.toml``
    of this installation; anything that exists as a path is taken as it is.
    """
    path = Path(text)
    if path.exists() or path.suffix == ".toml" or os.sep in text:
        return path
    bundled = robots_dir() / f"{text}.toml"
    return bundled if bundled.exists() else path


def as_if_created(path: str | Path, directory: bool = False) -> None:
    """Give a file made by ``tempfile.mkstemp`` / ``mkdtemp`` (mode 0600 / 0700) the mode a
    plain ``open``/``mkdir`` would have given it under the process's umask, before it is
    renamed into place: an output a user asked for is readable as their other files are."""
    mask = os.umask(0)
    os.umask(mask)
    os.chmod(path, (0o777 if directory else 0o666) & ~mask)
