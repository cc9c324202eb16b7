"""The simulated robot learning explores: the host-sim firmware in closed loop with a plant,
and the link and pose a learner gets from it (``proleg learn --sim``).

``simulated_robot`` gives the physical plant (friction mechanics, no matrix: what the body
does) or the table plant driven by a truth's matrix that the learner never sees (to prove
that learning recovers it); ``check_plant`` refuses a pairing that cannot work before
anything is built; ``explore_simulated`` is ``proleg learn ROBOT --sim`` as a function.
"""

from __future__ import annotations

from collections.abc import Callable

from ..robot import Robot
from .measure import Pose, TrialLog
from .runner import ExplorationError, Explorer, Progress


def check_plant(robot: Robot, truth: Robot | None, plant: str) -> None:
    """``ExplorationError`` when ``simulated_robot`` cannot drive ``plant`` with ``truth``."""
    if plant == "physical" and truth is not None:
        raise ExplorationError("--truth drives the table plant; the physical plant has no matrix")
    if plant == "table" and truth is None and getattr(robot, "unmeasured", False):
        raise ExplorationError(f"{robot.where}: the matrix is unmeasured, and the table plant moves by it: every "
                               "trial would read 0; learn on the physical plant (the default without --truth) "
                               "or give --truth TRUTH.toml")
    if truth is not None and truth.levels != robot.levels:
        raise ExplorationError(f"truth {truth.path} has state levels {truth.levels}, the robot {robot.levels}")
    if truth is not None:  # the table plant takes its limbs from the truth: they must be the robot's
        for mine, theirs in zip(robot.limbs, truth.limbs):
            a = (tuple(mine.psi_star_deg), mine.hysteresis_deg)
            b = (tuple(theirs.psi_star_deg), theirs.hysteresis_deg)
            if a != b:
                raise ExplorationError(
                    f"truth {truth.path}: limb {theirs.name!r} has psi_star_deg {list(b[0])} and hysteresis_deg "
                    f"{b[1]:g}, the robot's limb {mine.name!r} {list(a[0])} and {a[1]:g}: a truth file is the robot "
                    f"file with another matrix (proleg.learn.truth.write_truth writes one)")


def simulated_robot(robot: Robot, truth: Robot | None = None, *, seed: int = 1, plant: str = "table"):
    """The host-sim firmware of ``robot`` in closed loop with a table plant driven by
    ``truth``'s matrix and ``[plant]`` (its ``noise_mm``, ``step_mm``...; default: ``robot``)
    — the learner never sees the truth; ``plant="physical"``: the physical plant (friction
    mechanics, no matrix: ``truth`` must be None). Returns (SimulatedRobot, RobotClient over
    SimLink, ground-truth pose callable)."""
    from ..link import RobotClient
    from ..link.sim_link import SimLink
    from ..sim.closed_loop import SimulatedRobot
    from ..sim.plant import Plant, plant_params_from_robot, planar_motion_from_robot, true_rewards_from_robot

    check_plant(robot, truth, plant)
    if plant == "physical":
        sim = SimulatedRobot(robot, seed=seed)
        client = RobotClient(SimLink(sim, description=f"sim {robot.name} (physical plant)"),
                             watchdog_ms=robot.safety.link_watchdog_ms)
        return sim, client, lambda: (sim.plant.displacement_mm, None, None)
    truth = truth or robot
    # with the truth's planar statistics (dy, dθ and their variances) the table plant moves a
    # planar pose, as `proleg sim`'s does; without them Δy and Δθ were never learned on planar-4
    plant = Plant(plant_params_from_robot(truth), true_rewards_from_robot(truth), robot.levels, seed,
                  planar_motion_from_robot(truth))
    sim = SimulatedRobot(robot, seed=seed, plant=plant)
    client = RobotClient(SimLink(sim, description=f"sim {robot.name}"), watchdog_ms=robot.safety.link_watchdog_ms)

    steers = truth.transitions.moves_in_plane

    def pose() -> Pose:
        # variances alone (a learned file's var_dx) move no Δy, Δθ: recorded as 0 they were
        # written back as dy, dtheta_deg and made a worm a planar robot
        planar = sim.plant.pose
        return (sim.plant.displacement_mm, None, None) if planar is None or not steers else planar

    return sim, client, pose


def explore_simulated(robot: Robot, truth: Robot | None, log: TrialLog, *, repeats: int = 5, seed: int = 1,
                      on_progress: Callable[[Progress], None] | None = None, plant: str = "table"):
    """``proleg learn ROBOT --sim --truth TRUTH`` as a function: returns (trials added, sim)."""
    sim, client, pose = simulated_robot(robot, truth, seed=seed, plant=plant)
    with client:
        client.connect()
        ex = Explorer(client, robot, log, pose, repeats=repeats, source="sim", seed=seed, on_progress=on_progress)
        return ex.run(), sim
