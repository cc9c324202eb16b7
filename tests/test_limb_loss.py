"""Issue 15, limb loss: the fallback model against the paper's one-actuator robot, the
run-time limb→actuator map in the firmware, and R1 walking on after a dead coil, with the
host replanning and without a host (the firmware's build-time fallback)."""

from __future__ import annotations

from pathlib import Path

import pytest

from proleg.learn.replan import Replanner, replan
from proleg.limbloss import compiled_map, fallback, remap, remapped_table
from proleg.link.client import CommandRefused, Received, RobotClient
from proleg.link.listeners import Listener
from proleg.link.sim_link import SimLink
from proleg.protocol.definition import GAIT_USER, ClearWhat, ErrorCode, EventKind
from proleg.report import run_gait_on
from proleg.robot import load_robot
from proleg.sim.simulators import open_host_sim
from proleg.states import limb_levels

ROOT = Path(__file__).resolve().parents[1]
R1 = ROOT / "robots" / "paper-r1.toml"


def _pairs(t):
    return {(t.label(int(a)), t.label(int(b))) for a, b in zip(t.src, t.dst)}


def test_r1_without_its_right_coil_remapped_is_the_papers_one_actuator_robot():
    r1 = load_robot(R1)
    one = load_robot(ROOT / "robots" / "paper-r1-one-actuator.toml")
    assert remap(r1, 1) == (0, 0)
    assert _pairs(remapped_table(r1, (0, 0))) == _pairs(one.transitions)
    fb = fallback(r1, "sma-right", "+x")
    assert fb.mode == "remap" and fb.actuator_map == (0, 0)
    assert [fb.table.label(s) for s in fb.states] == ["10", "11", "10"] and fb.rate == pytest.approx(0.5)
    assert fallback(r1, "sma-right", "-x").states is None
    assert replan(r1, "sma-right").actuator_map == (0, 0)


def _reach_levels(robot, limb, coil):
    """How many of ``limb``'s entry edges (ψ* + hysteresis/2) the physical plant's body bends it
    past when coil ``coil`` alone is fully contracted (posed, not heated): the oracle for
    ``limbloss.foreign_top_level``, read from the plant rather than from the same formula."""
    from proleg.sim.closed_loop import make_plant

    plant = make_plant(robot, "physical")  # with the robot file's [plant] (overlap_mm, length_mm)
    plant.pose([1.0 if j == coil else 0.0 for j in range(len(robot.actuators))])
    psi = float(plant.psi_deg[limb])
    lb = robot.limbs[limb]
    return sum(1 for star in lb.psi_star_deg if star + lb.hysteresis_deg / 2 <= psi)


def _own_levels_oracle(robot, foreign, coil, level):
    """The level each own limb of ``coil`` reads (from above: ψ ≥ ψ* − hysteresis/2, at least
    1) when the coil is contracted just enough to lift ``foreign`` to ``level``: bisected on
    the physical plant's posed body, not from ``limbloss``'s proportion."""
    from proleg.sim.closed_loop import make_plant

    plant = make_plant(robot, "physical")
    lf = robot.limbs[foreign]
    edge = lf.psi_star_deg[level - 1] + lf.hysteresis_deg / 2

    def psi(c):
        plant.pose([c if j == coil else 0.0 for j in range(len(robot.actuators))])
        return [float(x) for x in plant.psi_deg]

    lo, hi = 0.0, 1.0
    for _ in range(30):
        mid = (lo + hi) / 2
        lo, hi = (lo, mid) if psi(mid)[foreign] >= edge else (mid, hi)
    at = psi(hi)
    own = compiled_map(robot)
    return {m: max(1, sum(1 for st in robot.limbs[m].psi_star_deg if st - robot.limbs[m].hysteresis_deg / 2 <= at[m]))
            for m in range(len(own)) if own[m] == coil}


def test_remapped_table_matches_a_brute_force_of_its_rule(tmp_path):
    """Foreign limbs rise only after every own limb of their coil, to at least the level the
    coil's contraction then bends it to, never together with another limb of that coil, and
    no higher than their new coil lifts them: checked state by state on the four-limb
    caterpillar with coils reaching 20 mm past their half of the body (on the example's 8 mm
    a neighbour's coil lifts no limb past its first edge: no remap at all)."""
    text = (ROOT / "robots" / "caterpillar-4.toml").read_text()
    assert all(remap(load_robot(ROOT / "robots" / "caterpillar-4.toml"), a) is None for a in range(4))
    path = tmp_path / "caterpillar-reach.toml"
    path.write_text(text.replace("[plant]\n", "[plant]\noverlap_mm = 20\n", 1))
    robot = load_robot(path)
    own = compiled_map(robot)
    tops_seen = set()
    for lost in range(len(robot.actuators)):
        new = remap(robot, lost)
        assert new is not None and lost not in new
        got = _pairs(remapped_table(robot, new, lost, body=False))
        assert _pairs(remapped_table(robot, new, lost)) <= got  # the body only takes away
        t = robot.transitions
        want = set()
        for a, b in zip(t.src.tolist(), t.dst.tolist()):
            la, lb = limb_levels(a, t.levels), limb_levels(b, t.levels)
            ok = True
            for coil in set(new):
                limbs = [i for i in range(len(new)) if new[i] == coil]
                foreign = [i for i in limbs if own[i] != coil]
                mine = [i for i in limbs if own[i] == coil]
                for lv in (la, lb):
                    if any(lv[m] < _own_levels_oracle(robot, f, coil, lv[f])[m]
                           for f in foreign if lv[f] for m in mine):
                        ok = False
                    if any(lv[f] > _reach_levels(robot, f, coil) for f in foreign):
                        ok = False
                changed = [i for i in limbs if la[i] != lb[i]]
                if set(changed) & set(foreign) and len(changed) > 1:
                    ok = False
                tops_seen.update(_reach_levels(robot, f, coil) for f in foreign)
            if ok:
                want.add((t.label(a), t.label(b)))
        assert got == want
    assert min(tops_seen) >= 1


def test_a_limb_a_partial_remap_leaves_on_the_lost_coil_stays_down(tmp_path):
    """Tail and rear share sma-tail; without it the front coil can lift the rear proleg but
    no coil can lift the tail: the rear is remapped, the tail stays on the lost coil, and no
    transition of the remapped table (nor of the fallback's) raises the tail."""
    text = (ROOT / "robots" / "caterpillar-4.toml").read_text()
    text = text.replace('levels = 3\npsi_star_deg = [12.0, 24.0]\nhysteresis_deg = 2.0\nactuator = "sma-rear"',
                        'levels = 3\npsi_star_deg = [12.0, 24.0]\nhysteresis_deg = 2.0\nactuator = "sma-tail"', 1)
    text = text.replace('[[actuator]]\nname = "sma-rear"\nchannel = 1\n\n', "")
    path = tmp_path / "shared-tail.toml"
    path.write_text(text.replace("[plant]\n", "[plant]\noverlap_mm = 20\n", 1))
    robot = load_robot(path)
    assert compiled_map(robot) == (0, 0, 1, 2)
    new = remap(robot, 0)
    assert new == (0, 1, 1, 2)  # the rear proleg to sma-front; the tail left on sma-tail
    t = remapped_table(robot, new, 0)
    assert t.n_transitions > 0
    assert all(limb_levels(int(x), t.levels)[0] == 0 for x in (*t.src, *t.dst))
    for direction in ("+x", "-x"):
        fb = fallback(robot, 0, direction)
        assert all(limb_levels(int(x), fb.table.levels)[0] == 0 for x in (*fb.table.src, *fb.table.dst))


@pytest.mark.parametrize("name, lost", [("inchworm-3", "sma-middle"), ("caterpillar-4", "sma-front")])
def test_no_remap_onto_a_coil_that_cannot_lift_the_limb(name, lost):
    """On the three- and four-limb examples a neighbour's coil lifts a limb 8–17°, short of
    its first edge (21°, 13°): the fallback leaves the limb down ("dead") rather than heat a
    healthy coil to its on-time limit and then blame it."""
    robot = load_robot(ROOT / "robots" / f"{name}.toml")
    lost_i = [a.name for a in robot.actuators].index(lost)
    amap = compiled_map(robot)
    for i, a in enumerate(amap):
        if a == lost_i:
            assert all(_reach_levels(robot, i, c) == 0 for c in set(amap) - {lost_i})
    for direction in ("+x", "-x"):
        assert fallback(robot, lost, direction).mode == "dead"


def test_after_a_coil_dies_on_the_inchworm_no_healthy_coil_is_driven_to_its_limit_or_blamed(capsys):
    """Before, the firmware fell back to a remap onto sma-tail, heated it to its on-time
    limit (SMA_ON_LIMIT on actuator 0) and then suspected it. Now every fault names the
    dead coil or its limb (both index 1 on the inchworm)."""
    import json

    from proleg.cli import main

    main(["sim", "inchworm-3", "--inject", "dead-actuator:sma-middle+5", "--duration", "30", "--json"])
    faults = json.loads(capsys.readouterr().out)["faults"]
    assert faults and all(f["detail"] == 1 for f in faults), faults


def test_a_far_limb_remapped_onto_a_three_level_limbs_coil_rises_only_with_that_limb_at_its_top(capsys):
    """A three-level rear pad (ψ* 10°, 22°) and a binary front pad: without the front coil the
    rear coil lifts the front end, but only contracted to ≈ 52° at its own end, where the rear
    pad reads level 2. The remap let the rear pad sit at level 1 with the front end up (11),
    so the fallback 10 20 21 11 10 held the rear coil at full stroke into SMA_ON_LIMIT and then
    blamed the healthy coil (21 -> 11 failed). Now 11 and 01 are out of the remap, and no
    fault names the rear coil."""
    import json

    from proleg.cli import main

    path = Path(__file__).parent / "fixtures" / "l3-l2.toml"
    robot = load_robot(path)
    assert remap(robot, 1) == (0, 0)
    t = remapped_table(robot, (0, 0), 1)
    assert {(t.label(int(a)), t.label(int(b))) for a, b in zip(t.src, t.dst)} == {
        ("00", "10"), ("10", "00"), ("10", "20"), ("20", "10"), ("20", "21"), ("21", "20")}
    main(["sim", str(path), "--inject", "dead-actuator:b+1", "--duration", "40", "--json"])
    faults = json.loads(capsys.readouterr().out)["faults"]
    assert faults and all(f["detail"] == 1 for f in faults), faults  # the front coil (b) or its limb


@pytest.fixture
def r1_sim():
    return open_host_sim(load_robot(R1))


def test_the_actuator_map_is_a_run_time_setting_checked_by_the_firmware(r1_sim):
    sim = r1_sim
    client = RobotClient(SimLink(sim, step_s=sim.plant_dt_s), max_limbs=2, max_channels=2)
    client.connect()
    m = client.request("GET_ACTUATOR_MAP")
    assert tuple(m.actuators) == (0, 1) and m.lost == 0xFF
    client.request("SET_ACTUATOR_MAP", actuators=(0, 0))
    assert tuple(client.request("GET_ACTUATOR_MAP").actuators) == (0, 0)
    with pytest.raises(CommandRefused) as e:
        client.request("SET_ACTUATOR_MAP", actuators=(0, 2))
    assert e.value.error == ErrorCode.OUT_OF_RANGE and e.value.detail == 1
    with pytest.raises(CommandRefused) as e:
        client.request("SET_ACTUATOR_MAP", actuators=(0,))
    assert e.value.error == ErrorCode.OUT_OF_RANGE and e.value.detail == 0xFFFF
    client.start(0, "+x")
    with pytest.raises(CommandRefused) as e:
        client.request("SET_ACTUATOR_MAP", actuators=())
    assert e.value.error == ErrorCode.NOT_ALLOWED
    client.request("STOP")
    client.request("SET_ACTUATOR_MAP", actuators=())
    assert tuple(client.request("GET_ACTUATOR_MAP").actuators) == (0, 1)


def test_with_the_map_swapped_the_right_coil_raises_the_left_limb(r1_sim):
    """The map is what the controller uses: swapped, the left limb's rise heats channel 1."""
    sim = r1_sim
    client = RobotClient(SimLink(sim, step_s=sim.plant_dt_s), max_limbs=2, max_channels=2)
    client.connect()
    client.request("SET_ACTUATOR_MAP", actuators=(1, 0))
    client.load_gait([0, 2])  # 00 → 10: raise the left limb
    client.start("user", "+x")
    duties = []
    t_end = client.link.clock() + 0.5
    while client.link.clock() < t_end:
        rx = client.recv_received(0.1)
        if rx is not None and rx.message.name == "TELEMETRY":
            duties.append(tuple(rx.message.duty))
    client.request("STOP")
    assert duties and max(d[1] for d in duties) > 0 and max(d[0] for d in duties) == 0


class _Track(Listener):
    """Injects a fault at a virtual time and records (time, displacement, events)."""

    def __init__(self, sim, at_s: float, fault: str):
        self.sim, self.at_s, self.fault = sim, at_s, fault
        self.injected_s: float | None = None
        self.points: list[tuple[float, float]] = []
        self.events: list[tuple[float, int, int]] = []
        self.cycle_s: list[float] = []

    def on_message(self, rx: Received) -> None:
        t = self.sim.time_s
        if self.injected_s is None and t >= self.at_s:
            self.sim.inject(self.fault)
            self.injected_s = t
        self.points.append((t, self.sim.plant.displacement_mm))
        m = rx.message
        if m.name == "EVENT":
            self.events.append((t, m.kind, m.code))
            if m.kind == EventKind.STATE_REACHED and m.code == 0:
                self.cycle_s.append(t)

    def moved_between(self, t0: float, t1: float) -> float:
        inside = [x for t, x in self.points if t0 <= t <= t1]
        return max(inside) - min(inside) if inside else 0.0

    def gain_after(self, t0: float, t1: float) -> float:
        before = [x for t, x in self.points if t <= t0]
        after = [x for t, x in self.points if t <= t1]
        return after[-1] - before[-1]


def _walk_with_dead_right_coil(robot, *, replanning: bool, seconds: float = 40.0):
    sim = open_host_sim(robot)
    client = RobotClient(SimLink(sim, step_s=sim.plant_dt_s), max_limbs=2, max_channels=2)
    client.connect()
    track = _Track(sim, 10.0, "dead-actuator:sma-right")
    said: list[str] = []
    replanner = Replanner(robot, client, "+x", say=said.append) if replanning else None
    run = run_gait_on(client, 0, "+x", seconds, listeners=[track], replanner=replanner)
    cycle = (track.cycle_s[2] - track.cycle_s[0]) / 2  # healthy cycle time
    return run, track, said, cycle


def _moving_on(track, cycle):
    """+x progress in the window that ends three healthy gait cycles after the loss."""
    t_loss = track.injected_s
    fault_t = next(t for t, k, _ in track.events if k == EventKind.FAULT and t > t_loss)
    restart = next(t for t, k, _ in track.events if k == EventKind.GAIT_STARTED and t > fault_t)
    return restart, track.gain_after(restart, t_loss + 3 * cycle), track.gain_after(restart, track.points[-1][0])


def test_without_a_host_the_firmware_falls_back_and_r1_keeps_moving_plus_x():
    robot = load_robot(R1)
    run, track, _, cycle = _walk_with_dead_right_coil(robot, replanning=False)
    kinds = [k for _, k, _ in track.events]
    assert EventKind.SUSPECT in kinds and EventKind.FALLBACK in kinds
    assert next(c for _, k, c in track.events if k == EventKind.FALLBACK) == 1  # sma-right
    restart, within3, total = _moving_on(track, cycle)
    assert restart - track.injected_s < 3 * cycle
    assert within3 > 0.5, f"+{within3:.2f} mm within three cycles ({cycle:.1f} s each) of the loss"
    assert total > 5.0


def test_a_coil_given_up_stays_given_up_until_the_operator_takes_it_back():
    """After the firmware fell back, START of a built-in gait used to go back to the build's map
    by itself: a host restarting gait 0 every 3-4.5 s past a dead coil heated it up to the state
    timeout at every START (58-73 % of the time), each fault ending in another fallback rather
    than a latch. Now a built-in gait is refused (NOT_ALLOWED, detail 3) until SET_ACTUATOR_MAP
    with no entries takes the coil back (a wrongly suspected or mended coil); the fallback gait
    (the loaded one) still runs."""
    robot = load_robot(R1)
    sim = open_host_sim(robot)
    client = RobotClient(SimLink(sim, step_s=sim.plant_dt_s), max_limbs=2, max_channels=2)
    client.connect()
    track = _Track(sim, 10.0, "dead-actuator:sma-right")
    run_gait_on(client, 0, "+x", 30.0, listeners=[track])
    assert EventKind.FALLBACK in [k for _, k, _ in track.events]
    m = client.request("GET_ACTUATOR_MAP")
    assert tuple(m.actuators) == (0, 0) and m.lost == 1  # the fallback's remap while it runs
    client.request("STOP")
    client.request("CLEAR", what=int(ClearWhat.FAULTS))  # a bare CLEAR: no fault is latched, nothing taken back
    with pytest.raises(CommandRefused) as refused:  # a built-in gait: refused for the coil given up
        client.request("START", gait=0, direction=0)
    assert (refused.value.error, refused.value.detail) == (ErrorCode.NOT_ALLOWED, 3)
    assert "fallback gave up a coil" in str(refused.value)
    with pytest.raises(CommandRefused) as refused:  # none such: NO_GAIT, as at any other time
        client.request("START", gait=77, direction=0)
    assert (refused.value.error, refused.value.detail) == (ErrorCode.NO_GAIT, 77)
    m = client.request("GET_ACTUATOR_MAP")
    assert tuple(m.actuators) == (0, 0) and m.lost == 1  # the dead coil is still given up
    client.request("START", gait=GAIT_USER, direction=0)  # the fallback gait runs on
    client.request("STOP")
    assert client.clear()  # the operator's clear (console key c) takes the coil back: SET_ACTUATOR_MAP, no entries
    assert not client.clear()  # nothing left to take back
    m = client.request("GET_ACTUATOR_MAP")
    assert tuple(m.actuators) == (0, 1) and m.lost == 0xFF
    client.request("START", gait=0, direction=0)
    client.request("STOP")


def test_with_the_fallback_off_the_host_replans_and_r1_keeps_moving_plus_x(tmp_path):
    text = R1.read_text().replace("telemetry_hz = 50", "telemetry_hz = 50\nfallback = false")
    p = tmp_path / "paper-r1.toml"
    p.write_text(text)
    robot = load_robot(p)
    run, track, said, cycle = _walk_with_dead_right_coil(robot, replanning=True)
    assert EventKind.FALLBACK not in [k for _, k, _ in track.events]
    assert any("suspects sma-right" in s for s in said), said
    assert any("loaded and started 10→11→10" in s for s in said), said
    restart, within3, total = _moving_on(track, cycle)
    assert within3 > 0.5, f"+{within3:.2f} mm within three cycles ({cycle:.1f} s each) of the loss; {said}"
    assert total > 5.0


def test_with_the_fallback_off_and_no_replanning_r1_stops_for_good(tmp_path):
    text = R1.read_text().replace("telemetry_hz = 50", "telemetry_hz = 50\nfallback = false")
    p = tmp_path / "paper-r1.toml"
    p.write_text(text)
    run, track, _, _ = _walk_with_dead_right_coil(load_robot(p), replanning=False, seconds=30.0)
    assert track.moved_between(22.0, 30.0) < 0.2


def test_a_loaded_gait_whose_way_is_unstated_neither_falls_back_nor_is_replanned():
    """A learning probe (START of the loaded gait, its way unstated) walks neither way: on an
    actuator loss the firmware keeps the fault latched instead of walking a +x fallback, and
    the host does not replan a gait of no known direction."""
    from proleg.link.direction import UNSTATED
    from proleg.protocol.definition import GAIT_USER

    robot = load_robot(R1)  # fallback on
    sim = open_host_sim(robot)
    client = RobotClient(SimLink(sim, step_s=sim.plant_dt_s), max_limbs=2, max_channels=2)
    client.connect()
    client.load_gait([0, 2, 1])
    track = _Track(sim, 5.0, "dead-actuator:sma-right")
    said: list[str] = []
    replanner = Replanner(robot, client, None, say=said.append)
    run_gait_on(client, GAIT_USER, UNSTATED, 30.0, listeners=[track], replanner=replanner)
    kinds = [k for _, k, _ in track.events]
    assert EventKind.FAULT in kinds and EventKind.FALLBACK not in kinds
    assert kinds.count(EventKind.GAIT_STARTED) == 1, kinds  # nothing restarted it
    assert any("way was not stated" in s and "not replanning" in s for s in said), said
    with pytest.raises(ValueError, match=r"expected \+x, -x or None"):
        Replanner(robot, client, UNSTATED)


def test_learned_on_the_physical_plant_walks_at_least_as_fast_as_the_hand_made_matrix(tmp_path):
    """Learn R1 on the physical plant (R = 3), then walk its learned firmware gait and the
    hand-made matrix's for 40 s each: the learned one covers at least as much ground (5 %
    allowance for the plant's noise)."""
    from proleg.cli.main import main
    from proleg.report import SimSession

    log = tmp_path / "trials.jsonl"
    out = tmp_path / "learned.toml"
    assert main(["learn", str(R1), "--sim", "--plant", "physical", "--log", str(log), "--repeats", "3",
                 "--out", str(out), "-q"]) == 0
    speeds = {}
    for name, path in (("hand", R1), ("learned", out)):
        run = SimSession(open_host_sim(load_robot(path))).run_gait("+x", 0, 40.0)
        assert run.cycles >= 3, (name, run)
        speeds[name] = run.displacement_mm / 40.0
    assert speeds["learned"] >= 0.95 * speeds["hand"] > 0, speeds


def test_suspect_and_fallback_events_are_shown_by_name():
    from proleg.console.names import RobotNames, describe_event

    r1 = load_robot(R1)
    names = RobotNames.for_robot(r1)
    lab = r1.transitions.label
    text = describe_event({"time_ms": 20000, "kind": int(EventKind.SUSPECT), "code": 1, "detail": 2 * 4 + 3},
                          names, lab)
    assert text.endswith("suspects sma-right (transition 10→11 failed)")
    text = describe_event({"time_ms": 20000, "kind": int(EventKind.FALLBACK), "code": 1, "detail": 2}, names, lab)
    assert "FALLBACK: gave up sma-right, runs its 2-step fallback gait" in text
    text = describe_event({"time_ms": 1, "kind": int(EventKind.SUSPECT), "code": 0xFF, "detail": 0xFFFF}, names)
    assert "suspects no actuator" in text


def test_proleg_run_replans_by_default_and_says_so_in_its_result(capsys):
    import json

    from proleg.cli.main import main

    assert main(["run", str(R1), "--sim", "--duration", "2", "--format", "jsonl"]) == 0
    result = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert result["msg"] == "RESULT" and result["replanned"] == []  # nothing lost, nothing done
    assert main(["run", str(R1), "--sim", "--duration", "1", "--no-replan"]) == 0


def test_proleg_sim_shows_the_suspect_and_the_fallback_by_name(capsys):
    from proleg.cli.main import main

    assert main(["sim", str(R1), "--duration", "30", "--inject", "dead-actuator:sma-right+10"]) in (0, 1)
    out = capsys.readouterr().out
    assert "suspects sma-right (transition 10→11 failed)" in out
    assert "FALLBACK: gave up sma-right" in out


def test_a_replanning_host_leaves_a_firmware_fallback_alone():
    run, track, said, _ = _walk_with_dead_right_coil(load_robot(R1), replanning=True, seconds=25.0)
    assert any("fell back by itself" in s and "10→11→10" in s for s in said), said
    assert not any(s.startswith("loaded and started") for s in said), said


def test_a_second_loss_is_replanned_without_the_first_coil_too():
    """caterpillar-4 without its tail coil walks on its rear, front and head coils; without its
    head coil too, the best gait without the head alone raises the tail. The replanner planned
    each loss on its own: after the second it mapped the dead tail coil back in, cleared the
    fault itself and heated that coil at the drive duty up to the state timeout again."""
    cat4 = load_robot(ROOT / "robots" / "caterpillar-4.toml")
    alone = replan(cat4, "sma-head", "+x")
    assert any(limb_levels(s, cat4.levels)[0] > 0 for s in alone.states)  # the tail rises
    plan = replan(cat4, "sma-head", "+x", lost_before=["sma-tail"])
    assert plan.states is not None and plan.reason.startswith("without sma-head and sma-tail: gait")
    assert not any(limb_levels(s, cat4.levels)[i] > 0 for s in plan.states for i in (0, 3))
    assert replan(cat4, "sma-head", "+x", lost_before=["sma-head"]).states == alone.states  # itself: no other
    r1 = load_robot(R1)
    assert replan(r1, "sma-right", "+x", lost_before=["sma-left"]).states is None


def test_after_a_second_loss_the_replanning_host_never_heats_the_first_dead_coil_again(tmp_path):
    """End to end, with the fallback off: the tail coil dies, the host replans; the head coil
    dies, the host replans again. From the first fault on the dead tail coil is never driven
    above the hold ceiling (it was for 9 s, until a third fault, after the second replan)."""
    text = (ROOT / "robots" / "caterpillar-4.toml").read_text()
    assert "telemetry_hz = 25" in text
    p = tmp_path / "caterpillar-4.toml"
    p.write_text(text.replace("telemetry_hz = 25", "telemetry_hz = 25\nfallback = false"))
    robot = load_robot(p)
    sim = open_host_sim(robot)
    client = RobotClient(SimLink(sim, step_s=sim.plant_dt_s), max_limbs=4, max_channels=4)
    client.connect()
    said: list[str] = []
    hold_ceiling_pm = 3000  # the default hold ceiling (caterpillar-4's [safety] leaves it)
    tail_duty: list[tuple[float, int]] = []
    events: list[tuple[float, int, int]] = []

    class Losses(Listener):
        def on_message(self, rx: Received) -> None:
            t = sim.time_s
            if t >= 10.0 and not hasattr(self, "first"):
                sim.inject("dead-actuator:sma-tail")
                self.first = t
            replanned = [s for s in said if s.startswith("loaded and started")]
            if len(replanned) == 1 and not hasattr(self, "second") and t >= self.first + 20.0:
                sim.inject("dead-actuator:sma-head")
                self.second = t
            m = rx.message
            if m.name == "TELEMETRY":
                tail_duty.append((t, m.duty[0]))
            elif m.name == "EVENT":
                events.append((t, m.kind, m.code))

    losses = Losses()
    run_gait_on(client, 0, "+x", 90.0, listeners=[losses], replanner=Replanner(robot, client, "+x", say=said.append))
    assert hasattr(losses, "second"), said
    faults = [t for t, k, _ in events if k == EventKind.FAULT]
    assert len(faults) == 2, (faults, said)  # one a loss: the second plan raised the tail and faulted again
    assert any(s.startswith("replanning: without sma-head and sma-tail: gait") for s in said), said
    assert [s for s in said if s.startswith("loaded and started")][-1] == "loaded and started 0110→0210→0220→0120→0110 in +x"
    assert max(d for t, d in tail_duty if t > faults[0]) <= hold_ceiling_pm


def test_the_build_says_which_fallbacks_the_firmware_carries(tmp_path):
    from proleg.firmware.gaits import fallback_lines

    r1 = load_robot(R1)
    assert fallback_lines(r1) == [
        "fallback without sma-left (-x): 01 11 01 (remap: left→sma-right, right→sma-right)",
        "fallback without sma-right (+x): 10 11 10 (remap: left→sma-left, right→sma-left)",
    ]
    # a coil lost with its limbs left down: those limbs, not the whole map read as "dead: …"
    i3 = fallback_lines(load_robot(R1.parent / "inchworm-3.toml"))
    assert "fallback without sma-tail (+x): 000 010 011 001 000 (tail left down)" in i3, i3
    p = tmp_path / "paper-r1.toml"
    p.write_text(R1.read_text().replace("telemetry_hz = 50", "telemetry_hz = 50\nfallback = \"yes\""))
    from proleg.errors import RobotFileError

    with pytest.raises(RobotFileError, match=r"control\.fallback: expected true or false"):
        load_robot(p)
    p.write_text(R1.read_text().replace("telemetry_hz = 50", "telemetry_hz = 50\nfallback = false"))
    assert fallback_lines(load_robot(p)) == ["fallback gaits: off ([control] fallback = false)"]


def test_a_timeout_with_every_limb_at_its_level_suspects_no_coil_and_does_not_fall_back(tmp_path):
    """IMU noise (5°) wider than inchworm-3's 2° bands, no debounce (one sample is a level change,
    and an excursion that unsettles a limb) and a hold_ms of 1 s: limbs reach their levels but
    rarely stay settled for the hold, and the step times out (3 s away from its target, not the
    file's 8 s: time at the target does not count). Whether a limb is off its level at the tick
    of the timeout is up to the noise, so the run is repeated with fresh noise until a timeout
    comes with every limb at its level. That used to name limb 0 (whose coil was off), suspect
    its healthy coil and fall back without it."""
    from proleg.console.names import RobotNames, describe_event, event_text
    from proleg.protocol.definition import FaultCode
    from proleg.sim.closed_loop import SimulatedRobot

    text = (ROOT / "robots" / "inchworm-3.toml").read_text()
    edits = {"debounce_ticks = 5": "debounce_ticks = 1", "hold_ms = 100": "hold_ms = 1000",
             "state_timeout_ms = 8000": "state_timeout_ms = 3000"}
    for old, new in edits.items():
        assert old in text
        text = text.replace(old, new)
    path = tmp_path / "inchworm-3.toml"
    path.write_text(text)
    robot = load_robot(path)

    def run(seed: int) -> list:
        sim = SimulatedRobot(robot, conditions=["imu_noise_deg=5"], seed=seed)
        client = RobotClient(SimLink(sim, step_s=sim.plant_dt_s))
        client.connect()
        client.start(0, "+x")
        events = []
        end = client.link.clock() + 40.0
        while client.link.clock() < end and not any(m.kind == EventKind.SUSPECT for m in events):
            m = client.recv(0.5)
            if m is not None and m.name == "EVENT":
                events.append(m)
        client.close()
        timeout = [m for m in events if m.kind == EventKind.FAULT and m.code == FaultCode.STATE_TIMEOUT]
        assert timeout, [(EventKind(m.kind).name, m.code, m.detail) for m in events]
        return events

    for seed in range(1, 13):
        events = run(seed)
        if next(m for m in events if m.kind == EventKind.FAULT).detail == 0xFF:
            break
    else:
        pytest.fail("no timeout with every limb at its level in 12 noisy runs")
    suspect = next(m for m in events if m.kind == EventKind.SUSPECT)
    assert suspect.code == 0xFF
    assert not [m for m in events if m.kind == EventKind.FALLBACK]
    # measured = target: the text said "transition 110→110 failed"; it is the state it is in
    n = robot.transitions.n_states
    assert suspect.detail // n == suspect.detail % n
    said = event_text({"time_ms": 1, "kind": int(EventKind.SUSPECT), "code": 0xFF, "detail": suspect.detail},
                      RobotNames.for_robot(robot), robot.transitions.label)
    assert said == f"suspects no actuator (in state {robot.transitions.label(suspect.detail % n)}, the step's target)"
    text = describe_event({"time_ms": 1, "kind": int(EventKind.FAULT), "code": int(FaultCode.STATE_TIMEOUT),
                           "detail": 0xFF}, RobotNames.for_robot(robot))
    assert "every limb at its level, one would not settle" in text


def test_a_remap_whose_coil_would_hold_the_body_up_is_not_used(tmp_path):
    """inchworm-3 on a 160 mm body: the middle coil alone lifts the head past its band, so the
    head was remapped onto it without its own coil, but the contraction that holds the head up
    bends the middle limb to 60° and keeps the tail above its band: 111 -> 011 never finished,
    the middle coil ran into its on-time limit and the fault blamed the tail. The remapped
    table now keeps only what the body lets the remapped robot hold and finish."""
    robot_path = tmp_path / "iw160.toml"
    robot_path.write_text((ROOT / "robots" / "inchworm-3.toml").read_text().replace("[plant]", "[plant]\nlength_mm = 160", 1))
    robot = load_robot(robot_path)
    lost = [a.name for a in robot.actuators].index("sma-head")
    new_map = remap(robot, lost)
    assert new_map is not None  # the middle coil reaches the head on this body
    t = robot.transitions
    table = remapped_table(robot, new_map, lost)
    allowed = {(t.label(int(a)), t.label(int(b))) for a, b in zip(table.src, table.dst)}
    # 011: the middle coil holding the head up lifts the tail to 23.5°, past its band
    assert not any("011" in pair for pair in allowed) and ("110", "111") in allowed
    fb = fallback(robot, lost, "+x")
    assert fb.mode == "dead" or fb.states is None or all(
        (t.label(a), t.label(b)) in allowed for a, b in zip(fb.states, fb.states[1:]))


def test_the_fallback_does_not_heat_a_coil_for_the_limb_whose_coil_it_gave_up(capsys, tmp_path):
    """R2 without its boost, with a mismatched pair (a sweep row, docs/plant.md "Off the grid"):
    the weak left coil times out and is given up; the fallback raises both ends with the right
    coil, which lifts the left end through the body to 23.8°, short of its hold edge (25°). The
    firmware heated the right coil on toward that edge, after its own end had topped out, for
    the rest of each step: 128-130 °C every cycle. Now a limb whose coil was given up asks for no
    hold heat. With the boost (R2's default) the weak coil makes its rises at the duty ceiling
    and nothing is given up."""
    import re

    from proleg.cli.main import main

    row = ["--calibrated", "--duration", "40", "--condition", "coil_mismatch=0.30", "--condition", "mass_g=3.4",
           "--condition", "power_scale=rear:0.82"]
    r2 = ROOT / "robots" / "paper-r2.toml"
    rc = main(["sim", str(r2), *row])
    out = capsys.readouterr().out
    assert rc == 0 and "FALLBACK" not in out and int(re.search(r"cycles completed: (\d+)", out).group(1)) >= 4, out
    text = r2.read_text(encoding="utf-8")
    assert text.count("\n[control]\n") == 1
    no_boost = tmp_path / "paper-r2.toml"
    no_boost.write_text(text.replace("\n[control]\n", "\n[control]\nboost_ms = 0\n"), encoding="utf-8")
    rc = main(["sim", str(no_boost), *row])
    out = capsys.readouterr().out
    assert "FALLBACK: gave up sma-left" in out
    peak = int(re.search(r"sma-right (\d+) °C", out.split("coils, hottest:")[1]).group(1))
    assert peak < 100, out
    cycles = int(re.search(r"cycles completed: (\d+)", out).group(1))
    assert cycles >= 4 and rc == 1, out  # the STATE_TIMEOUT that gave the coil up is a fault


def test_the_dead_fallback_leaves_out_what_the_body_cannot_hold_or_end():
    """A three-limb robot (4, 3 and 2 levels) whose middle pad raised lifts the back pad past
    its edge (010, 011, 020, 021: load warnings, `unholdable` in every gait): without the back
    coil the firmware was built to fall back on +x 000 -> 010 -> 011 -> 001, through two of
    them, which would have ended in STATE_TIMEOUT too. The dead mode keeps the compiled map, so
    the intact body's states it cannot hold and steps it cannot end are out of its table."""
    from proleg.limbloss import dead_table

    robot = load_robot(ROOT / "tests" / "fixtures" / "crab-3-entry.toml")
    t = robot.transitions
    unheld = {t.label(s) for s in robot.unholdable}
    assert {"010", "011"} <= unheld and ("000", "010") in _pairs(t)
    for lost in range(len(robot.actuators)):
        pairs = _pairs(dead_table(robot, lost))
        assert pairs and not any(a in unheld or b in unheld for a, b in pairs), robot.actuators[lost].name
        assert not any((t.index(a), t.index(b)) in robot.blocked for a, b in pairs)
