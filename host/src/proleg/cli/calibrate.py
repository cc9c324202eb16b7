"""``proleg calibrate``: level calibration of a robot's IMUs (docs/calibration.md).

With the robot at rest on flat ground (every coil cold), ``proleg calibrate ROBOT --port …``
has the firmware record each IMU's rest tilt and store it in the board's non-volatile memory;
``--show`` prints what is stored, ``--clear`` erases it. Exit 0 when stored (or shown/cleared),
1 when the robot refuses, 130 on Ctrl-C with a line saying what the board keeps.
"""

from __future__ import annotations

import argparse
from typing import Any

from ..errors import Interrupted, LinkError
from ..names import counted, display_width, padded


#: How long the host watches ψ before it asks for a calibration, and how far a limb's mean ψ may
#: move between the first and the second half of that time: a coil cooling after a gait moves
#: its end by degrees a second (R1: 17° to 8° in about 2 s); 1.5° of IMU noise moves a mean of
#: 25 samples by about 0.4°.
REST_WATCH_S = 1.0
REST_DRIFT_DEG = 1.0


def _not_at_rest(client: Any, robot: Any) -> str | None:
    """Why the robot is not at rest (a coil heating, or a limb whose ψ still moves), from
    ``REST_WATCH_S`` of telemetry; None when it rests. The board refuses a calibration while a
    gait runs, within 2 s at rest of a gait or a fault (NACK 6) and beyond 20° of tilt; this also
    sees a limb still moving or a coil heating past that: a robot stopped a moment ago, its ends
    still coming down, was calibrated with +17° of bend and then refused START on flat ground
    (TOO_STEEP)."""
    from ..protocol.definition import Flag

    hz = getattr(client.info, "telemetry_hz", 0) or 50
    client.wait_known_state()  # a board that has just reset reads its IMUs first: no ψ to judge yet
    frames = list(client.telemetry(timeout=2.0, count=max(4, round(hz * REST_WATCH_S))))
    known = [f for f in frames if not int(f.flags) & Flag.STATE_UNKNOWN]
    frames = known if len(known) >= 4 else frames  # a limb between its levels leaves the state unknown
    names = [limb.name for limb in robot.limbs]
    acts = [a.name for a in robot.actuators]
    for f in frames:
        hot = [j for j, d in enumerate(f.duty) if d]
        if hot:
            j = hot[0]
            coil = repr(acts[j]) if j < len(acts) else f"#{j + 1}"
            return f"actuator {coil} is heating (duty {f.duty[j] / 100:g} %)"
    half = len(frames) // 2
    for i, name in enumerate(names[:len(frames[0].psi)]):
        first = sum(f.psi[i] for f in frames[:half]) / half / 100
        second = sum(f.psi[i] for f in frames[half:]) / (len(frames) - half) / 100
        if abs(second - first) > REST_DRIFT_DEG:
            return f"limb {name!r} is still moving (ψ {first:+.1f}° then {second:+.1f}° within {REST_WATCH_S:g} s)"
    return None


def _limb_names(robot: Any, n: int) -> list[str]:
    names = [limb.name for limb in robot.limbs]
    if len(names) != n:
        raise LinkError(f"the robot reports {counted(n, 'limb')}, {robot.path.name} has {len(names)}: "
                        f"is this the firmware of this robot file?")
    return names


def _table(names: list[str], offsets_cdeg: tuple[int, ...], status: list[str], what: str = "rest tilt") -> str:
    w = max(map(display_width, names))
    return "\n".join(f"  limb {padded(n, w)}  {what} {o / 100:+6.2f}°  {s}" for n, o, s in zip(names, offsets_cdeg, status))


def cmd_calibrate(args: argparse.Namespace) -> int:
    from ..robot import load_robot
    from .robot_link import open_client

    robot = load_robot(args.robot)
    asked: list[str] = []  # the command that changes what the board keeps, once it is being sent
    try:
        with open_client(args, args.robot, robot=robot) as client:
            return _calibrate(args, robot, client, asked)
    except KeyboardInterrupt as e:
        if isinstance(e, Interrupted):
            raise
        raise Interrupted(_interrupted(args, asked[-1] if asked else None)) from None


def _interrupted(args: argparse.Namespace, asked: str | None) -> str:
    """The one line a Ctrl-C'd ``proleg calibrate`` ends with: what the board keeps. The board
    does the sampling and the writing on its own once asked (core/level.c): the host leaving
    does not stop it half-way, and a record is used only whole (its CRC checked)."""
    if asked is None:
        return "interrupted before anything was asked of the board: its level calibration is unchanged"
    if getattr(args, "sim", False):
        return ("interrupted while the simulated board was " + ("clearing" if asked == "CLEAR_LEVEL" else "calibrating")
                + "; nothing kept: a --sim board lives for this command only")
    link = f"--port {args.port}" if args.port else f"--can {args.can}"
    check = f"proleg calibrate {args.robot} {link} --show"
    if asked == "CLEAR_LEVEL":
        return f"interrupted after asking the board to clear its level calibration: it erases it on its own; check: {check}"
    if asked == "ground":
        return ("interrupted while the board was levelling on this ground: it finishes on its own and applies the "
                f"result in RAM only, until it resets (nothing stored); check: {check}")
    return ("interrupted while the board was calibrating: it finishes on its own within a second or so and either "
            "stores the new record whole or keeps the one it had (a record is used only whole, its CRC checked); "
            f"check which: {check}")


def _calibrate(args: argparse.Namespace, robot: Any, client: Any, asked: list[str]) -> int:
    from ..link.client import CommandRefused
    from ..link.level import ask_level_calibration, clear_level, get_level, level_outcome
    from ..protocol.definition import LevelStatus

    where = client.link.description
    if args.show or args.clear:
        if args.clear:
            asked.append("CLEAR_LEVEL")
        reading = clear_level(client) if args.clear else get_level(client)
        names = _limb_names(robot, len(reading.offsets_cdeg))
        what = {LevelStatus.NONE: "no level calibration stored",
                LevelStatus.STORED: "level calibration stored",
                LevelStatus.CORRUPT: "the stored level calibration is corrupt (ignored: offsets 0); calibrate again",
                LevelStatus.CALIBRATING: "a level calibration is under way"}[reading.status]
        print(f"{'cleared: ' if args.clear else ''}{what} on {where}")
        if reading.status == LevelStatus.STORED:
            print(_table(names, reading.offsets_cdeg, ["applied"] * len(names)))
        if any(reading.ground_cdeg):
            print("levelled on this ground (until a power-on):")
            print(_table(names, reading.ground_cdeg, ["applied"] * len(names), "slope tilt"))
        return 0
    if (moving := _not_at_rest(client, robot)) is not None:
        raise LinkError(f"{where}: not at rest, nothing asked of the board: {moving}; let the coils cool and the "
                        "body settle (docs/calibration.md, step 2), then calibrate")
    try:
        asked.append("ground" if args.ground else "CALIBRATE_LEVEL")
        ask_level_calibration(client, ground=args.ground)
    except CommandRefused as e:  # the reasons are the client's (link/replies.py), one table for both
        raise LinkError(f"{where}: robot refused the level calibration: {e.why or e}") from None
    outcome = level_outcome(client)
    names = _limb_names(robot, len(outcome.reading.offsets_cdeg))
    if outcome.ok and args.ground:
        if outcome.reading.status != LevelStatus.STORED:
            print("note: no flat calibration is stored, so the tilts below include each IMU's mounting tilt")
        print(f"levelled on this ground on {where} (applied until a power-on; not stored)")
        print(_table(names, outcome.reading.ground_cdeg, ["applied"] * len(names), "slope tilt"))
        return 0
    if outcome.ok:
        print(f"level calibration stored on {where} (applied from now on, kept across resets)")
        print(_table(names, outcome.reading.offsets_cdeg, ["stored"] * len(names)))
        if getattr(args, "sim", None):
            from .robot_commands import SIM_IS_FRESH

            print(SIM_IS_FRESH)
        return 0
    print(f"level calibration refused on {where}: nothing changed")
    kept = outcome.reading
    print(_table(names, kept.offsets_cdeg if kept.status == LevelStatus.STORED else (0,) * len(names),
                 [outcome.limb_text(i) for i in range(len(names))]))
    return 1


def add_arguments(subparsers: Any) -> None:
    from .main import robot_arg
    from .robot_link import add_link_options

    c = subparsers.add_parser(
        "calibrate", help="level calibration: record each IMU's rest tilt on flat ground and store it on the board",
        description="Put the robot at rest on flat, level ground with every coil cold, then run this. "
                    "The firmware averages each IMU for 64 ticks, stores each limb's rest tilt in "
                    "non-volatile memory (EEPROM / flash) and takes it off every reading from then on.")
    c.add_argument("robot", metavar="ROBOT", type=robot_arg)
    add_link_options(c, sim_takes_robot=False)
    g = c.add_mutually_exclusive_group()
    g.add_argument("--show", action="store_true", help="print the stored calibration, change nothing")
    g.add_argument("--clear", action="store_true", help="erase the stored calibration (offsets 0)")
    g.add_argument("--ground", action="store_true",
                   help="level on the ground the robot rests on now (a slope), on top of the flat calibration; "
                        "kept in RAM until a power-on (a reset that is not one, such as a Nano's when its port opens, keeps it)")
    c.set_defaults(run=cmd_calibrate)
