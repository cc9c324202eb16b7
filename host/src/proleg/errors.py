"""Exceptions at proleg's package boundaries.

Every user mistake surfaces as a ``ProlegError`` whose message is one complete line:
where (file, field or line) and what was expected. The CLI prints that line and exits 2
(usage), or 1 for a ``LinkError`` (the robot, the link or an output failed);
anything else reaching the CLI is a bug and keeps its traceback.
"""


class ProlegError(Exception):
    """Base of every error a user can cause."""


class RobotFileError(ProlegError):
    """A robot file (or the transition table it names) is malformed."""


class GaitError(ProlegError):
    """A gait request cannot be answered (invalid sequence, unsupported objective...)."""


class BoardError(ProlegError):
    """A board file is malformed or unknown."""


class BuildError(ProlegError):
    """Rendering, compiling or flashing firmware failed."""


class ProtocolError(ProlegError):
    """A frame or message violates the link protocol."""


class SimError(ProlegError):
    """The simulated board or plant was misused."""


class LinkError(ProlegError):
    """A link to a robot (serial, CAN, simulated) failed or timed out."""


class RecordingError(ProlegError):
    """A recording given to read back (``proleg plot``) is missing or malformed: a bad input
    file, exit 2 like a bad robot file. Writing one that fails is a ``LinkError`` (exit 1)."""


class LearnError(ProlegError):
    """A learn option or file the user got wrong (one line, exit code 2)."""


class Interrupted(KeyboardInterrupt):
    """Ctrl-C, saying in one line what was kept ("interrupted; nothing built"): the CLI prints
    ``proleg: `` and the message and exits 130. A ``KeyboardInterrupt``, so that whatever
    stops a run on Ctrl-C (``finally`` blocks, ``except KeyboardInterrupt``) still runs."""


class UsageError(ProlegError):
    """An option's value the command cannot take (an output's file type, an endpoint, a node
    id): exit 2, like any other usage mistake."""


class WorkerLost(ProlegError):
    """A worker process of a command that runs its work in several (``proleg check --jobs``,
    ``--measure-matrix --hold-range --jobs``) died without an answer: killed by the system
    (out of memory) or by a signal. Exit 1, a failure: ``multiprocessing.Pool`` waited for the
    lost answer for ever."""

