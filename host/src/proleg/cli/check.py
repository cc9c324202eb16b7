"""``proleg check``: the robot's firmware under random operating conditions, before it meets them.

``proleg sim`` runs one condition a user names. A lab's robot meets supplies, rooms, worn coils
and loose IMUs nobody listed, so ``check`` draws them (``report.sweep``: three plant keys a row,
seeded) and, for each, runs the idealised drive (can the coils walk the gait at all?) and the
firmware on the simulated board (does it?). It fails (exit 1) on a row the coils can walk that
the firmware does not complete (a fault stop, the wrong way, a coil past 120 °C), and on a stop
that heated a coil past 120 °C. Exit codes as in ``main``.
"""

from __future__ import annotations

import argparse
import json
import logging
import os
import sys
from typing import Any

from ..names import counted, display_width, padded
from ..physics.materials import shown_c
from .main import EXIT_FAILED, EXIT_OK, robot_arg
from .number_args import MAX_CHECK_ROWS, check_rows, gait_number, worker_jobs

log = logging.getLogger("proleg")

#: Rows a check draws unless told (0.5–6 s of CPU each on host-sim for the example robots: R1's
#: 40 s runs the least, caterpillar-4's 60 s of four limbs the most).
DEFAULT_ROWS = 20


def add_arguments(sub) -> None:
    c = sub.add_parser("check", help="run the robot's firmware on the simulated board under random operating "
                                     "conditions; exit 1 where it fails a walk the coils can make, or cooks a coil",
                       description="Run the robot's firmware on the simulated board under random operating "
                                   "conditions (three plant keys a row, seeded), each against an idealised drive "
                                   "that says whether the coils can walk the gait there at all.",
                       epilog="exit status: 0 every row passed; 1 the firmware did not complete the nominal row "
                              "(row 0: --condition alone), missed a row the coils can walk "
                              "(a fault stop, the wrong way where the idealised drive makes 5 % of its nominal "
                              "speed or more, a coil past 120 °C) or stopped one nothing walks with "
                              "a coil past 120 °C, or the gait cannot be checked (even the idealised drive does not "
                              "walk it on the nominal plant); 2 a usage mistake")
    c.add_argument("robot", metavar="ROBOT", type=robot_arg)
    c.add_argument("--rows", type=check_rows, default=DEFAULT_ROWS, metavar="N",
                   help=f"random conditions to run (default {DEFAULT_ROWS}, at most {MAX_CHECK_ROWS})")
    c.add_argument("--seed", type=int, default=1, help="seed of the draws: the same rows for the same seed (default 1)")
    c.add_argument("--gait", type=gait_number, default=0, metavar="N", help="gait index in the firmware's table (default 0)")
    c.add_argument("--direction", choices=("+x", "-x"), default="+x")
    c.add_argument("--condition", action="append", default=[], metavar="KEY=VALUE",
                   help="a plant condition in every row, on top of the robot file's [plant] (as proleg sim "
                        "--condition takes it; its key is not drawn); --condition help lists the keys")
    from ..sim.simulated_boards import SIMULATED_BOARDS

    c.add_argument("--board", choices=tuple(SIMULATED_BOARDS), default="host-sim",
                   help="host-sim: the firmware's C on the host (default, 0.5-6 s a row); avr-emu / "
                        "arm-emu: the exact arduino-nano / bluepill firmware.elf on an emulated MCU (avr-emu about "
                        "twice real time, arm-emu 0.4-0.6x: a 40 s row takes about 20 s / 65-105 s; "
                        "bench/results/mcu.json)")
    c.add_argument("--jobs", type=worker_jobs, default=None, metavar="N",
                   help="rows run at once (default: the machine's cores)")
    c.add_argument("--json", action="store_true", help="print the report as one JSON object")
    c.set_defaults(run=cmd_check)


def _work(job: tuple[str, tuple[str, ...], float, str, int, str, str, Any]) -> Any:
    from ..report import sweep
    from ..robot import load_robot

    path, conditions, run_s, direction, gait, name, board, ideal = job
    return sweep.run_row(load_robot(path), conditions, run_s, direction=direction, gait=gait, name=name,
                         board=board, ideal=ideal)


def _moves(nominal: Any, direction: str) -> Any:
    """The idealised drive's nominal walk, not possible where it moves the gait's way by less than
    a run that does not move (``matrix_check.STILL_MM`` a cycle). A six-limb robot's gait 0 went
    +0.0002 mm a cycle (+0.0001 mm/s, the plant's noise): every row the firmware drifted back
    0.01 mm/s was a miss, and the check exited 1 saying the firmware did not complete the gait
    "where the idealised drive walks +0.000 mm/s", where -0.0002 would have said that nothing
    walks it."""
    from dataclasses import replace

    from ..report.matrix_check import STILL_MM

    if not nominal.possible or nominal.speed_mm_s is None or nominal.s_per_cycle is None:
        return nominal
    mm = nominal.speed_mm_s * nominal.s_per_cycle
    if (1 if direction == "+x" else -1) * mm >= STILL_MM:
        return nominal
    return replace(nominal, possible=False,
                   why_not=f"the coils complete the gait, but even an ideal drive (true ψ) moves {mm:+.4f} mm per cycle "
                           f"(under {STILL_MM:g} mm: no motion): under this condition the gait does not go {direction}")


def cmd_check(args: argparse.Namespace) -> int:
    from ..errors import GaitError, SimError
    from ..firmware.gaits import firmware_gaits
    from ..report import sweep
    from ..robot import load_robot
    from .sim_plant import wants_help

    if wants_help(args):
        return EXIT_OK
    robot = load_robot(args.robot)
    every = firmware_gaits(robot)
    gaits = every.get(args.direction, ())
    if args.gait >= len(gaits):
        why = every.left_out_line(args.direction)
        if why is not None:  # the build leaves the direction out: say why, as the build did
            raise GaitError(f"--gait {args.gait} of {args.direction}: {robot.where}: {why}")
        from ..firmware.gaits import no_such_gait

        raise GaitError(no_such_gait(args.gait, robot.name, args.direction, {d: len(g) for d, g in every.items()}))
    if args.board != "host-sim":  # before the nominal walk: every row would fail the same way
        from ..firmware.boards import load_board
        from ..firmware.build import check_board_takes
        from ..sim.simulated_boards import simulated_board

        entry = simulated_board(args.board)
        lacking = entry.missing()
        if lacking:
            raise SimError(lacking)
        check_board_takes(robot, load_board(entry.firmware_board))  # its PWM channels, IMUs, link rate
    base = tuple(args.condition)
    base_keys = {c.partition("=")[0].strip() for c in base}
    run_s, nominal = sweep.run_length(robot, direction=args.direction, gait=args.gait, base=base)  # checks base
    nominal = _moves(nominal, args.direction)
    label = " ".join(robot.transitions.label(s) for s in gaits[args.gait].states)
    if not nominal.possible:  # a finding about the robot file, not a mistake on the command line: exit 1
        on = f" under {' '.join(base)}" if base else " on the nominal plant"
        advice = ("The physical plant moves limbs in a row along x only and this robot file's planar "
                  "statistics describe a body that moves in the plane: `proleg check` cannot check it "
                  "(docs/plant.md, \"Not modelled\")" if robot.transitions.moves_in_plane else
                  "If the robot file's matrix was not measured on this body, measure it (proleg sim ROBOT "
                  "--measure-matrix) and build the gaits from that")
        print(f"proleg: error: {robot.name}: gait {args.gait} ({label}) cannot be checked{on}: {nominal.why_not}. "
              f"{advice}", file=sys.stderr)
        return EXIT_FAILED
    held = sorted(k for k in sweep.ROBOT_KEYS if k in robot.plant.given and k not in base_keys)
    if held:
        log.info("%s: %s held at the robot file's [plant] values (what the robot is, not drawn)", robot.name,
                 ", ".join(held))
    draws = sweep.draw_rows(args.rows, args.seed, [limb.name for limb in robot.limbs],
                            leave_out=tuple(base_keys | set(held)))
    rows_conditions = [base + d for d in draws]
    # job 0: the nominal row (only --condition's keys), the speed each row is measured against;
    # its idealised walk is the one run_length just made
    jobs = [(str(args.robot), c, run_s, args.direction, args.gait, f"{robot.name} #{i}", args.board,
             nominal if i == 0 else None)
            for i, c in enumerate([base, *rows_conditions])]
    log.info("%s: gait %d (%s) in %s under %s, %g s each (the idealised drive walks "
             "%+.3f mm/s%s)", robot.name, args.gait, label, args.direction, counted(len(draws), "random condition"),
             run_s, nominal.speed_mm_s or 0.0, f" under {' '.join(base)}" if base else " on the nominal plant")
    done: list = []
    try:
        _run(jobs, args.jobs or os.cpu_count() or 1, done)
    except KeyboardInterrupt:
        from ..errors import Interrupted

        raise Interrupted(_interrupted(args, max(len(done) - 1, 0), len(jobs) - 1)) from None
    nominal_row, rows = done[0], sweep.barely_moving(done[1:], nominal.speed_mm_s, args.direction)
    done = [nominal_row, *rows]
    summary = {**sweep.summary(rows), **_kept(nominal_row, rows),
               "hottest_c": round(max(r.coil_peak_c for r in done), 1)}  # the nominal row's coils too
    failed = [(i, r) for i, r in enumerate(done) if r.failed]
    errors = [_error(i, r) for i, r in failed]
    if args.json:
        print(json.dumps({
            "robot": robot.name, "board": args.board, "gait": args.gait, "states": label, "direction": args.direction,
            "seed": args.seed, "conditions": list(base), "held": held, "run_s": run_s,
            "idealised_nominal_mm_s": None if nominal.speed_mm_s is None else round(nominal.speed_mm_s, 4),
            "nominal": nominal_row.to_json(), "rows": [r.to_json() for r in rows], "summary": summary,
            "ok": not failed, "errors": errors,
        }, indent=1))
    else:
        _print(robot, args, label, run_s, nominal_row, rows, summary)
    for e in errors:
        print(f"proleg: error: {e}", file=sys.stderr)
    return EXIT_FAILED if failed else EXIT_OK


def _run(jobs: list, n_jobs: int, rows: list) -> None:
    """The rows, in order, appended to ``rows``; each says so on stderr when it ends (INFO:
    ``-q`` hides it)."""
    n_jobs = min(n_jobs, len(jobs))
    if n_jobs <= 1:
        for job in jobs:
            rows.append(_quiet_work(job))
            _progress(len(rows), len(jobs), rows[-1])
        return
    from ..interrupts import in_workers

    for row in in_workers(_work, jobs, n_jobs, "running the check's rows"):
        rows.append(row)
        _progress(len(rows), len(jobs), row)


def _quiet_work(job: tuple) -> Any:
    """``_work`` in this process, as quiet as a pool's worker (``interrupts.quiet_worker``): the
    plant's advice about a drawn condition (a coil that "would settle at 156 °C with this
    supply: lower the supply") is not printed once per row and run. With one job (``--jobs 1``,
    ``--rows 1``, a one-core machine) it was, twice for each hot draw, where the same rows in a
    pool printed none; the progress lines, logged here between rows, still show."""
    before = logging.root.manager.disable
    logging.disable(logging.WARNING)
    try:
        return _work(job)
    finally:
        logging.disable(before)


def _interrupted(args: argparse.Namespace, done: int, total: int) -> str:
    """The line a Ctrl-C leaves: how far the check got, and the options that run those rows
    again (the same draws need the same --condition keys left out, and the same gait, way and
    board; --rows and --seed alone drew other rows under other conditions)."""
    if not done:
        return f"interrupted after 0 of {counted(total, 'row')} (nothing written)"
    again = [f"--rows {done}", f"--seed {args.seed}", *(f"--condition {c}" for c in args.condition)]
    if args.gait:
        again.append(f"--gait {args.gait}")
    if args.direction != "+x":
        again.append(f"--direction {args.direction}")
    if args.board != "host-sim":
        again.append(f"--board {args.board}")
    shown = "the rows run are on stderr above; " if log.isEnabledFor(logging.INFO) else ""
    return f"interrupted after {done} of {counted(total, 'row')} (nothing written: {shown}{' '.join(again)} runs them again)"


def _progress(done: int, total: int, row: Any) -> None:
    """``done`` counts the nominal row (job 0) too: it is row 0 of the rows drawn."""
    log.info("row %d of %d: %s: %s", done - 1, total - 1, row.verdict, " ".join(row.conditions) or "nominal")


#: A row keeps its speed when it walks at least this fraction of the nominal row's (the claim
#: bench's line: docs/plant.md). Reported, not a failure: a weak supply slows any drive.
KEPT = 0.75
#: A nominal row the firmware completes at less than this share of the idealised drive's speed is noted.
SLOW_NOMINAL = 0.5


def _fraction(nominal: Any, r: Any) -> float | None:
    """``r``'s speed as a fraction of the nominal row's (None where the nominal did not walk)."""
    if not nominal.completed or nominal.speed_mm_s == 0 or not r.completed:
        return None
    return r.speed_mm_s / nominal.speed_mm_s


def _kept(nominal: Any, rows: list) -> dict:
    walked = [r for r in rows if r.possible]
    kept = [r for r in walked if (_fraction(nominal, r) or 0.0) >= KEPT]
    share = _share_of_idealised(nominal)
    return {"nominal_mm_s": round(nominal.speed_mm_s, 4), "nominal_completed": nominal.completed,
            "nominal_share_of_idealised": None if share is None else round(share, 3),
            "kept_75pct_of_nominal_where_possible": len(kept) if nominal.completed else None}


def _share_of_idealised(nominal: Any) -> float | None:
    """The nominal row's firmware speed as a share of the idealised drive's there (None where the
    idealised drive does not walk it). The rows' "% of nominal" is against the firmware's own
    nominal speed, so a firmware that crawls on the nominal plant looked fine in every row: a
    lab's two-pad wedge walked -0.062 mm/s against the idealised -0.56 and passed with rows at
    869 % of nominal."""
    ideal = nominal.idealised_mm_s
    if ideal is None or ideal == 0.0:
        return None
    return nominal.speed_mm_s / ideal


def _slow_nominal_note(nominal: Any) -> str | None:
    """A NOTE where the firmware completed the nominal row at less than ``SLOW_NOMINAL`` of the
    idealised drive's speed (the example robots: 57 % to 130 %, bench/results/claim*.json)."""
    share = _share_of_idealised(nominal)
    if not nominal.completed or share is None or share >= SLOW_NOMINAL:
        return None
    return (f"NOTE: on the nominal plant the firmware walks {nominal.speed_mm_s:+.3f} mm/s, {share:.0%} of the "
            f"idealised drive's {nominal.idealised_mm_s:+.3f} (true ψ, no stall rules), and each row's share is "
            "of that slow nominal: the gait's states are reached slowly (hold margins, stall and settle rules: "
            "docs/control.md)")


def _error(i: int, r: Any) -> str:
    conds = " ".join(r.conditions) or "none drawn"
    if i == 0:
        return f"the nominal row ({conds}): the firmware did not complete the gait ({r.what_happened()})"
    if r.hot_stop:
        return (f"row {i} ({conds}): nothing walks this gait here, but the firmware's stop heated a coil to "
                f"{shown_c(r.coil_peak_c)} °C, past the 120 °C that wears NiTi out")
    ideal = f"the idealised drive walks {r.idealised_mm_s:+.3f} mm/s" if r.idealised_mm_s is not None \
        else "the coils can walk it"
    return f"row {i} ({conds}): the firmware did not complete the gait ({r.what_happened()}), where {ideal}"


def _print(robot: Any, args: argparse.Namespace, label: str, run_s: float, nominal: Any, rows: list,
           s: dict) -> None:
    base = f", with {' '.join(args.condition)}" if args.condition else ""
    print(f"{robot.name} on {args.board}: gait {args.gait} ({label}) in {args.direction} under "
          f"{counted(len(rows), 'random condition')} "
          f"({counted(len(rows[0].conditions) - len(args.condition), 'key')} each, seed {args.seed}{base}), {run_s:g} s each "
          "from cold")
    width = max(len("nominal"), *(display_width(" ".join(r.conditions[len(args.condition):])) for r in rows))
    for i, r in enumerate([nominal, *rows]):
        conds = " ".join(r.conditions[len(args.condition):]) or "nominal"
        ideal = ("cannot walk" if r.idealised_mm_s is None else
                 f"{r.idealised_mm_s:+.3f}" + ("" if r.possible else " back"))
        frac = _fraction(nominal, r)
        share = "" if i == 0 or frac is None else f"{frac:4.0%} of nominal"
        print(f"  {i:3d}  {padded(conds, width)}  idealised {ideal:>11}  firmware {r.verdict:<10} "
              f"{r.what_happened():<24} {share:>16}  coils ≤ {shown_c(r.coil_peak_c)} °C")
    parts = [f"the coils can walk {s['possible']} of {s['rows']}: the firmware completed "
             f"{s['completed_where_possible']}" + (f", missed {s['missed']}" if s["missed"] else "")
             + (f", drifted back where the gait barely moves in {s['drifted']}" if s["drifted"] else "")]
    if s["impossible"]:
        stops = [f"stopped cool in {s['impossible_stopped_below_120c']}"] if s["impossible_stopped_below_120c"] else []
        if s["impossible_completed_by_the_firmware"]:
            stops.append(f"walked {s['impossible_completed_by_the_firmware']}")
        if s["hot_stops"]:
            stops.append(f"stopped hot in {s['hot_stops']}")
        parts.append(f"nothing walks {s['impossible']}: the firmware " + ", ".join(stops))
    if s["kept_75pct_of_nominal_where_possible"] is not None and s["possible"]:
        parts.append(f"{s['kept_75pct_of_nominal_where_possible']} of the {s['possible']} keep {KEPT:.0%} of the "
                     "nominal speed")
    # from the rows' own peaks, as each row shows its own: s['hottest_c'] is rounded to 0.1 °C for
    # --json, and 104.5012 read "≤ 105" in its row and "hottest coil 104" here (104.5 to the even degree)
    parts.append(f"hottest coil {shown_c(max(r.coil_peak_c for r in [nominal, *rows]))} °C")
    print("  " + "; ".join(parts))
    note = _slow_nominal_note(nominal)
    if note:
        print("  " + note)
    for i, r in enumerate(rows, 1):
        if not r.possible and r.why_not:
            print(f"  row {i}: the idealised drive cannot walk it: {r.why_not}")
