"""Render a robot's configuration and gait tables for the firmware core.

``render_config(robot, gaits_by_direction, board)`` fills ``firmware_templates/robot_config.h.j2``
and ``gait_table.c.j2``. Only data is rendered (STYLE.md: generate data, keep logic
hand-written): limb levels, ψ* and the hysteresis band of every threshold (the firmware
turns them into the Q14 cos/sin of each band edge at start-up, so the control path
classifies ψ with two multiplications, no atan2), actuator channels and the board's
PWM pin map (each pin's entry from its HAL family's ``family.toml``), the UART buffers,
the safety envelope in ticks, the gait step tables of both directions, the allowed-
transition bitmap and the gait selection that chose the gaits. Same inputs, same bytes:
no timestamps.

The work is a chain of small functions, each filling one part of a ``RenderContext``:
``_board_part`` (board and family), ``_limb_part`` (thresholds), ``control_part`` (tick,
duties, safety envelope), ``render_gaits.gait_part`` (step tables, transitions, hashes).
"""

from __future__ import annotations

import hashlib
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, fields
from pathlib import Path
from typing import Any

import jinja2

from .. import __version__
from ..errors import BoardError, BuildError
from ..paths import display_path, templates_dir
from ..robot import DUTY_WINDOW_MS_RANGE, MAX_ON_LIMIT_LATCH, Safety, stroke_leads
from ..robot_body import worn_holds_of
from ..robot_climb import check_climb_limit
from ..robot_reach import boost_ms_of
from .boards import DEFAULT_I2C_HZ, DEFAULT_UART_RX_BUFFER, DEFAULT_UART_TX_BUFFER, pwm_channel_error
from .build_id import build_id
from .families import Family, load_family
from .placement import place_imus
from .render_gaits import GaitPart, gait_part

#: LOAD_GAIT capacity (the protocol's MAX_GAIT_STEPS).
MAX_LOADED_STEPS = 24
GENERATOR = "proleg.firmware.render"


# ------------------------------------------------------------------ the typed context


@dataclass(frozen=True)
class BoardPart:
    board_name: str
    family: str
    family_id: int
    pins: list[str]
    pwm_map: list[str]
    imu_addresses: list[int]
    uart_baud: int
    uart_rx_buffer: int
    uart_tx_buffer: int
    clock_hz: int
    pwm_hz: int
    i2c_hz: int
    main_loop: bool = False  # core/main.c runs app_init once per reset (False: a host may call it again)
    link_can: bool = False  # [link] transport = "can": core/canlink.c carries the protocol
    can_btr: str = "0x00000000UL"  # CAN_BTR from the board's [can] clock and bit rate (can_config.bit_timing)
    can_timing: str = ""
    can_bitrate: int = 0
    can_remap: int = 0
    can_node: int = 0
    can_base: str = "0x100u"
    can_tx_frames: int = 0


@dataclass(frozen=True)
class LimbPart:
    n_limbs: int
    n_actuators: int
    limbs: list[Any]
    levels: list[int]
    max_levels: int
    max_thr: int
    n_states: int
    state_type: str
    state_bytes: int
    limb_actuator: list[int]
    imu_addr: list[str]
    imu_bus: list[int]
    imu_mux: list[str]  # 0x00u: wired directly
    imu_channel: list[int]
    n_i2c_buses: int
    mux_used: bool
    placement: list[str]  # one line per limb, for the header comment
    psi_cdeg: list[list[int]]
    hyst_cdeg: list[int]
    stroke_cdeg: list[str]  # empty: no limb has a stroke (the table is not rendered)
    stroke_leads: tuple[int, int | None] | None  # (rise lead, fall lead) limb indices (robot.stroke_leads)
    actuators: list[Any]
    act_channels: list[int]


@dataclass(frozen=True)
class ControlPart:
    tick_hz: int
    tick_us: int
    debounce: int
    hold_ms: int
    hold_ticks: int
    hold_margin_cdeg: int
    telemetry_hz: int
    drive_pm: int
    hold_pm: int
    max_duty_pm: int
    max_on_ms: int
    max_on_ticks: int
    cooldown_ms: int
    cooldown_ticks: int
    timeout_ms: int
    timeout_ticks: int
    watchdog_ms: int
    watchdog_ticks: int
    hold_max_duty_pm: int  # thermal budget (docs/safety.md)
    mean_duty_pm: int
    duty_window_ms: int
    on_limit_latch: int
    stuck_samples: int
    max_loaded: int
    overrun_fault: int
    max_climb_cdeg: int | None  # [control] max_climb_deg (+x) in 0.01°; None: no climb guard
    max_climb_mx_cdeg: int | None  # its -x limit where that differs (None: the same)
    max_climb_gaits_px: tuple[int, ...] = ()  # each built-in +x gait's own limit (): the way's for all
    max_climb_gaits_mx: tuple[int, ...] = ()
    hold_watch: int = 0  # 1: core/ctl.h's hold watch is built in (robot_body.worn_holds)
    boost_ms: int = 0  # [control] boost_ms: CTL_BOOST_MS (0: no boost, none of its code)
    coil_tau_ms: int = 0  # [safety] coil_heat_ceiling: CFG_COIL_TAU_MS of core/sma.h (0: off, none of its code)




@dataclass(frozen=True)
class RenderContext:
    version: str
    robot_name: str
    robot_path: str
    robot_sha: str
    build_id: str
    board: BoardPart
    limb: LimbPart
    control: ControlPart
    gait: GaitPart

    def template_vars(self) -> dict[str, Any]:
        """The flat names the templates use (each part's fields, plus the identity)."""
        out: dict[str, Any] = {}
        for f in fields(self):
            v = getattr(self, f.name)
            if isinstance(v, (BoardPart, LimbPart, ControlPart, GaitPart)):
                out.update({g.name: getattr(v, g.name) for g in fields(v)})
            else:
                out[f.name] = v
        return out


# ------------------------------------------------------------------ small helpers


def _get(obj: Any, key: str, default: Any = None) -> Any:
    if isinstance(obj, Mapping):
        return obj.get(key, default)
    getter = getattr(obj, "get", None)
    if callable(getter):
        return getter(key, default)
    return getattr(obj, key, default)


def _ticks(ms: float, tick_hz: int) -> int:
    return int(math.ceil(ms * tick_hz / 1000.0 - 1e-9))


def _file_sha256(path: Any) -> str:
    try:
        return hashlib.sha256(Path(path).read_bytes()).hexdigest()
    except (OSError, TypeError):
        return "unavailable"


def _display_path(path: Any) -> str:
    return "(no file)" if path is None else display_path(path)


def _chunks(values: Sequence[Any], per_line: int = 16) -> list[str]:
    """Comma-joined lines of at most per_line values (for C initialisers)."""
    vals = [str(v) for v in values]
    return [", ".join(vals[i : i + per_line]) for i in range(0, len(vals), per_line)]




# ------------------------------------------------------------------ the parts


def _family(board_name: str, name: str) -> Family:
    try:
        return load_family(name)
    except BoardError as e:
        raise BuildError(f"board {board_name}: {e}") from None


def _board_part(board: Any) -> BoardPart:
    """The board's data and its HAL family's PWM map; BuildError for what the HAL cannot do."""
    board_name = str(_get(board, "name"))
    family = _family(board_name, str(_get(board, "family")))
    pins = [str(p) for p in (_get(board, "pwm_channels", None) or _get(board, "pwm_pins", ()) or ())]
    if not pins:
        raise BuildError(f"board {board_name}: no PWM channels")
    i2c = _get(board, "i2c", {}) or {}
    return BoardPart(
        board_name=board_name,
        family=family.name,
        family_id=family.id,
        pins=pins,
        pwm_map=[family.pwm_entry(board_name, i, pin) for i, pin in enumerate(pins)],
        imu_addresses=list(_get(i2c, "imu_addresses", [0x68, 0x69])),
        # a board file's values were checked by load_board; the defaults are for a partial board dict
        uart_baud=int(_get(board, "uart_baud", 115200)),
        uart_rx_buffer=int(_get(board, "uart_rx_buffer", DEFAULT_UART_RX_BUFFER)),
        uart_tx_buffer=int(_get(board, "uart_tx_buffer", DEFAULT_UART_TX_BUFFER)),
        clock_hz=int(_get(board, "clock_hz", 0)),
        pwm_hz=int(_get(board, "pwm_frequency_hz", 1000)),
        i2c_hz=int(_get(i2c, "hz", DEFAULT_I2C_HZ)),
        main_loop=bool(_get(board, "main_loop", False)),
        **_can_part(board),
    )


def _can_part(board: Any) -> dict[str, Any]:
    """The CAN link's constants (can_config.py computed and checked them when the board file was read)."""
    can = _get(board, "can", None)
    if _get(board, "transport", "uart") != "can" or can is None:
        return {}
    return dict(link_can=True, can_btr=f"0x{can.timing.btr:08X}UL", can_timing=can.timing.describe(),
                can_bitrate=can.bitrate, can_remap=can.remap, can_node=can.node, can_base=f"0x{can.base_id:03X}u",
                can_tx_frames=can.tx_frames)


def _check_bands(robot: Any, limb: Any) -> None:
    """Each of a limb's hysteresis bands lies strictly inside (-90, 90) deg (psi.c's edges)."""
    h = float(limb.hysteresis_deg)
    for p in limb.psi_star_deg:
        up, lo = p + h / 2.0, p - h / 2.0
        if not (-90.0 < lo and up < 90.0):
            raise BuildError(
                f"{robot.where}: limb {limb.name!r}: band {lo:g}..{up:g} deg around psi* {p:g} "
                "must lie strictly inside (-90, 90)"
            )


def _strokes(limbs: Sequence[Any]) -> list[str]:
    """Each limb's ``stroke_deg`` in 0.01° (PSI_NO_STROKE: none), or [] when no limb has one."""
    strokes = [getattr(limb, "stroke_deg", None) for limb in limbs]
    if all(s is None for s in strokes):
        return []
    return ["PSI_NO_STROKE" if s is None else str(round(float(s) * 100)) for s in strokes]


def _limb_part(robot: Any, board: BoardPart, raw_board: Any) -> LimbPart:
    limbs, actuators = list(robot.limbs), list(robot.actuators)
    placements = place_imus(robot, raw_board)
    for a in actuators:
        if not 0 <= a.channel < len(board.pins):
            raise BuildError(pwm_channel_error(robot, a, board.board_name, board.pins))
    levels = [int(limb.levels) for limb in limbs]
    n_states = math.prod(levels)
    if n_states > 0xFFFF:
        raise BuildError(f"{robot.where}: {n_states} states, the firmware supports at most 65535")
    max_thr = max(k - 1 for k in levels)
    for limb in limbs:
        _check_bands(robot, limb)
    act_index = {a.name: i for i, a in enumerate(actuators)}
    return LimbPart(
        n_limbs=len(limbs),
        n_actuators=len(actuators),
        limbs=limbs,
        levels=levels,
        max_levels=max(levels),
        max_thr=max_thr,
        n_states=n_states,
        state_type="uint8_t" if n_states <= 256 else "uint16_t",
        state_bytes=1 if n_states <= 256 else 2,
        limb_actuator=[act_index[limb.actuator] for limb in limbs],
        imu_addr=[f"0x{p.address:02X}u" for p in placements],
        imu_bus=[p.bus for p in placements],
        imu_mux=[f"0x{p.mux or 0:02X}u" for p in placements],
        imu_channel=[p.channel or 0 for p in placements],
        n_i2c_buses=max(p.bus for p in placements) + 1,
        mux_used=any(p.mux is not None for p in placements),
        placement=[p.describe() for p in placements],
        psi_cdeg=[[round(p * 100) for p in limb.psi_star_deg] + [0] * (max_thr - len(limb.psi_star_deg))
                  for limb in limbs],
        hyst_cdeg=[round(float(limb.hysteresis_deg) * 100) for limb in limbs],
        stroke_cdeg=_strokes(limbs),
        stroke_leads=stroke_leads(limbs, robot.control),
        actuators=actuators,
        act_channels=[a.channel for a in actuators],
    )


#: Thermal-budget keys of [safety] (docs/safety.md) and their defaults (``Safety``'s) for a
#: stand-in robot that has none: hold_max_duty None = max(0.3, control.hold_duty).
BUDGET_DEFAULTS: dict[str, Any] = {
    k: getattr(Safety(), k) for k in ("hold_max_duty", "max_mean_duty", "duty_window_ms", "on_limit_latch")
}


def thermal_budget(name: str, safety: Any, ctl: Any) -> dict[str, int]:
    """The [safety] keys of the thermal budget, read with their defaults (docs/safety.md)."""
    v = {k: getattr(safety, k, d) for k, d in BUDGET_DEFAULTS.items()}
    # read as a Safety, so that a stand-in safety gets Safety's rules for the default ceiling
    budget = Safety(max_duty=float(safety.max_duty), **v)
    mean = budget.mean_ceiling
    hold_max = budget.hold_ceiling(float(ctl.hold_duty))
    if not 0.0 <= float(hold_max) <= mean:
        raise BuildError(
            f"robot {name}: safety.hold_max_duty {hold_max:g} must lie in 0 .. max_mean_duty ({mean:g}): "
            "a duty the coil may hold forever must fit the mean-duty window"
        )
    lo, hi = DUTY_WINDOW_MS_RANGE
    if not lo <= int(v["duty_window_ms"]) <= hi:
        raise BuildError(f"robot {name}: safety.duty_window_ms {v['duty_window_ms']} must lie in {lo} .. {hi}")
    if not 1 <= int(v["on_limit_latch"]) <= MAX_ON_LIMIT_LATCH:  # the hit count is a byte (safety.c)
        raise BuildError(f"robot {name}: safety.on_limit_latch {v['on_limit_latch']} must lie in 1 .. "
                         f"{MAX_ON_LIMIT_LATCH}")
    return dict(
        hold_max_duty_pm=round(float(hold_max) * 10000),
        mean_duty_pm=round(mean * 10000),
        duty_window_ms=int(v["duty_window_ms"]),
        on_limit_latch=int(v["on_limit_latch"]),
    )


def _climb_cdeg(limit: Any) -> dict[str, int | None]:
    """The climb guard's limits in 0.01°: +x, -x only where it differs, and each way's per-gait
    list where the robot file gives one (its length is checked against the gaits in
    ``render_context``)."""
    if limit is None:
        return {"max_climb_cdeg": None, "max_climb_mx_cdeg": None}
    plus, minus = round(limit.plus_x * 100), round(limit.minus_x * 100)
    return {"max_climb_cdeg": plus, "max_climb_mx_cdeg": None if minus == plus else minus,
            "max_climb_gaits_px": tuple(round(v * 100) for v in limit.plus_x_gaits),
            "max_climb_gaits_mx": tuple(round(v * 100) for v in limit.minus_x_gaits)}


def coil_tau_ms(robot: Any) -> int:
    """The coils' thermal time constant in ms (the longest, rounded up: a slower cooling is the
    safe side) with which core/sma.c smooths each coil's duty into its heat, where the robot file
    sets ``[safety] coil_heat_ceiling = true``; 0 otherwise (none of its code is built in, and the
    firmware is byte for byte what it was without the key). The ceiling is sma.c's alone: it
    needs no other part of the firmware, and any robot and board may carry it."""
    if not getattr(robot.safety, "coil_heat_ceiling", False):
        return 0
    from ..physics.params import coil_time_constant_s

    # sma.c takes dt × 2^32 / tau in 32 bits for a dt up to 400 ms: no coil of the library is near
    return max(401, math.ceil(coil_time_constant_s(robot, len(robot.actuators)) * 1000))


def control_part(robot: Any) -> ControlPart:
    """The robot's control and safety numbers as the firmware is built with them (whole ticks)."""
    ctl, safety = robot.control, robot.safety
    tick_hz = int(ctl.tick_hz)
    if tick_hz < 200:
        raise BuildError(f"{robot.where}: control.tick_hz {tick_hz} below 200")
    return ControlPart(
        tick_hz=tick_hz,
        tick_us=round(1_000_000 / tick_hz),
        debounce=int(ctl.debounce_ticks),
        hold_ms=int(ctl.hold_ms),
        hold_ticks=_ticks(ctl.hold_ms, tick_hz),
        hold_margin_cdeg=round(float(ctl.hold_margin_deg) * 100),
        telemetry_hz=int(ctl.telemetry_hz),
        drive_pm=round(float(ctl.drive_duty) * 10000),
        hold_pm=round(float(ctl.hold_duty) * 10000),
        max_duty_pm=round(float(safety.max_duty) * 10000),
        max_on_ms=int(safety.max_on_ms),
        max_on_ticks=_ticks(safety.max_on_ms, tick_hz),
        cooldown_ms=int(safety.min_cooldown_ms),
        cooldown_ticks=_ticks(safety.min_cooldown_ms, tick_hz),
        timeout_ms=int(safety.state_timeout_ms),
        timeout_ticks=_ticks(safety.state_timeout_ms, tick_hz),
        watchdog_ms=int(safety.link_watchdog_ms),
        watchdog_ticks=_ticks(safety.link_watchdog_ms, tick_hz),
        **thermal_budget(robot.name, safety, ctl),
        hold_watch=int(bool(worn_holds_of(robot))),
        boost_ms=boost_ms_of(robot),
        coil_tau_ms=coil_tau_ms(robot),
        stuck_samples=max(20, tick_hz // 5),
        max_loaded=MAX_LOADED_STEPS,
        overrun_fault=int(getattr(ctl, "overrun_fault", 10)),
        **_climb_cdeg(getattr(ctl, "max_climb_deg", None)),
    )


def render_context(robot: Any, gaits_by_direction: Mapping[str, Sequence[Any]], board: Any) -> RenderContext:
    """Everything the templates need, checked (BuildError when the robot does not fit)."""
    board_part = _board_part(board)
    limb_part = _limb_part(robot, board_part, board)
    control = control_part(robot)
    gaits = gait_part(robot, gaits_by_direction, limb_part.n_states)
    if why := check_climb_limit(getattr(robot.control, "max_climb_deg", None), gaits_by_direction):
        raise BuildError(f"{robot.where}: {why}")
    robot_sha = _file_sha256(getattr(robot, "path", None))
    return RenderContext(
        version=__version__,
        robot_name=robot.name,
        robot_path=_display_path(getattr(robot, "path", None)),
        robot_sha=robot_sha,
        build_id=build_id(robot_sha, board_part.board_name, board_part.family, board_part.pins, gaits.gait_hash),
        board=board_part,
        limb=limb_part,
        control=control,
        gait=gaits,
    )


def _comment_safe(value: Any) -> Any:
    """Every rendered value, with ``*/`` and ``/*`` broken up: limb names ("any printable
    text"), IMU placement lines, fallback lines and the robot file's path are written into C
    comments, and a limb named ``tail */ x`` ended the comment: the build failed with compiler
    errors ("stray '\\' in program") instead of building; ``left /* x`` opened one inside it
    ("'/*' within comment", an error under -Werror). No rendered code value contains either."""
    return value.replace("*/", "*\\/").replace("/*", "/\\*") if isinstance(value, str) else value


def _environment() -> jinja2.Environment:
    env = jinja2.Environment(
        loader=jinja2.FileSystemLoader(str(templates_dir())),
        undefined=jinja2.StrictUndefined,
        keep_trailing_newline=True,
        trim_blocks=True,
        lstrip_blocks=True,
        finalize=_comment_safe,
    )
    env.filters["chunks"] = _chunks
    return env


def render_config(robot: Any, gaits_by_direction: Mapping[str, Sequence[Any]], board: Any) -> dict[str, str]:
    """Filename → text of ``robot_config.h`` and ``gait_table.c`` for this robot on this board.

    ``gaits_by_direction`` is ``{"+x": gaits, "-x": gaits}``; when it is a
    ``FirmwareGaits`` (``firmware_gaits``) its selection is named in both headers.
    Raises BuildError when the robot does not fit what the firmware supports (thresholds
    near ±90°, more states than 65535, a channel the board lacks, a pin the HAL cannot drive).
    """
    ctx = render_context(robot, gaits_by_direction, board).template_vars()
    env = _environment()
    return {
        "robot_config.h": env.get_template("robot_config.h.j2").render(generator=GENERATOR, **ctx),
        "gait_table.c": env.get_template("gait_table.c.j2").render(generator=GENERATOR, **ctx),
    }
