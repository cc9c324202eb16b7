"""The gait half of the firmware's rendered tables (``firmware/render.py`` renders the rest):
every compiled gait's steps (+x first, then −x), the entry path from rest into each gait,
the allowed-transition table (a bitmap up to BITMAP_MAX_STATES states, else a sorted key
list), the gait-table hash the firmware reports, the build-time fallback gaits for a lost
actuator and the gait library. ``gait_part`` fills the ``GaitPart`` of a ``RenderContext``;
``BuildError`` when the robot's gaits do not fit the firmware's tables."""

from __future__ import annotations

import hashlib
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from ..errors import BuildError

#: Largest state space whose allowed-transition table is a bitmap (n*n bits); above, a sorted key list.
BITMAP_MAX_STATES = 64


@dataclass(frozen=True)
class GaitPart:
    selection: str  # how the gaits were chosen (GaitSelection.describe), for the headers
    rows: list[tuple[int, str, tuple[int, ...]]]
    n_px: int
    n_mx: int
    steps: list[int]
    gait_first: list[int]
    gait_len: list[int]
    use_bitmap: bool
    bitmap: list[str]
    edges: list[str]
    n_transitions: int
    labels: list[str]
    gait_hash: str
    entry_steps: list[int]  # every gait's entry path from rest (rest and join state excluded)
    entry_first: list[int]
    entry_len: list[int]
    entry_join: list[int]  # the gait step the entry path joins
    fallback: bool  # build-time fallback gaits for a lost actuator (core/limbmap.c)
    fb_maps: list[list[int]]  # per (lost actuator, direction): actuator index per limb to run with
    fb_steps: list[int]  # every fallback gait's steps (open walk), concatenated
    fb_first: list[int]  # per (lost actuator, direction +x/-x): first step in fb_steps
    fb_len: list[int]  # per (lost actuator, direction): steps, 0 = no fallback
    fb_notes: list[str]  # one comment line per fallback
    library: list[str] = field(default_factory=list)  # the gait library, one line per entry (header comments)
    library_selection: str = ""  # the planar question the library answers (LibrarySpec.describe)


def gait_table_rows(gaits_by_direction: Mapping[str, Sequence[Any]]) -> list[tuple[int, str, tuple[int, ...]]]:
    """(direction code, direction, open step list) of every compiled gait: +x first, then -x."""
    rows = []
    for code, d in ((0, "+x"), (1, "-x")):
        for g in gaits_by_direction.get(d, ()) or ():
            st = tuple(int(s) for s in g.states)
            if len(st) >= 2 and st[-1] == st[0]:
                st = st[:-1]
            rows.append((code, d, st))
    return rows


def _step_table(robot: Any, rows: list[tuple[int, str, tuple[int, ...]]]) -> tuple[list[int], list[int], list[int]]:
    """(steps of every gait concatenated, first step of each gait, length of each gait)."""
    steps: list[int] = []
    first, length = [], []
    for _, _, st in rows:
        first.append(len(steps))
        length.append(len(st))
        steps.extend(st)
    if len(steps) > 0xFFFF:
        raise BuildError(f"{robot.where}: gait table of {len(steps)} steps, at most 65535")
    return steps, first, length


def _transition_table(src: list[int], dst: list[int], n_states: int) -> tuple[bool, list[str], list[str]]:
    """(use_bitmap, bitmap bytes, sorted src*n+dst keys): a bitmap for small state spaces."""
    if n_states <= BITMAP_MAX_STATES:
        bitmap = [0] * ((n_states * n_states + 7) // 8)
        for a, b in zip(src, dst):
            k = a * n_states + b
            bitmap[k >> 3] |= 1 << (k & 7)
        return True, [f"0x{b:02X}" for b in bitmap], []
    return False, [], [f"{e}UL" for e in sorted(a * n_states + b for a, b in zip(src, dst))]


def entry_tables(robot: Any, rows: list[tuple[int, str, tuple[int, ...]]]
                 ) -> tuple[list[int], list[int], list[int], list[int]]:
    """Per gait, the way in from rest (proleg.gait.feasibility.entry_path): the states
    between rest and the join state, concatenated, their offset and count, and the join
    step. A gait with no way in keeps the old start (step 0, no entry states); the build
    refuses such a gait 0 (build.check_gaits)."""
    from ..errors import GaitError
    from ..gait.feasibility import entry_path

    steps: list[int] = []
    first, length, join = [], [], []
    for _, _, st in rows:
        first.append(len(steps))
        try:
            path = entry_path(robot, st)
        except GaitError:
            length.append(0)
            join.append(0)
            continue
        inner = list(path.states[1:-1])
        steps.extend(inner)
        length.append(len(inner))
        join.append(path.gait_step)
    return steps, first, length, join


def _gait_hash(n_states: int, rows: list[tuple[int, str, tuple[int, ...]]], src: list[int], dst: list[int],
               entry: tuple[list[int], list[int], list[int], list[int]] | None = None) -> int:
    """Covers exactly what gait_table.c carries: steps, gaits, entry paths, allowed transitions."""
    gh = hashlib.sha256()
    gh.update(f"states={n_states};".encode())
    for code, _, st in rows:
        gh.update(f"g{code}:{','.join(map(str, st))};".encode())
    if entry is not None and (entry[0] or any(entry[3])):  # gaits entered from rest off their step 0
        gh.update(("e:" + ";".join(",".join(map(str, part)) for part in entry)).encode())
    gh.update(("t:" + ",".join(f"{a}>{b}" for a, b in zip(src, dst))).encode())
    return int.from_bytes(gh.digest()[:4], "big")


def _selection_text(gaits_by_direction: Mapping[str, Sequence[Any]]) -> str:
    selection = getattr(gaits_by_direction, "selection", None)
    return selection.describe() if selection is not None else "gaits given directly (no selection named)"


def gait_part(robot: Any, gaits_by_direction: Mapping[str, Sequence[Any]], n_states: int) -> GaitPart:
    rows = gait_table_rows(gaits_by_direction)
    n_px = sum(1 for r in rows if r[0] == 0)
    n_mx = len(rows) - n_px
    if n_px > 255 or n_mx > 255:
        raise BuildError(f"{robot.where}: more than 255 optimal gaits in one direction")
    steps, first, length = _step_table(robot, rows)
    table = robot.transitions
    src = [int(x) for x in table.src]
    dst = [int(x) for x in table.dst]
    use_bitmap, bitmap, edges = _transition_table(src, dst, n_states)
    entry = entry_tables(robot, rows)
    fb = _fallback_part(robot)
    ghash = _gait_hash(n_states, rows, src, dst, entry)
    if fb["fallback"]:  # the hash covers the fallback tables too
        text = f"{ghash}|{fb['fb_maps']}|{fb['fb_steps']}|{fb['fb_first']}|{fb['fb_len']}"
        ghash = int.from_bytes(hashlib.sha256(text.encode()).digest()[:4], "big")
    return GaitPart(
        selection=_selection_text(gaits_by_direction),
        rows=rows,
        n_px=n_px,
        n_mx=n_mx,
        steps=steps,
        gait_first=first,
        gait_len=length,
        use_bitmap=use_bitmap,
        bitmap=bitmap,
        edges=edges,
        n_transitions=len(src),
        labels=[table.label(i) for i in range(n_states)] if n_states <= 64 else [],
        gait_hash=f"0x{ghash:08X}",
        entry_steps=entry[0],
        entry_first=entry[1],
        entry_len=entry[2],
        entry_join=entry[3],
        **fb,
        **_library_part(robot, gaits_by_direction, table),
    )


def _fallback_part(robot: Any) -> dict[str, Any]:
    """The fallback tables (proleg.firmware.gaits.firmware_fallbacks), flattened per
    (lost actuator, direction +x/-x): the map to run with, the gait's steps."""
    from .gaits import DIRECTIONS, firmware_fallbacks

    fbs = firmware_fallbacks(robot)
    compiled = _compiled_map(robot)
    maps: list[list[int]] = []
    steps: list[int] = []
    first: list[int] = []
    length: list[int] = []
    notes: list[str] = []
    for a in range(len(robot.actuators)):
        for d in DIRECTIONS:
            fb = fbs.get((a, d))
            first.append(len(steps))
            if fb is None:
                maps.append(compiled)
                length.append(0)
                continue
            maps.append([int(x) for x in fb.actuator_map])
            walk = [int(s) for s in fb.states[:-1]]
            steps += walk
            length.append(len(walk))
            notes.append(f"{d}: {fb.describe(robot)}; {fb.mode}: {_mode_text(fb, robot)}")
    return dict(fallback=bool(fbs), fb_maps=maps, fb_steps=steps, fb_first=first, fb_len=length, fb_notes=notes)


def _mode_text(fb: Any, robot: Any) -> str:
    """What a fallback's mode means for this loss, for the generated file's comment: after the
    map, a bare "(dead)" read as if the last limb in it were the dead one."""
    if fb.mode == "dead":
        return f"the limbs on {fb.actuator} stay down"
    moved = [lb.name for lb, a in zip(robot.limbs, fb.actuator_map) if robot.actuators[a].name != lb.actuator]
    return "moved to another coil: " + ", ".join(moved)


def _compiled_map(robot: Any) -> list[int]:
    index = {a.name: i for i, a in enumerate(robot.actuators)}
    return [index[limb.actuator] for limb in robot.limbs]


def _library_part(robot: Any, gaits_by_direction: Mapping[str, Sequence[Any]], table: Any) -> dict[str, Any]:
    """The gait library's header lines (issue 17; empty without a library)."""
    library = getattr(gaits_by_direction, "library", ())
    if not library:
        return {}
    total = sum(len(gaits_by_direction.get(d, ()) or ()) for d in ("+x", "-x"))
    if total > 255:
        raise BuildError(f"{robot.where}: {total} gaits with the library, at most 255 (fewer headings)")
    spec = getattr(gaits_by_direction, "library_spec", None)
    return {"library": [lg.describe(table.label) for lg in library],
            "library_selection": spec.describe() if spec is not None else ""}
