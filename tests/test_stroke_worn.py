"""A worn robot at full strokes (docs/control.md, "Full strokes"): fatigue takes stroke off every
coil alike, so both of R1's ends top out at the same angle and the strokes' order, which makes
its whole-body ratchet (the right end, raised less, comes down first), is gone unless the
controller keeps it."""

from __future__ import annotations

from pathlib import Path

from proleg.report import claim
from proleg.robot import load_robot
from proleg.physics.materials import NITI_OVERHEAT_C

STROKE = Path(__file__).resolve().parents[1] / "robots" / "paper-r1-stroke.toml"


def test_a_worn_robot_at_full_strokes_keeps_its_ratchet_and_its_coils_below_overheating():
    """30,000 cycles of fatigue (R1's ends top out near 66° instead of 76°/72°): the limb that
    stopped short sets how far the others climb in that step, so the right end stays below the
    left and comes down first. Before, the right end climbed on to the same 66°, its coil
    heated last came down last, and the robot walked 0.34 mm/s against 6.85 fresh."""
    robot = load_robot(STROKE)
    fresh = claim.feedback_run(robot, claim.NOMINAL, duration_s=30.0)
    worn = claim.feedback_run(robot, claim.point("fatigue (strong)"), duration_s=30.0)
    assert fresh.completed and worn.completed, (fresh, worn)
    assert worn.fault == "" and worn.coil_peak_c < NITI_OVERHEAT_C, worn
    assert worn.speed_mm_s > 0.5 * fresh.speed_mm_s, (worn.speed_mm_s, fresh.speed_mm_s)
