"""MCAP for Foxglove: JSON-encoded messages on JSON-schema channels ``/proleg/telemetry``
(the CSV columns as fields) and ``/proleg/events``; the metadata as an MCAP metadata record
``proleg`` (string values; lists as JSON). Log times: the start time plus the host time
since the first message. Written with the ``mcap`` library; ``McapReader`` reads it back.

A killed recorder (SIGKILL, a crash, a power cut) writes no footer. The chunks are kept small
(``CHUNK_BYTES``) and each is in the file once it is complete, and the reader reads a file
without a footer up to its last whole record, with a warning, as the CSV and JSONL readers drop
a torn last line. (With the library's 1 MiB chunks, and a reader that needed the footer, a
console killed after minutes of recording left an MCAP that read back as nothing.)
"""

from __future__ import annotations

import json
import os
from datetime import datetime
from typing import Any, BinaryIO

from ..errors import RecordingError
from .base import Reader, Recording, Writer, log
from .fields import EVENT_COLUMNS, INTEGER_FIELDS, RecordingMeta, dumps

TELEMETRY_TOPIC = "/proleg/telemetry"
EVENTS_TOPIC = "/proleg/events"
#: bytes of messages per MCAP chunk, at most what a killed recorder loses (the library's
#: default, 1 MiB, is about an hour of telemetry at 50 Hz; 16 KiB, about a second, still
#: compresses several times)
CHUNK_BYTES = 16 * 1024


def _schema(columns: list[str], integers: tuple[str, ...], strings: tuple[str, ...] = ()) -> bytes:
    props = {c: {"type": "integer" if c in integers else "string" if c in strings else ["number", "null"]}
             for c in columns}
    return json.dumps({"type": "object", "properties": props}).encode()


class McapWriter(Writer):
    suffixes = (".mcap",)

    def open(self) -> None:
        from mcap.writer import Writer as _Mcap

        self._f: BinaryIO = self._create(self.path, "wb")
        self._w = _Mcap(self._f, chunk_size=CHUNK_BYTES)
        self._w.start(profile="", library="proleg")
        tel = self._w.register_schema(name="proleg.Telemetry", encoding="jsonschema",
                                      data=_schema(self.meta.columns(), INTEGER_FIELDS))
        ev = self._w.register_schema(name="proleg.Event", encoding="jsonschema",
                                     data=_schema(list(EVENT_COLUMNS), ("code", "detail"), ("msg", "kind", "text")))
        self._tel = self._w.register_channel(topic=TELEMETRY_TOPIC, message_encoding="json", schema_id=tel)
        self._ev = self._w.register_channel(topic=EVENTS_TOPIC, message_encoding="json", schema_id=ev)
        self._w.add_metadata("proleg", {k: v if isinstance(v, str) else json.dumps(v)
                                        for k, v in self.meta.as_dict().items()})
        try:
            self._t0_ns = int(datetime.fromisoformat(self.meta.start_utc.replace("Z", "+00:00")).timestamp() * 1e9)
        except ValueError:
            self._t0_ns = 0
        self._host0: float | None = None

    def _log(self, channel: int, row: dict[str, Any]) -> None:
        if self._host0 is None:
            self._host0 = row["t_host_s"]
        t = self._t0_ns + round((row["t_host_s"] - self._host0) * 1e9)
        self._w.add_message(channel_id=channel, log_time=t, publish_time=t, data=dumps(row).encode())
        self._f.flush()  # a chunk the library has just completed goes to the file, not our buffer

    def write_telemetry(self, row: dict[str, Any]) -> None:
        self._log(self._tel, row)

    def write_event(self, row: dict[str, Any]) -> None:
        self._log(self._ev, row)

    def close(self) -> None:
        self._w.finish()
        self._f.close()


class McapReader(Reader):
    suffixes = (".mcap",)

    def read(self) -> Recording:
        p = self.path
        try:
            f = open(p, "rb")
        except FileNotFoundError:
            raise RecordingError(f"record file {p} does not exist") from None
        except OSError as e:
            raise RecordingError(f"cannot read record file {p}: {e.strerror or e}") from None
        with f:
            meta, rows, events = self._records(f)
        if meta is None:
            raise RecordingError(f"{p}: not a proleg MCAP recording (no 'proleg' metadata)")
        return Recording.from_rows(p, meta, rows, events)

    def _records(self, f: BinaryIO) -> tuple[RecordingMeta | None, list, list]:
        """The metadata, the telemetry and the events, each message with its number."""
        import struct

        from mcap.exceptions import EndOfFile, McapError
        from mcap.reader import FOOTER_SIZE, make_reader
        from mcap.stream_reader import MAGIC_SIZE

        p = self.path
        rows: list[tuple[str, dict[str, Any]]] = []
        events: list[tuple[str, dict[str, Any]]] = []
        meta: RecordingMeta | None = None
        try:
            if os.fstat(f.fileno()).st_size < 2 * MAGIC_SIZE + FOOTER_SIZE:
                # the index is read from the footer, seeking back from the end: a file shorter
                # than that (a recorder killed as it began) failed the seek, an OSError that
                # said "cannot write: Invalid argument" (exit 1) for a recording that does not load
                raise EndOfFile()
            reader = make_reader(f)
            for record in reader.iter_metadata():
                if record.name == "proleg":
                    meta = _meta(p, record.metadata)
            for n, (_schema, channel, message) in enumerate(reader.iter_messages(), start=1):
                self._message(n, channel, message, rows, events)
        except (EndOfFile, EOFError, struct.error):
            return self._cut_short(f, "it ends early: a run cut short, a full disk, or not MCAP")
        except McapError as e:  # a damaged record, or where a killed recorder left no footer, none
            return self._cut_short(f, str(e) or e.__class__.__name__)
        except _undecompressable() as e:  # a chunk whose compressed bytes were damaged
            return self._cut_short(f, f"a damaged chunk: {e or e.__class__.__name__}")
        except ValueError as e:  # JSON that is not
            raise RecordingError(f"{p}: not a readable MCAP recording ({e or e.__class__.__name__})") from None
        return meta, rows, events

    def _message(self, n: int, channel: Any, message: Any, rows: list, events: list) -> None:
        row = json.loads(message.data)
        if not isinstance(row, dict):
            raise RecordingError(f"{self.path}: message {n}: expected a JSON object")
        (rows if channel.topic == TELEMETRY_TOPIC else events).append((f"{self.path}: message {n}", row))

    def _cut_short(self, f: BinaryIO, why: str) -> tuple[RecordingMeta | None, list, list]:
        """A file without its footer (a recorder killed before it finished the file): its
        records read in order from the start, up to the last one written whole; ``why`` the
        index could not be read (the error when nothing can be read so either)."""
        import struct

        from mcap.exceptions import EndOfFile, McapError
        from mcap.records import Channel, Message, Metadata
        from mcap.stream_reader import StreamReader

        p = self.path
        rows: list[tuple[str, dict[str, Any]]] = []
        events: list[tuple[str, dict[str, Any]]] = []
        meta: RecordingMeta | None = None
        channels: dict[int, Any] = {}
        n = 0
        f.seek(0)
        try:
            for record in StreamReader(f, record_size_limit=2**28).records:
                if isinstance(record, Metadata) and record.name == "proleg":
                    meta = _meta(p, record.metadata)
                elif isinstance(record, Channel):
                    channels[record.id] = record
                elif isinstance(record, Message) and record.channel_id in channels:
                    n += 1
                    self._message(n, channels[record.channel_id], record, rows, events)
        except (EndOfFile, EOFError, struct.error, McapError, *_undecompressable()):
            pass  # the torn end (or a damaged chunk): what came before it is kept
        except ValueError as e:  # JSON that is not
            raise RecordingError(f"{p}: not a readable MCAP recording ({e or e.__class__.__name__})") from None
        if meta is not None and not rows and not _ends_with_magic(f):
            # a whole header and metadata, then no whole message: not garbage, the first chunk never came
            # whole (the footer was read from the metadata's last bytes: "unknown (opcode 34) record")
            raise RecordingError(f"{p}: not a readable MCAP recording (no telemetry in it: it ends, without a footer, "
                                 "before its first chunk was written whole: a recorder killed in its first second "
                                 "or so)")
        if meta is None or not rows:
            raise RecordingError(f"{p}: not a readable MCAP recording ({why})")
        if _ends_with_magic(f):  # finished, its footer written: damaged after, not cut short
            log.warning("warning: %s: not readable past message %d (%s): read up to it", p, n, why)
        else:
            log.warning("warning: %s: no MCAP footer: read up to message %d, the last whole one (the recording "
                        "was cut short while writing it)", p, n)
        return meta, rows, events


def _undecompressable() -> tuple[type[BaseException], ...]:
    """What the mcap library's decompressors raise on a chunk whose compressed bytes are damaged
    (a disk or copy error, a power cut's garbage): zstandard's ZstdError, lz4's RuntimeError.
    Neither is an McapError: such a file was a traceback, not one line or the messages before it."""
    errors: list[type[BaseException]] = [RuntimeError]  # lz4.frame.decompress
    try:
        from zstandard import ZstdError

        errors.append(ZstdError)
    except ImportError:
        pass
    return tuple(errors)


def _ends_with_magic(f: BinaryIO) -> bool:
    """``f`` ends with MCAP's magic, as a file whose writer finished it (footer and all) does."""
    try:
        f.seek(-8, 2)
        return f.read(8) == b"\x89MCAP0\r\n"
    except OSError:
        return False


def _meta(path: Any, metadata: dict[str, str]) -> RecordingMeta:
    try:
        return RecordingMeta.from_dict({k: v if k in ("robot", "board", "start_utc") else json.loads(v)
                                        for k, v in metadata.items()})
    except ValueError as e:
        raise RecordingError(f"{path}: not proleg recording metadata ({e})") from None
