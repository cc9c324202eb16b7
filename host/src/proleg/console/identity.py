"""Is the board running the firmware built from this robot file? (``proleg console --robot``)

The firmware's INFO reports the robot name, the hash of its compiled gait table and its build
id. ``expected_identity`` recomputes the last two from the robot file exactly as the build
does (``proleg.firmware.render``: the gait hash covers the states, gaits and allowed
transitions; the build id also the robot file's bytes, the board and the proleg version), for
each gait objective a build can use, and ``check_identity`` refuses a mismatch with both
values shown. The build id is only checked when INFO's board is a known board file.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from ..errors import LinkError, ProlegError
from ..link.client import RobotInfo
from ..names import counted

OBJECTIVES = ("total", "rate", "speed")


class IdentityMismatch(LinkError):
    """The board does not run firmware built from the given robot file."""


@dataclass(frozen=True)
class Identity:
    robot_name: str
    gait_hash: int
    build_id: int | None  # None: the board named in INFO is not a board file proleg knows
    objective: str


def expected_identity(robot: Any, board_name: str, objective: str = "total") -> Identity:
    """What INFO reports for firmware built from ``robot`` for board ``board_name``."""
    from ..firmware.boards import load_board
    from ..firmware.gaits import firmware_gaits
    from ..firmware.render import render_context

    try:
        board: Any = load_board(board_name)
    except ProlegError:
        board = None
    gaits = firmware_gaits(robot, objective)
    if board is None:  # the gait hash does not depend on the board: any bundled one renders it
        ctx = render_context(robot, gaits, load_board("host-sim"))
        return Identity(robot.name, int(ctx.gait.gait_hash, 16), None, objective)
    ctx = render_context(robot, gaits, board)
    return Identity(robot.name, int(ctx.gait.gait_hash, 16), int(ctx.build_id, 16), objective)


def identity_problems(info: RobotInfo, robot: Any) -> list[str]:
    """What differs between INFO and the robot file (empty when they match)."""
    from ..robot import info_name

    if info.robot_name != info_name(robot.name):
        return [f"robot {info.robot_name!r} on the board, {robot.name!r} in {robot.path}"]
    best: list[str] | None = None
    for objective in OBJECTIVES:
        try:
            want = expected_identity(robot, info.board, objective)
        except ProlegError:
            if objective == OBJECTIVES[0]:
                raise
            continue  # e.g. "speed" needs transition durations this robot file does not give
        problems = []
        if want.gait_hash != info.gait_hash:
            problems.append(f"gait table hash {info.gait_hash:08x} on the board, {want.gait_hash:08x} from {robot.path}")
        if want.build_id is not None and want.build_id != info.build_id:
            problems.append(f"build id {info.build_id:08x} on the board, {want.build_id:08x} from {robot.path} "
                            f"built for {info.board}")
        if not problems:
            return []
        if best is None:
            best = problems
    return best or []


def check_identity(info: RobotInfo, robot: Any, *, force: bool = False, link: str = "the board") -> list[str]:
    """Raise ``IdentityMismatch`` when the board does not run ``robot``'s firmware (unless
    ``force``); returns the differences (empty when none). A board of another shape (limb or
    actuator count) is refused even with ``force``: its frames read with the file's shape are
    wrong (3-digit states beside 2 ψ)."""
    problems = identity_problems(info, robot)
    if problems and not force:
        raise IdentityMismatch(f"the board does not run firmware built from {robot.path}: "
                               f"{'; '.join(problems)} (rebuild and flash it, or --force)")
    if len(robot.limbs) != info.limbs or len(robot.actuators) != info.actuators:
        raise IdentityMismatch(f"{link} has {counted(info.limbs, 'limb')} and {counted(info.actuators, 'actuator')}, {robot.path} "
                               f"{len(robot.limbs)} and {len(robot.actuators)}: --force cannot read one with the other")
    return problems
