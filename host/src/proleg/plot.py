"""``proleg plot FILE -o OUT.png``: ψ per limb (by name) against ψ*, robot state (measured
and target), SMA duty per actuator (by name) and — when the recording has it — displacement,
over firmware time; faults, E-stops and injected faults as vertical markers on every panel. matplotlib with the Agg backend; written to a temp file and renamed, so a failed plot
leaves no half-written output. ``figure_problem``, ``new_figure`` and ``save_figure`` do that
for every figure proleg draws (``proleg gait --plot`` too); ``write_figure`` names the file
when the write fails.
"""

from __future__ import annotations

import logging
import re
from pathlib import Path
from typing import Any

import numpy as np

from .errors import LinkError, UsageError
from .outputs import check_writable, replacing
from .protocol.enums import Flag
from .record import Recording, read_recording
from .states import label, state_count

log = logging.getLogger("proleg")

#: the figure formats proleg writes (matplotlib's Agg backend), chosen by the file's suffix
FIGURE_FORMATS = ("png", "svg", "pdf")

#: the ``measured`` value of a frame whose state the board does not know (docs/data.md)
STATE_UNKNOWN_VALUE = 0xFFFF


def figure_problem(out: Path, what: str) -> str | None:
    """Why ``out`` is no figure's name (its suffix, a folder that does not exist: a usage
    mistake, exit 2), else None; ``LinkError`` (exit 1, ``outputs.check_writable``) when it
    names a place no figure can be written (a directory), as every output proleg writes says
    it. ``what``: the command and option, the message's prefix."""
    if out.suffix.lower().lstrip(".") not in FIGURE_FORMATS:
        return "the file must end in .png, .svg or .pdf"
    directory = out.parent  # "." for a bare file name
    if not directory.is_dir():
        return f"directory {directory} does not exist"
    check_writable(out, what)
    return None


def new_figure(width_in: float, height_in: float) -> Any:
    """A matplotlib ``Figure`` on the Agg backend (no display needed), constrained layout."""
    import matplotlib

    matplotlib.use("Agg", force=True)
    from matplotlib.figure import Figure

    return Figure(figsize=(width_in, height_in), layout="constrained")


def save_figure(fig: Any, out: Path, dpi: float | None = None) -> None:
    """Write ``fig`` to ``out`` in the format its suffix names, through a temporary file
    renamed over it (``proleg.outputs.replacing``: a symlink's target replaced, a FIFO or
    device written in place): a failed write leaves nothing. ``OSError`` propagates."""
    import warnings

    ext = out.suffix.lower().lstrip(".")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        with replacing(out, suffix=f".{ext}") as tmp:
            fig.savefig(tmp, format=ext, dpi=dpi)
    _say_missing_glyphs(out, caught)


#: matplotlib's warning for a character its font cannot draw (once per character and panel)
_MISSING_GLYPH = re.compile(r"Glyph (\d+) .*missing from font\(s\) (.+)\.$")


def _say_missing_glyphs(out: Path, caught: list) -> None:
    """A name the font cannot draw (a limb called 後ろ足) was one raw ``UserWarning`` with
    matplotlib's source line per character and panel: one line instead, naming the
    characters. Other warnings go on as they came."""
    import warnings

    chars: dict[str, None] = {}
    font = ""
    for w in caught:
        m = _MISSING_GLYPH.search(str(w.message))
        if m:
            chars[chr(int(m.group(1)))] = None
            font = m.group(2)
        else:
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    if chars:
        log.warning("warning: %s: the plot's font (%s) has no glyph for %s, drawn as boxes: give matplotlib a "
                    "font that has them (font.family in a matplotlibrc, e.g. Noto Sans CJK JP from Debian's "
                    "fonts-noto-cjk)", out, font, " ".join(chars))


def write_figure(fig: Any, out: Path, dpi: float | None = None) -> None:
    """``save_figure``, a failure (a full disk...) one ``LinkError`` naming ``out`` (exit 1)."""
    try:
        save_figure(fig, out, dpi)
    except OSError as e:
        raise LinkError(f"cannot write plot {out}: {e.strerror or e}") from None


def _levels(rec: Recording) -> tuple[int, ...]:
    stars = rec.meta.psi_star_deg
    if len(stars) == rec.limbs:
        return tuple(len(s) + 1 for s in stars)
    return (2,) * rec.limbs


#: The most state labels the state panel's axis carries.
MAX_STATE_TICKS = 16


def state_ticks(target: Any, measured: Any, n_states: int) -> list[int]:
    """The states the state panel labels: every one when there are ``MAX_STATE_TICKS`` or
    fewer, else those the recording visits (targets and measured), if as few; else none (the
    axis counts indices). A robot of more than 16 states (caterpillar-4: 36) was plotted by
    index, 0..35, where its labels (0220) are what a lab reads."""
    if n_states <= MAX_STATE_TICKS:
        return list(range(n_states))
    seen = {int(v) for v in np.concatenate([np.asarray(target, float), np.asarray(measured, float)])
            if np.isfinite(v) and 0 <= v < n_states}
    return sorted(seen) if len(seen) <= MAX_STATE_TICKS else []


def known_measured(rec: Recording) -> np.ndarray:
    """The measured state per frame as floats, NaN where the board did not know it (the
    ``STATE_UNKNOWN`` flag, and the 65535 a recording keeps there, docs/data.md): the state
    panel leaves a gap at boot instead of an axis that runs up to 65535."""
    unknown = ((rec.flags & int(Flag.STATE_UNKNOWN)) != 0) | (rec.measured == STATE_UNKNOWN_VALUE)
    return np.where(unknown, np.nan, rec.measured.astype(float))


def _markers(rec: Recording) -> list[tuple[float, str, str]]:
    """(firmware time, colour, label) of every fault, E-stop and injected fault (the reader has
    made every event's ``t_s`` a number or None)."""
    out = []
    for e in rec.events:
        t = e.get("t_s")
        if t is None:
            continue
        kind = e.get("kind", "")
        if kind == "FAULT":
            out.append((t, "red", str(e.get("text", "fault"))))
        elif kind == "ESTOP":
            out.append((t, "black", "E-stop"))
        elif kind == "INJECT":
            out.append((t, "darkorange", f"injected {e.get('text', '')}"))
    return out


def plot_recording(path: str | Path, out: str | Path, *, title: str | None = None) -> Path:
    """Plot recording ``path`` into ``out`` (format from its extension: png, svg, pdf)."""
    rec = read_recording(path)
    out = Path(out)
    problem = figure_problem(out, "plot -o")
    if problem:
        raise UsageError(f"{out}: {problem}")

    panels = 4 if rec.displacement_mm is not None else 3
    fig = new_figure(10, 2.4 * panels)
    axes = fig.subplots(panels, 1, sharex=True)
    t = rec.time_s
    colors = [f"C{i}" for i in range(max(rec.limbs, rec.channels))]

    ax = axes[0]
    stars = rec.meta.psi_star_deg
    limb_names = list(rec.meta.limb_names) or [f"limb #{i + 1}" for i in range(rec.limbs)]
    for i in range(rec.limbs):
        ax.plot(t, rec.psi_deg[:, i], color=colors[i], lw=1.2, label=f"ψ {limb_names[i]}")
        for s in stars[i] if i < len(stars) else []:
            ax.axhline(s, color=colors[i], ls="--", lw=0.8, label=f"ψ* {limb_names[i]} = {s:g}°")
    ax.set_ylabel("ψ (°)")
    ax.legend(loc="upper right", fontsize="small", ncols=2)

    ax = axes[1]
    levels = _levels(rec)
    ax.step(t, rec.target, where="post", color="0.6", lw=2.5, label="target")
    ax.step(t, known_measured(rec), where="post", color="C3", lw=1.2, label="measured")
    n_states = state_count(levels)
    shown = state_ticks(rec.target, known_measured(rec), n_states)
    if shown:
        ax.set_yticks(shown, [label(s, levels) for s in shown])
    ax.set_ylabel("state" if shown or n_states <= 1 else "state (index)")
    ax.legend(loc="upper right", fontsize="small")

    ax = axes[2]
    for j in range(rec.channels):
        name = rec.meta.channel_names[j] if j < len(rec.meta.channel_names) else f"channel {j}"
        ax.plot(t, rec.duty_pct[:, j], color=colors[j], lw=1.0, label=name)
    ax.set_ylabel("duty (%)")
    ax.set_ylim(-2, 102)
    ax.legend(loc="upper right", fontsize="small")

    if rec.displacement_mm is not None:
        ax = axes[3]
        ax.plot(t, rec.displacement_mm, color="C2", lw=1.2)
        ax.set_ylabel("displacement (mm)")
    seen: set[str] = set()
    for when, color, text in _markers(rec):
        for ax in axes:
            ax.axvline(when, color=color, ls=":", lw=1.2)
        if text not in seen:  # one label per distinct fault, on the top panel
            seen.add(text)
            axes[0].annotate(text, (when, 1.0), xycoords=("data", "axes fraction"), rotation=90, va="top",
                             ha="right", fontsize="x-small", color=color)
    axes[-1].set_xlabel("firmware time (s)")
    fig.suptitle(title or f"{rec.meta.robot} {rec.meta.board} — {rec.path.name}".strip())

    write_figure(fig, out, dpi=110)
    return out
