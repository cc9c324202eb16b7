"""The live console: a textual UI on a ``RobotClient`` (``proleg console``), or one line per
telemetry frame (``--plain``, for pipes).

It is a listener like any other: a ``Notifier`` feeds ``ConsoleModel`` from the client's
message stream; the UI redraws from the model ten times a second, so a 1 kHz telemetry
stream costs the terminal nothing. Commands (start, stop, E-stop, clear) run on worker
threads, so the UI never blocks on a reply.

Keys: s start · x stop · e E-stop · c clear faults and E-stop · g next gait · d direction ·
q (or Ctrl-C) quit. ``g`` offers only the gaits INFO says the firmware has (and ``user`` once
a user gait is loaded, selected with its way unstated; ``d`` then cycles +x, -x, unstated).
Events name their kind, fault, stop reason, limb and actuator (``proleg.console.names``). The
layout fits an 80×24 terminal. Leaving stops the robot: that is ``console_main``'s job
(``proleg.link.leave``), whatever ended the UI.

Given the robot file (``robot``), the console replans after a limb loss unless told not to
(``replan=False``, ``--no-replan``): when a gait stops on a fault that names an actuator and
the firmware did not fall back by itself, ``proleg.console.replan.ReplanWorker`` loads and
starts the best gait of what the robot can still do. Each step shows in the events panel as
``host: …`` and in the status line; the "link · host" panel says whether replanning is on.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

from rich.text import Text
from textual.app import App, ComposeResult
from textual.binding import Binding
from textual.containers import Horizontal
from textual.css.query import NoMatches
from textual.widgets import Footer, Static

from ..errors import LinkError
from ..names import counted
from ..protocol.definition import DIR_UNSTATED, GAIT_USER, Direction, Flag
from ..states import label as state_label
from ..states import limb_levels, state_count
from ..link.client import RobotClient
from ..link.direction import direction_text
from ..link.listeners import CallbackListener, Listener, Notifier
from ..link.sim_link import temperature_key
from ..robot import Robot
from ..physics.materials import NITI_OVERHEAT_C
from .model import ConsoleModel, LimbView
from .names import RobotNames, gait_text, step_text
from .plain import replan_state
from .terminal import TerminalGone, UiLog
from .replan import ReplanWorker

BAR_WIDTH = 24


def _bar(fraction: float, width: int = BAR_WIDTH) -> str:
    fraction = min(1.0, max(0.0, fraction))
    full = round(fraction * width)
    return "█" * full + "░" * (width - full)


def _flags_text(flags: int) -> str:
    return " ".join(f.name.lower() for f in Flag if f & flags and f.name) or "-"


class ConsoleApp(App[None]):
    """The live console on one robot. ``names`` name limbs and actuators in events; the app
    exits by itself when the link is lost (``model.link_error``)."""

    def get_driver_class(self) -> Any:
        """Textual's driver for this platform, writing to the terminal through ``TerminalGone``."""
        base = super().get_driver_class()

        class Driver(base):  # type: ignore[misc, valid-type]
            def __init__(self, *args: Any, **kw: Any) -> None:
                super().__init__(*args, **kw)
                if getattr(self, "_file", None) is not None:
                    self._file = TerminalGone(self._file)

        return Driver

    CSS = """
    Screen { layout: vertical; }
    #top { height: 2; padding: 0 1; background: $boost; }
    #middle { height: auto; }
    .panel { border: round $primary; padding: 0 1; height: auto; }
    #limbs { width: 3fr; }
    #state { width: 2fr; }
    #duty { height: auto; }
    #bottom { height: 1fr; min-height: 4; }
    #events { width: 3fr; height: 1fr; }
    #counters { width: 2fr; height: 1fr; }
    #status { height: 1; padding: 0 1; color: $warning; }
    """
    BINDINGS = [
        Binding("s", "start", "Start"),
        Binding("x", "stop", "Stop"),
        Binding("e", "estop", "E-STOP"),
        Binding("c", "clear", "Clear"),
        Binding("g", "next_gait", "Gait"),
        Binding("d", "direction", "Dir"),
        Binding("q", "quit", "Quit"),
        Binding("ctrl+c", "quit", "Quit", show=False, priority=True),
    ]

    def __init__(self, client: RobotClient, *, limbs: Sequence[LimbView] = (), levels: Sequence[int] = (),
                 listeners: Sequence[Listener] = (), refresh_s: float = 0.1, names: RobotNames | None = None,
                 robot: Robot | None = None, replan: bool = True, duration_s: float | None = None):
        super().__init__()
        self.client = client
        #: leave after this many wall seconds (``--duration``), as the plain mode does
        self.duration_s = duration_s
        #: set from a signal handler (SIGHUP, SIGTERM): the next refresh leaves (``exit`` is not
        #: safe to call there: it may interrupt textual's own output code)
        self.leave_requested = False
        self.limb_views = list(limbs)
        self.levels = tuple(levels)
        if names is None:
            names = RobotNames(tuple(v.name for v in self.limb_views))
        self.model = ConsoleModel(info=client.info, names=names, state_label=self._state_text)
        self.extra_listeners = list(listeners)
        self.keep_open: list[Listener] = []  # listeners the caller stops itself (after the leaving STOP)
        self.refresh_s = refresh_s
        self.gait = 0
        self.direction = Direction.PLUS_X
        self.status = ""
        self.notifier: Notifier | None = None
        self.robot = robot
        self.replan = replan and robot is not None
        #: what the counters panel says about replanning (``replan_state``)
        self.replan_state = replan_state(replan, robot is not None)
        self.replanner: ReplanWorker | None = None
        #: proleg's log lines while the UI is up (``UiLog``)
        self.ui_log = UiLog(self.host_says, self._warn)

    # ------------------------------------------------------------------ layout
    def compose(self) -> ComposeResult:
        yield Static(id="top")
        with Horizontal(id="middle"):
            yield Static(id="limbs", classes="panel")
            yield Static(id="state", classes="panel")
        yield Static(id="duty", classes="panel")
        with Horizontal(id="bottom"):
            yield Static(id="events", classes="panel")
            yield Static(id="counters", classes="panel")
        yield Static(id="status")
        yield Footer()

    def on_mount(self) -> None:
        self.ui_log.install()
        info = self.client.info
        self.title = f"proleg console — {info.robot_name if info else self.client.link.description}"
        for wid, title in (("limbs", "limbs: ψ vs ψ*"), ("state", "robot state"), ("duty", "SMA duty"),
                           ("events", "events & faults"), ("counters", "link · host")):
            self.query_one(f"#{wid}", Static).border_title = title
        if self.replan and self.robot is not None:
            self.replanner = ReplanWorker(self.robot, self.client, say=self.host_says)
        self.notifier = Notifier(self.client, [CallbackListener(self.model.on_message, self.model.on_error),
                                               *self.extra_listeners,
                                               *([self.replanner] if self.replanner is not None else [])])
        self.refresh_view()
        self._timer = self.set_interval(self.refresh_s, self.refresh_view)
        if self.duration_s is not None:  # it was ignored here: a session meant to end ran on
            self.set_timer(self.duration_s, self.exit)

    def on_unmount(self) -> None:
        timer = getattr(self, "_timer", None)
        if timer is not None:
            timer.stop()
        if self.notifier is not None:
            self.notifier.stop(keep=self.keep_open)  # stops the listeners too, the replan worker among them
        self.ui_log.uninstall()  # said on stderr from now on; those said in the UI: replay, after run

    def _warn(self, text: str) -> None:
        self.notify(text, severity="warning", timeout=15)  # thread-safe (textual posts it to the app)

    def run(self, *args: Any, **kwargs: Any) -> Any:
        """``App.run``; then the log lines the UI showed are said on stderr as well."""
        try:
            return super().run(*args, **kwargs)
        finally:
            self.ui_log.replay()

    def host_says(self, text: str) -> None:
        """A line from the host (the replan worker's thread, a log line): events panel and status
        line."""
        self.model.note(f"host: {text}")
        self.status = text

    # ------------------------------------------------------------------ view
    def _n_limbs(self, tel: dict | None) -> int:
        if tel is not None:
            return len(tel["psi"])
        return self.client.info.limbs if self.client.info else len(self.limb_views)

    def _levels(self, n: int) -> tuple[int, ...]:
        return self.levels if len(self.levels) == n else (2,) * n

    def _label(self, state: int, n: int) -> str:
        try:
            return state_label(state, self._levels(n))
        except Exception:
            return str(state)

    def _state_text(self, state: int) -> str:
        return self._label(state, self._n_limbs(self.model.telemetry))

    def refresh_view(self) -> None:
        try:
            self._refresh_view()
        except NoMatches:  # a timer tick while the app is shutting down
            pass
        if (self.model.link_error is not None or self.leave_requested) and self.is_running:
            self.exit()  # the link is gone, or a signal asked to leave: console_main stops the robot

    def _refresh_view(self) -> None:
        tel, truth, events, faults = self.model.snapshot()
        info = self.client.info
        names = self.model.names
        top = Text()
        if info is not None:
            top.append(f"{info.robot_name}", style="bold")
            top.append(f" on {info.board} · {counted(info.limbs, 'limb')} · {counted(info.gaits, 'gait')} · {info.tick_hz} Hz tick\n"
                       f"build {info.build_id:08x} · gait table {info.gait_hash:08x} · {self.client.link.description}")
        else:
            top.append(self.client.link.description)
        self.query_one("#top", Static).update(top)

        n = self._n_limbs(tel)
        levels = self._levels(n)
        limbs = Text()
        if tel is None:
            limbs.append("waiting for telemetry…")
        else:
            measured = limb_levels(tel["measured"], levels) if tel["measured"] < state_count(levels) else (None,) * n
            target = limb_levels(tel["target"], levels) if tel["target"] < state_count(levels) else (None,) * n
            for i, p in enumerate(tel["psi"]):
                view = self.limb_views[i] if i < len(self.limb_views) else LimbView(names.limb(i), ())
                psi = p / 100
                stars = view.psi_star_deg
                star = "/".join(f"{s:.2f}°" for s in stars) if stars else "?"
                rel = "≥" if stars and psi >= stars[0] else ("<" if stars else " ")
                limbs.append(f"{view.name[:12]:<12} ψ{psi:7.2f}° {rel} ψ* {star:<6}  ")
                s_now, s_want = measured[i], target[i]
                limbs.append(f"S {s_now}→{s_want}", style="green" if s_now == s_want else "yellow")
                if i < len(tel["psi"]) - 1:
                    limbs.append("\n")
        self.query_one("#limbs", Static).update(limbs)

        state = Text()
        if tel is not None:
            ok = tel["measured"] == tel["target"]
            state.append("now ")
            state.append(self._label(tel["measured"], n), style="bold green" if ok else "bold yellow")
            state.append(f"  target {self._label(tel['target'], n)}\n")
            state.append(f"gait {gait_text(tel['gait'])} {direction_text(tel['direction'])} · {step_text(tel['step'])}\n")
            state.append(f"{_flags_text(tel['flags'])}\n",
                         style="bold red" if tel["flags"] & (Flag.ESTOP | Flag.FAULT) else "")
            if "displacement_mm" in truth:
                state.append(f"displacement {truth['displacement_mm']:.1f} mm (sim)\n")
        state.append(f"selected: gait {gait_text(self.gait)} {direction_text(self.direction)}", style="dim")
        self.query_one("#state", Static).update(state)

        duty = Text()
        if tel is not None:
            for j, dv in enumerate(tel["duty"]):
                duty.append(f"{names.actuator(j)[:16]:<16} ")
                duty.append(_bar(dv / 10000), style="red" if dv else "grey50")
                duty.append(f" {dv / 100:5.1f} %")
                temp = truth.get(temperature_key(names.actuator(j)))
                if temp is not None:  # the simulated coil's temperature: a real board senses none
                    duty.append(f"  {temp:4.0f} °C (sim)", style="bold red" if temp > NITI_OVERHEAT_C else "")
                if j < len(tel["duty"]) - 1:
                    duty.append("\n")
        self.query_one("#duty", Static).update(duty)

        panel = self.query_one("#events", Static)
        room = max(1, panel.content_region.height)
        latched = faults[-max(1, room // 2):] if faults else []  # latched faults stay in view
        n_recent = room - len(latched)
        recent = events[max(0, len(events) - n_recent):] if n_recent > 0 else []
        lines = [(line, "bold red") for line in latched] + [(line, "") for line in recent]
        ev = Text()
        for k, (line, style) in enumerate(lines):
            ev.append(("\n" if k else "") + line, style=style)
        panel.update(ev)

        st = self.client.stats
        counters = Text(
            f"telemetry {self.model.frame_rate():5.1f} fps\n"
            f"frames ok {st.frames_ok}\n"
            f"lost {st.lost} · corrupt {st.corrupt}\n"
            f"reconnects {st.reconnects} · timeouts {st.timeouts}\n"
            f"{self.replan_state}"
        )
        self.query_one("#counters", Static).update(counters)
        status = self.model.error or self.status
        self.query_one("#status", Static).update(status)

    # ------------------------------------------------------------------ commands
    def _command(self, what: str, call: Callable[[], object]) -> None:
        """Run ``call`` off the UI thread, saying so in the status line. Its "ok" replaces only
        its own "…" line: a warning the host said meanwhile (a recording that hit a full disk)
        stays in view, where the "ok" of the START that raced it used to replace it. A failure
        is always said."""
        pending = f"{what}…"

        def work() -> None:
            try:
                call()
                if self.status == pending:
                    self.status = f"{what}: ok"
            except LinkError as e:
                self.status = f"{what}: {e}"

        self.status = pending
        self.run_worker(work, thread=True, group="commands", exclusive=False)

    def action_start(self) -> None:
        gait, direction = self.gait, self.direction
        if gait not in self.gait_choices():
            self.status = "no gait to start: the firmware has none (load one with proleg load-gait)"
            return
        self._command(f"start gait {gait_text(gait)} {direction_text(direction)}",
                      lambda: self.client.start(gait, direction))

    def action_stop(self) -> None:
        self._command("stop", self.client.stop)

    def action_estop(self) -> None:
        self._command("E-STOP", self.client.estop)

    def action_clear(self) -> None:
        self._command("clear", self.client.clear)

    def gait_choices(self) -> list[int]:
        """The gaits ``g`` offers: 0 .. INFO's count − 1, and ``user`` once one is loaded."""
        info = self.client.info
        n = info.gaits if info else 0
        tel = self.model.telemetry
        user = bool(tel and tel["flags"] & Flag.USER_GAIT)
        return list(range(n)) + ([GAIT_USER] if user else [])

    def action_next_gait(self) -> None:
        choices = self.gait_choices()
        if not choices:
            self.status = "the firmware has no gaits (and no user gait is loaded)"
        else:
            idx = choices.index(self.gait) if self.gait in choices else -1
            self.gait = choices[(idx + 1) % len(choices)]
            # the loaded gait's way is not known here: unstated until d states it (the climb
            # guard checks a stated way); a built-in gait runs +x or -x
            if self.gait == GAIT_USER:
                self.direction = DIR_UNSTATED
            elif self.direction == DIR_UNSTATED:
                self.direction = Direction.PLUS_X
        self.refresh_view()

    def action_direction(self) -> None:
        """+x → -x (→ unstated, for the loaded gait) → +x."""
        ways = [Direction.PLUS_X, Direction.MINUS_X] + ([DIR_UNSTATED] if self.gait == GAIT_USER else [])
        self.direction = ways[(ways.index(self.direction) + 1) % len(ways)] if self.direction in ways else ways[0]
        self.refresh_view()
