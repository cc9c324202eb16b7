"""The one lock on a serial device that every proleg tool takes before using it.

A console, ``run``, ``learn``, ``calibrate``, ``load-gait`` or ``set-param`` (``SerialLink``) and ``proleg flash`` (around the
flash tool: avrdude and stm32flash take no lock of their own) each hold an exclusive
``flock`` on the device while they use it, taken before anything touches the port (no
termios change, no byte written). A second one is refused with one line naming the port,
who holds it (from ``/proc/locks``, where it can be read) and what to do; it never shares
the port: a flash under a running console breaks both (the console reads avrdude's bytes,
avrdude loses the bootloader's replies). It is the lock pyserial's ``exclusive=True`` takes,
so a program that opens the port that way is refused as well.

Only a terminal device is locked: a socket:// or loop:// URL, a path that is not there (the
opener then says so) or a file that is no terminal (``/dev/null``) is used as it is. Without
``fcntl`` (Windows) the system already opens a COM port for one program only.
"""

from __future__ import annotations

import errno
import os
from collections.abc import Iterator
from contextlib import contextmanager

from .errors import LinkError

try:
    import fcntl
except ImportError:  # pragma: no cover (Windows)
    fcntl = None  # type: ignore[assignment]

#: the proleg commands that may hold a port, as a holder's command line names them
_COMMANDS = ("flash", "console", "run", "learn", "calibrate", "plot", "load-gait", "set-param")


class PortBusy(LinkError):
    """The serial device is held by another program (exit 1, like any link failure)."""


def is_local_device(port: str) -> bool:
    return "://" not in port


class PortLock:
    """An exclusive lock on ``port`` held until ``release`` (a ``PortBusy`` if another holds it)."""

    def __init__(self, port: str, *, doing: str = "open serial port"):
        self.port = port
        self._fd: int | None = None
        if fcntl is None or not is_local_device(port):
            return
        try:
            fd = os.open(port, os.O_RDWR | os.O_NOCTTY | os.O_NONBLOCK | getattr(os, "O_CLOEXEC", 0))
        except OSError:
            return  # not there, no permission: whoever opens it next says so in its own words
        try:
            if not os.isatty(fd):
                os.close(fd)
                return
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError as e:
            os.close(fd)
            if e.errno in (errno.EWOULDBLOCK, errno.EAGAIN):
                raise PortBusy(busy_message(port, doing)) from None
            return  # a device that takes no lock (flock unsupported): used unlocked
        self._fd = fd

    @property
    def held(self) -> bool:
        return self._fd is not None

    def release(self) -> None:
        fd, self._fd = self._fd, None
        if fd is not None:
            try:
                os.close(fd)  # closing the descriptor drops the flock
            except OSError:
                pass

    def __enter__(self) -> PortLock:
        return self

    def __exit__(self, *exc: object) -> None:
        self.release()


@contextmanager
def hold_port(port: str | None, *, doing: str = "open serial port") -> Iterator[PortLock | None]:
    """``port`` locked for the block; ``None`` (no lock) for no port."""
    if not port:
        yield None
        return
    lock = PortLock(port, doing=doing)
    try:
        yield lock
    finally:
        lock.release()


def refuse_if_held(port: str, *, doing: str = "open serial port") -> None:
    """``PortBusy`` when another process holds ``port``'s lock, read from ``/proc/locks``
    without opening the device: opening a USB serial port raises DTR, and an Arduino resets.
    ``proleg flash``'s check before building opened and closed the port for it, one reset of
    the Nano more than avrdude's own (and, on the emulated Nano, a third open now and then).
    Where ``/proc/locks`` cannot be read nothing is checked here: the lock taken around the
    flash tool still refuses."""
    if fcntl is None or not is_local_device(port):
        return
    if lock_holder(port) is not None:
        raise PortBusy(busy_message(port, doing))


def busy_message(port: str, doing: str = "open serial port") -> str:
    """One line: the port is in use, by whom if that can be read, and what to do."""
    holder = lock_holder(port)
    if holder is None:
        who, then = "another program has it open (a proleg console, run, learn or calibrate?)", "close it first"
    elif holder[1] == "flash":
        who, then = f"proleg flash is writing firmware through it (pid {holder[0]})", "wait for the flash to end"
    elif holder[1]:
        who = f"a proleg {holder[1]} has it open (pid {holder[0]})"
        then = "close the console first" if holder[1] == "console" else f"stop the proleg {holder[1]} first"
    else:
        who, then = f"another program has it open ({holder[2]}, pid {holder[0]})", "close it first"
    return f"cannot {doing} {port}: {who}; {then}"


def lock_holder(port: str) -> tuple[int, str, str] | None:
    """``(pid, proleg command or '', program name)`` of the process holding ``port``'s flock,
    read from ``/proc/locks`` (Linux); ``None`` where that cannot be read."""
    try:
        st = os.stat(port)
        with open("/proc/locks", encoding="ascii", errors="replace") as f:
            lines = f.read().splitlines()
    except OSError:
        return None
    ident = f"{os.major(st.st_dev):02x}:{os.minor(st.st_dev):02x}:{st.st_ino}"
    for line in lines:
        fields = line.split()
        # "1: FLOCK  ADVISORY  WRITE 1234 00:1a:3 0 EOF" ("->" marks a waiter)
        if len(fields) >= 6 and fields[1] == "FLOCK" and fields[5] == ident and fields[4].isdigit():
            pid = int(fields[4])
            if pid == os.getpid():
                continue
            return (pid, *_describe(pid))
    return None


def _describe(pid: int) -> tuple[str, str]:
    try:
        with open(f"/proc/{pid}/cmdline", "rb") as f:
            argv = [a.decode(errors="replace") for a in f.read().split(b"\0") if a]
    except OSError:
        argv = []
    program = os.path.basename(argv[0]) if argv else "unknown program"
    for i, arg in enumerate(argv):
        module = argv[i + 1] if arg == "-m" and i + 1 < len(argv) else ""
        if arg == "proleg" or arg.endswith("/proleg") or module == "proleg" or module.startswith("proleg."):
            for later in argv[i + 1:]:
                if later in _COMMANDS:
                    return later, program
            return "", program
    return "", program
