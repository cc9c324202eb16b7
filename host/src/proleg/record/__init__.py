"""Recording the decoded-message stream to a file and reading it back.

``Recorder`` is a ``Listener`` (``proleg.link.listeners``) writing every message; the file's
suffix picks the format (``record_format``: ``.csv`` or ``.jsonl``). ``read_recording`` reads
either back into a ``Recording``.
"""

from .recorder import Recorder, Recording, csv_columns, read_recording, record_format

__all__ = ["Recorder", "Recording", "csv_columns", "read_recording", "record_format"]
