"""The gait engine: optimal gaits of a transition table, and scores of typed sequences.

    optimal_gaits(table, objective="total"|"rate"|"speed", direction="+x"|"-x",
                  max_transitions=None) -> GaitResult      # ties ranked, gait 0 first
    evaluate_sequence(table, states) -> Gait
    rank_gaits(gaits, direction, tol) -> list[Gait]

    feasibility: gait_problems(robot, states) -> list[Problem], check_gait(robot, states),
                 entry_path(robot, states) -> EntryPath
    entry:       entry_walk(table, cycle, rest, can_step, unheld, blocked) -> EntryPath (the search)
    planar:      optimal_planar_gaits(table, PlanarObjective(...), kind, max_transitions,
                                  rotation_cap_deg, simple_cycles=, rotate=, translation_cap=)
    compose:     net_motion(table, states) -> Pose, gait_path(table, states, cycles) -> [Pose]
    library:     gait_library(table, "0,90,rot-cw", ...) -> [LibraryEntry],
                 library_gaits(entries) -> [(Heading, Gait)] (the firmware's table, in order)

See ``optimal.py`` for which algorithm answers which objective, docs/gait-selection.md
for what ``total`` counts (repeated walks: ``Gait.repeats``) and how ties are ranked.
"""

from .evaluate import evaluate_sequence
from .entry import EntryPath
from .feasibility import Problem, check_gait, entry_path, gait_problems
from .optimal import optimal_gaits, rank_gaits
from .compose import Pose, gait_path, net_motion
from .library import Heading, LibraryEntry, gait_library, library_gaits, parse_headings
from .planar import PlanarObjective, optimal_planar_gaits
from .result import MAX_TIES, RELATIVE_TOLERANCE, Gait, GaitResult

__all__ = [
    "EntryPath", "Gait", "GaitResult", "Heading", "LibraryEntry", "MAX_TIES", "PlanarObjective", "Pose", "Problem",
    "RELATIVE_TOLERANCE", "check_gait", "entry_path", "evaluate_sequence", "gait_library", "gait_path",
    "gait_problems", "library_gaits", "net_motion", "optimal_gaits", "optimal_planar_gaits", "parse_headings",
    "rank_gaits",
]
