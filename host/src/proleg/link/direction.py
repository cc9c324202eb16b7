"""A gait's way on the link: START's direction byte from what a user or a caller says
(``+x``, ``-x``, a ``Direction``, or ``UNSTATED`` for the loaded sequence), and back to text."""

from __future__ import annotations

from ..errors import LinkError
from ..protocol.definition import DIR_UNSTATED, GAIT_USER, Direction

#: The way of a LOAD_GAIT sequence that the host does not state (a learning probe, a planar
#: heading): START sends DIR_UNSTATED and the firmware's climb guard does not check it.
UNSTATED = "unstated"


def direction_code(direction: Direction | int | str, gait: int) -> int:
    """START's direction byte for ``gait``: ``UNSTATED`` only for the loaded sequence."""
    if direction in (UNSTATED, DIR_UNSTATED):
        if gait != GAIT_USER:
            raise LinkError(f"gait {gait}: a built-in gait runs +x or -x; only the loaded sequence (user) "
                            "may leave its way unstated")
        return DIR_UNSTATED
    return int(parse_direction(direction))


def direction_text(direction: int) -> str:
    """A direction byte as text: +x, -x, or "unstated" (DIR_UNSTATED: the loaded gait started
    without its way)."""
    if direction == Direction.PLUS_X:
        return "+x"
    return "-x" if direction == Direction.MINUS_X else UNSTATED if direction == DIR_UNSTATED else f"?{direction}"


def parse_direction(direction: Direction | int | str) -> Direction:
    if isinstance(direction, str):
        text = direction.strip().lower()
        if text in ("+x", "x", "plus_x", "+"):
            return Direction.PLUS_X
        if text in ("-x", "minus_x", "-"):
            return Direction.MINUS_X
        raise LinkError(f"unknown direction {direction!r}; expected +x or -x (or, for the loaded gait, {UNSTATED})")
    try:
        return Direction(int(direction))
    except ValueError:
        raise LinkError(f"unknown direction {direction!r}; expected 0 (+x) or 1 (-x)") from None
