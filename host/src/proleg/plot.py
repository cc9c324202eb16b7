"""``proleg plot FILE -o OUT.png``: ψ per limb against ψ*, robot state (measured and
target), SMA duty per channel and — when the recording has it — displacement, over firmware
time. matplotlib with the Agg backend; written to a temp file and renamed, so a failed plot
leaves no half-written output.
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

from .errors import LinkError
from .states import label
from .record import Recording, read_recording


def _psi_stars(rec: Recording) -> list[list[float]]:
    """``psi_star_deg`` header: limbs separated by ';', levels by ','."""
    text = rec.header.get("psi_star_deg", "")
    if not text:
        return []
    try:
        return [[float(v) for v in limb.split(",") if v.strip()] for limb in text.split(";")]
    except ValueError:
        return []


def _levels(rec: Recording) -> tuple[int, ...]:
    stars = _psi_stars(rec)
    if len(stars) == rec.limbs:
        return tuple(len(s) + 1 for s in stars)
    return (2,) * rec.limbs


def plot_recording(path: str | Path, out: str | Path, *, title: str | None = None) -> Path:
    """Plot recording ``path`` into ``out`` (format from its extension: png, svg, pdf)."""
    rec = read_recording(path)
    out = Path(out)
    ext = out.suffix.lower().lstrip(".")
    if ext not in ("png", "svg", "pdf"):
        raise LinkError(f"{out}: plot format must be .png, .svg or .pdf")
    directory = out.parent if str(out.parent) else Path(".")
    if not directory.is_dir():
        raise LinkError(f"{out}: directory {directory} does not exist")

    import matplotlib

    matplotlib.use("Agg", force=True)
    from matplotlib.figure import Figure

    panels = 4 if rec.displacement_mm is not None else 3
    fig = Figure(figsize=(10, 2.4 * panels), layout="constrained")
    axes = fig.subplots(panels, 1, sharex=True)
    t = rec.time_s
    colors = [f"C{i}" for i in range(max(rec.limbs, rec.channels))]

    ax = axes[0]
    stars = _psi_stars(rec)
    for i in range(rec.limbs):
        ax.plot(t, rec.psi_deg[:, i], color=colors[i], lw=1.2, label=f"ψ{i}")
        for s in stars[i] if i < len(stars) else []:
            ax.axhline(s, color=colors[i], ls="--", lw=0.8, label=f"ψ*{i} = {s:g}°")
    ax.set_ylabel("ψ (°)")
    ax.legend(loc="upper right", fontsize="small", ncols=2)

    ax = axes[1]
    levels = _levels(rec)
    ax.step(t, rec.target, where="post", color="0.6", lw=2.5, label="target")
    ax.step(t, rec.measured, where="post", color="C3", lw=1.2, label="measured")
    n_states = 1
    for k in levels:
        n_states *= k
    if n_states <= 16:
        ax.set_yticks(range(n_states), [label(s, levels) for s in range(n_states)])
    ax.set_ylabel("state")
    ax.legend(loc="upper right", fontsize="small")

    ax = axes[2]
    for j in range(rec.channels):
        ax.plot(t, rec.duty_pct[:, j], color=colors[j], lw=1.0, label=f"SMA {j}")
    ax.set_ylabel("duty (%)")
    ax.set_ylim(-2, 102)
    ax.legend(loc="upper right", fontsize="small")

    if rec.displacement_mm is not None:
        ax = axes[3]
        ax.plot(t, rec.displacement_mm, color="C2", lw=1.2)
        ax.set_ylabel("displacement (mm)")
    axes[-1].set_xlabel("firmware time (s)")
    robot = rec.header.get("robot", "")
    fig.suptitle(title or f"{robot} {rec.header.get('board', '')} — {rec.path.name}".strip())

    fd, tmp = tempfile.mkstemp(prefix=f".{out.name}.", suffix=f".{ext}", dir=directory)
    os.close(fd)
    try:
        fig.savefig(tmp, format=ext, dpi=110)
        os.replace(tmp, out)
    except OSError as e:
        raise LinkError(f"cannot write plot {out}: {e.strerror or e}") from None
    finally:
        Path(tmp).unlink(missing_ok=True)
    return out
