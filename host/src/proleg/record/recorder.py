"""Record every frame to CSV or JSON Lines (chosen by the file extension) and read it back.

Both formats start with a header (robot, board, firmware build id, gait-table hash, ...):
CSV as leading ``# key: value`` comment lines, JSON Lines as a first ``{"header": {...}}``
object. Every message is one line, flushed at once, so a killed console loses at most the
line being written.

CSV: one row per message; TELEMETRY fills ``seq … flags``, ``psi<i>_deg`` and
``duty<j>_pct`` (converted from 0.01° and permyriad), ``displacement_mm`` when the link knows
it (simulated robot); other messages fill ``detail`` with ``field=value`` pairs.
JSON Lines: ``{"t": host_s, "msg": NAME, <protocol fields in protocol units>, "truth": {...}}``.
"""

from __future__ import annotations

import csv
import io
import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, TextIO

import numpy as np

from ..errors import LinkError
from ..link.client import Received
from ..link.listeners import Listener

FORMATS = {".csv": "csv", ".jsonl": "jsonl", ".ndjson": "jsonl"}
TELEMETRY_SCALARS = ("seq", "time_ms", "measured", "target", "gait", "direction", "step", "flags")


def record_format(path: str | Path) -> str:
    suffix = Path(path).suffix.lower()
    try:
        return FORMATS[suffix]
    except KeyError:
        raise LinkError(f"{path}: unknown record format {suffix or '(none)'!r}; use .csv or .jsonl") from None


def csv_columns(limbs: int, channels: int) -> list[str]:
    return (["host_s", "msg", *TELEMETRY_SCALARS]
            + [f"psi{i}_deg" for i in range(limbs)]
            + [f"duty{j}_pct" for j in range(channels)]
            + ["displacement_mm", "detail"])


class Recorder(Listener):
    """A listener writing every message to ``path`` (CSV or JSON Lines by extension)."""

    def __init__(self, path: str | Path, header: dict[str, Any], *, limbs: int, channels: int):
        self.path = Path(path)
        self.format = record_format(self.path)
        self.limbs = limbs
        self.channels = channels
        self.lines = 0
        try:
            self._f: TextIO | None = open(self.path, "w", encoding="utf-8", newline="")
        except OSError as e:
            raise LinkError(f"cannot write record file {self.path}: {e.strerror or e}") from None
        self._header = {k: str(v) for k, v in header.items()}
        if self.format == "csv":
            self._columns = csv_columns(limbs, channels)
            self._index = {c: i for i, c in enumerate(self._columns)}
            for k, v in self._header.items():
                self._write_line(f"# {k}: {v}")
            self._write_csv_row(self._columns)
        else:
            self._write_line(json.dumps({"header": self._header}))

    def _write_line(self, line: str) -> None:
        assert self._f is not None
        self._f.write(line + "\n")
        self._f.flush()
        self.lines += 1

    def _write_csv_row(self, row: list[Any]) -> None:
        buf = io.StringIO()
        csv.writer(buf, lineterminator="\n").writerow(row)
        self._write_line(buf.getvalue()[:-1])

    def on_message(self, rx: Received) -> None:
        if self._f is None:
            return
        m = rx.message
        if self.format == "jsonl":
            obj: dict[str, Any] = {"t": round(rx.time, 6), "msg": m.name}
            for k, v in m.fields.items():
                obj[k] = list(v) if isinstance(v, tuple) else v
            if rx.truth:
                obj["truth"] = rx.truth
            self._write_line(json.dumps(obj, separators=(",", ":")))
            return
        row: list[Any] = [""] * len(self._columns)
        row[0] = f"{rx.time:.6f}"
        row[1] = m.name
        f = m.fields
        if m.name == "TELEMETRY":
            for k in TELEMETRY_SCALARS:
                row[self._index[k]] = f[k]
            for i, p in enumerate(f["psi"][: self.limbs]):
                row[self._index[f"psi{i}_deg"]] = f"{p / 100:.2f}"
            for j, d in enumerate(f["duty"][: self.channels]):
                row[self._index[f"duty{j}_pct"]] = f"{d / 100:.2f}"
            if "displacement_mm" in rx.truth:
                row[self._index["displacement_mm"]] = f"{rx.truth['displacement_mm']:.3f}"
        else:
            if "time_ms" in f:
                row[self._index["time_ms"]] = f["time_ms"]
            row[-1] = " ".join(f"{k}={v}" for k, v in f.items() if k != "time_ms")
        self._write_csv_row(row)

    def stop(self) -> None:
        f, self._f = self._f, None
        if f is not None:
            f.close()


# --------------------------------------------------------------------------- reading back
@dataclass
class Recording:
    """A recording's telemetry as arrays (firmware time in seconds, ψ in degrees, duty in %)."""

    path: Path
    header: dict[str, str]
    time_s: np.ndarray
    measured: np.ndarray
    target: np.ndarray
    step: np.ndarray
    flags: np.ndarray
    psi_deg: np.ndarray  # [frames, limbs]
    duty_pct: np.ndarray  # [frames, channels]
    displacement_mm: np.ndarray | None
    events: list[dict[str, Any]] = field(default_factory=list)

    @property
    def limbs(self) -> int:
        return int(self.psi_deg.shape[1])

    @property
    def channels(self) -> int:
        return int(self.duty_pct.shape[1])


def read_recording(path: str | Path) -> Recording:
    """Read a CSV or JSON Lines recording; ``LinkError`` names the file and line if it is bad."""
    p = Path(path)
    fmt = record_format(p)
    try:
        text = p.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise LinkError(f"record file {p} does not exist") from None
    except (OSError, UnicodeDecodeError) as e:
        raise LinkError(f"cannot read record file {p}: {getattr(e, 'strerror', None) or e}") from None
    rows: list[dict[str, Any]] = []
    events: list[dict[str, Any]] = []
    header: dict[str, str] = {}
    if fmt == "csv":
        lines = text.splitlines()
        k = 0
        while k < len(lines) and lines[k].startswith("#"):
            key, _, value = lines[k][1:].partition(":")
            header[key.strip()] = value.strip()
            k += 1
        reader = csv.DictReader(lines[k:])
        if not reader.fieldnames or "msg" not in reader.fieldnames:
            raise LinkError(f"{p}: not a proleg CSV recording (no 'msg' column after the header)")
        limbs = sum(1 for c in reader.fieldnames if c.startswith("psi") and c.endswith("_deg"))
        channels = sum(1 for c in reader.fieldnames if c.startswith("duty") and c.endswith("_pct"))
        for n, r in enumerate(reader, start=k + 2):
            if r.get("msg") == "TELEMETRY":
                try:
                    rows.append({
                        "time_s": int(r["time_ms"]) / 1000, "measured": int(r["measured"]),
                        "target": int(r["target"]), "step": int(r["step"]), "flags": int(r["flags"]),
                        "psi": [float(r[f"psi{i}_deg"]) for i in range(limbs)],
                        "duty": [float(r[f"duty{j}_pct"]) for j in range(channels)],
                        "x": float(r["displacement_mm"]) if r.get("displacement_mm") else math.nan,
                    })
                except (KeyError, TypeError, ValueError):
                    raise LinkError(f"{p}:{n}: malformed TELEMETRY row") from None
            elif r.get("msg"):
                events.append({"msg": r["msg"], "time_ms": r.get("time_ms"), "detail": r.get("detail", "")})
    else:
        for n, line in enumerate(text.splitlines(), start=1):
            if not line.strip():
                continue
            try:
                obj = json.loads(line)
            except json.JSONDecodeError:
                if n == len(text.splitlines()):
                    break  # a killed recorder's last, half-written line
                raise LinkError(f"{p}:{n}: not JSON") from None
            if not isinstance(obj, dict):
                raise LinkError(f"{p}:{n}: expected a JSON object")
            if "header" in obj and n == 1:
                header = {str(k): str(v) for k, v in obj["header"].items()}
                continue
            if obj.get("msg") == "TELEMETRY":
                try:
                    rows.append({
                        "time_s": int(obj["time_ms"]) / 1000, "measured": int(obj["measured"]),
                        "target": int(obj["target"]), "step": int(obj["step"]), "flags": int(obj["flags"]),
                        "psi": [v / 100 for v in obj["psi"]], "duty": [v / 100 for v in obj["duty"]],
                        "x": float(obj.get("truth", {}).get("displacement_mm", math.nan)),
                    })
                except (KeyError, TypeError, ValueError):
                    raise LinkError(f"{p}:{n}: malformed TELEMETRY line") from None
            elif "msg" in obj:
                events.append(obj)
    if not rows:
        raise LinkError(f"{p}: no TELEMETRY frames in the recording")
    limbs = max(len(r["psi"]) for r in rows)
    channels = max(len(r["duty"]) for r in rows)

    def pad(v: list[float], n: int) -> list[float]:
        return v + [math.nan] * (n - len(v))

    x = np.array([r["x"] for r in rows], dtype=float)
    return Recording(
        path=p, header=header,
        time_s=np.array([r["time_s"] for r in rows]),
        measured=np.array([r["measured"] for r in rows], dtype=np.int64),
        target=np.array([r["target"] for r in rows], dtype=np.int64),
        step=np.array([r["step"] for r in rows], dtype=np.int64),
        flags=np.array([r["flags"] for r in rows], dtype=np.int64),
        psi_deg=np.array([pad(r["psi"], limbs) for r in rows], dtype=float).reshape(len(rows), limbs),
        duty_pct=np.array([pad(r["duty"], channels) for r in rows], dtype=float).reshape(len(rows), channels),
        displacement_mm=None if np.all(np.isnan(x)) else x,
        events=events,
    )
