"""``proleg sim --pty --inject FAULT+T``: timed injections are made T simulated seconds after
the pty starts serving (as without --pty and in ``proleg console --sim``), never dropped
silently; a bad one is refused before the pty opens."""

from __future__ import annotations

from pathlib import Path

from proleg.cli.main import main
from proleg.robot import load_robot
from proleg.sim.pty import PtyServer
from proleg.sim.simulators import open_simulated

R1 = Path(__file__).resolve().parents[1] / "robots" / "paper-r1.toml"


def test_the_pty_server_injects_a_timed_fault_once_its_time_has_come():
    sim = open_simulated(load_robot(R1), "host-sim")
    said: list[str] = []
    with PtyServer(sim, speed=20.0, faults=[(0.6, "link-drop:0.5"), (9.0, "link-corrupt:0.5")],
                   say=said.append) as server:
        server.serve(0.4)
        assert sim.link_faults.drop == 0 and said == []  # not yet
        server.serve(0.4)  # times count from the first serve: 0.8 s in all
        assert sim.link_faults.drop == 0.5
        assert said == ["injected link-drop:0.5 at 0.6 s (simulated)"]
        assert sim.link_faults.corrupt == 0 and server.due == [(9.0, "link-corrupt:0.5")]


def test_proleg_sim_pty_injects_timed_faults_and_names_those_it_could_not(capsys):
    rc = main(["sim", str(R1), "--pty", "--duration", "1", "--speed", "20",
               "--inject", "link-drop:0.5+0.5", "--inject", "dead-actuator:sma-right+5"])
    out, err = capsys.readouterr()
    assert rc == 0
    assert "injected link-drop:0.5 at 0.5 s (simulated)" in out
    assert "dead-actuator" not in out
    assert "proleg: not injected: dead-actuator:sma-right+5 (the simulation stopped at 1." in err


def test_a_timed_injection_naming_no_fault_is_refused_before_serving(capsys):
    rc = main(["sim", str(R1), "--pty", "--duration", "1", "--inject", "melt:sma-right+1"])
    out, err = capsys.readouterr()
    assert rc != 0 and "simulated" not in out
    assert err.strip().splitlines() == [
        "proleg: error: --inject melt:sma-right+1: unknown fault (expected one of: dead-actuator, drift, "
        "imu-garbage, imu-silent, imu-stuck, link-corrupt, link-drop)"
    ]


def test_an_explicit_duration_of_60_s_stops_the_pty_like_any_other(capsys):
    """60 is the default without --pty; it was taken for "no limit" even when given."""
    import threading

    done: list[int] = []
    runner = threading.Thread(target=lambda: done.append(main(["sim", str(R1), "--pty", "--duration", "60",
                                                                 "--speed", "200"])), daemon=True)
    runner.start()
    runner.join(timeout=30.0)
    assert done == [0], "still serving 30 s after a 60-simulated-second run at 200x"
    capsys.readouterr()


def test_output_nobody_reads_is_dropped_beyond_a_small_backlog():
    """The server held 64 KiB of output nobody read (half a minute of 50 Hz frames), which a
    client that connected later took for its own session: proleg run --port counted 624 frames
    for a 1 s run, the first ones 11 s before its START."""
    from proleg.sim.pty import BACKLOG_BYTES

    sim = open_simulated(load_robot(R1), "host-sim")
    with PtyServer(sim, say=lambda _: None) as server:
        pending = b""
        for _ in range(200):  # 200 × 4 KiB, nobody reading: the pty fills, then the server holds the rest
            pending = server._write(pending + bytes(4096))
        assert server.bytes_dropped > 0 and len(pending) <= BACKLOG_BYTES <= 4096


def test_a_speed_faster_than_the_machine_still_serves_the_pty_and_stops_when_asked():
    """The server caught up on speed × wall time before serving again: at 1e9 × it never came
    back (0.0 s simulated, not a byte served, Ctrl-C's stop never looked at)."""
    import threading
    import time

    sim = open_simulated(load_robot(R1), "host-sim")
    with PtyServer(sim, speed=1e9, say=lambda _: None) as server:
        start = time.monotonic()
        runner = threading.Thread(target=server.serve, kwargs={"should_stop": lambda: time.monotonic() - start > 1.0},
                                  daemon=True)
        runner.start()
        runner.join(timeout=10.0)
        assert not runner.is_alive(), "still serving 10 s after it was asked to stop at 1 s"
        assert server.elapsed_s > 0 and server.bytes_out > 0  # telemetry went out on the pty
