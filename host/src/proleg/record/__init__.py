"""Recording the decoded-message stream and reading it back, one writer and one reader per
format, chosen by the file's suffix (``registry``: ``.csv``, ``.jsonl``, ``.mcap``).

``Logger(path, meta)`` is a ``Listener`` writing every message; ``read_recording(path)``
reads any format back into a ``Recording``. ``UdpStreamer`` sends the same rows live to
PlotJuggler or Teleplot (``udp``). Field names and units: ``fields``; formats and
how pandas, PlotJuggler and Foxglove read them: docs/data.md.
"""

from .base import Reader, Recording, Writer
from .fields import RecordingMeta
from .jsonl_format import JsonlPrinter
from .registry import READERS, WRITERS, LogReader, Logger, check_suffix, read_recording
from .udp import UDP_FORMATS, UdpStreamer

__all__ = ["JsonlPrinter", "READERS", "WRITERS", "LogReader", "Logger", "Reader", "Recording", "RecordingMeta", "UDP_FORMATS", "UdpStreamer",
           "Writer",
           "check_suffix", "read_recording"]
