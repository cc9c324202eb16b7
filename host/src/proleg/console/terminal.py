"""The console UI's terminal: writes that outlive a closed window (``TerminalGone``) and
proleg's log lines shown in the UI instead of written under it (``UiLog``)."""

from __future__ import annotations

import logging
from collections.abc import Callable
from typing import Any


class TerminalGone:
    """The UI's terminal file, whose writes and flushes outlive the terminal: once its window is
    closed (SIGHUP) a write fails with EIO, and that ended textual's writer thread; its queue
    then filled and the next screen update blocked the console for ever, its heartbeat keeping
    the gait running. Now such writes go nowhere, so the console gets to its leaving STOP."""

    def __init__(self, file: Any) -> None:
        self._file = file

    def write(self, text: str) -> int:
        try:
            return self._file.write(text)
        except (OSError, ValueError):  # EIO: the terminal is gone; ValueError: the file was closed
            return len(text)

    def flush(self) -> None:
        try:
            self._file.flush()
        except (OSError, ValueError):
            pass

    def __getattr__(self, name: str) -> Any:
        return getattr(self._file, name)


class UiLog(logging.Handler):
    """While the UI is up, proleg's log lines (a recording that hit a full disk, on the Notifier's
    thread) go to the events panel and the status line (``say``), a warning to a notification as
    well (``warn``): the CLI's handler wrote them to the terminal under textual's screen,
    scribbling over it until the next redraw. ``install`` puts it in place of the ``proleg``
    logger's handlers, ``uninstall`` puts those back, and ``replay`` gives them every line said
    meanwhile, once the UI has left the terminal (said on the alternate screen they would vanish
    with it)."""

    def __init__(self, say: Callable[[str], None], warn: Callable[[str], None] | None = None) -> None:
        super().__init__()
        self.say = say
        self.warn = warn
        self.held: list[logging.LogRecord] = []
        self._saved: tuple[list[logging.Handler], bool] | None = None

    def emit(self, record: logging.LogRecord) -> None:
        try:
            self.held.append(record)
            text = record.getMessage()
            self.say(text)
            if self.warn is not None and record.levelno >= logging.WARNING:
                self.warn(text)  # a notification too: the status line is one line, soon overwritten
        except Exception:  # a log line never breaks the thread that logged it
            self.handleError(record)

    def install(self) -> None:
        logger = logging.getLogger("proleg")
        if self._saved is None:
            self._saved = (logger.handlers[:], logger.propagate)
            logger.handlers[:] = [self]
            logger.propagate = False

    def uninstall(self) -> None:
        logger = logging.getLogger("proleg")
        if self._saved is not None:
            logger.handlers[:], logger.propagate = self._saved
            self._saved = None

    def replay(self) -> None:
        self.uninstall()
        held, self.held = self.held, []
        logger = logging.getLogger("proleg")
        for record in held:
            logger.handle(record)  # the CLI's stderr handler (or logging's last resort) says it now
