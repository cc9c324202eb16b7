"""``proleg run`` when the board stops the gait by itself: it reset (a brown-out, its watchdog),
without a fault (before, the run went on to its end, printed "0 faults" and exited 0), or its
link watchdog stopped it after the host went quiet for a while (a FAULT: exit 1)."""

from __future__ import annotations

from build_checks import R1, cli
from proleg.link import sim_link


def _patch(monkeypatch, *, reset_at_s: float | None = None, mute_s: tuple[float, float] | None = None) -> None:
    real_read, real_write = sim_link.SimLink.read, sim_link.SimLink.write
    done: list[bool] = []

    def read(self, timeout):
        sim = self.board
        if reset_at_s is not None and not done and sim.time_s > reset_at_s:
            done.append(True)
            sim.board.reset()  # the firmware reboots; the plant goes on
        return real_read(self, timeout)

    def write(self, data):
        if mute_s is not None and mute_s[0] <= self.board.time_s < mute_s[1]:
            return  # the host's frames are lost (a stalled link that comes back)
        real_write(self, data)

    monkeypatch.setattr(sim_link.SimLink, "read", read)
    monkeypatch.setattr(sim_link.SimLink, "write", write)


def test_a_board_that_resets_mid_run_fails_the_run(capsys, monkeypatch):
    _patch(monkeypatch, reset_at_s=4.0)
    code, out, err = cli(capsys, "run", R1, "--sim", "--duration", "8", "-q")
    assert code == 1, (out, err)
    assert "proleg: error: the board reset after START (its clock went back from 4.0" in err
    assert err.rstrip().endswith("a reset board stops the gait and boots idle")


def test_a_gait_the_link_watchdog_stopped_fails_the_run(capsys, monkeypatch):
    """(A regression check: the watchdog's stop comes with a FAULT LINK_WATCHDOG, which fails the run.)"""
    _patch(monkeypatch, mute_s=(3.0, 6.0))  # 3 s without a host frame: the 2 s watchdog stops the gait
    code, out, err = cli(capsys, "run", R1, "--sim", "--duration", "9", "-q")
    assert code == 1, (out, err)
    assert ": LINK_WATCHDOG" in out and "1 fault" in out


def test_an_undisturbed_run_is_still_ok(capsys):
    code, _, err = cli(capsys, "run", R1, "--sim", "--duration", "6", "-q")
    assert code == 0 and "error" not in err, err


def test_a_link_lost_mid_run_says_what_stops_the_coils_and_what_was_kept(capsys, monkeypatch, tmp_path):
    """A cable pulled mid-run ended with the link's error alone: nothing said what the robot was
    left doing (no STOP can reach it) or whether the recording was kept."""
    from proleg.errors import LinkError
    from proleg.record import read_recording

    real_read = sim_link.SimLink.read

    def read(self, timeout):
        if self.board.time_s > 4.0:
            raise LinkError("sim paper-r1: device disconnected and not back within 10 s")
        return real_read(self, timeout)

    monkeypatch.setattr(sim_link.SimLink, "read", read)
    record = tmp_path / "run.mcap"
    code, out, err = cli(capsys, "run", R1, "--sim", "--duration", "8", "-q", "--record", record)
    assert code == 1, (out, err)
    assert err == ("proleg: error: sim paper-r1: device disconnected and not back within 10 s; the link was lost "
                   "during the run, no STOP could be sent: the board's link watchdog stops the gait and turns the "
                   f"coils off within 2000 ms of the last frame; recording kept in {record} (complete up to there)\n")
    assert len(read_recording(record).time_s) > 0


def test_a_plain_console_says_when_the_board_resets(capsys, monkeypatch):
    """--plain showed only the board's clock starting again: a reset (and the gait it stopped)
    went unmentioned."""
    _patch(monkeypatch, reset_at_s=3.0)
    code, _, err = cli(capsys, "console", "--sim", "paper-r1", "--plain", "--duration", "4")
    assert code == 0, err
    assert "proleg: the board reset: boot (reset cause POWER_ON); it boots idle (a gait it ran is stopped)\n" in err
    code, _, err = cli(capsys, "console", "--sim", "paper-r1", "--plain", "--duration", "2")
    assert "reset" not in err  # the board's first boot is no reset
