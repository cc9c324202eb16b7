"""The gait engine: optimal gaits of a transition table, and scores of typed sequences.

    optimal_gaits(table, objective="total"|"rate"|"speed", direction="+x"|"-x",
                  max_transitions=None) -> GaitResult      # ties ranked, gait 0 first
    evaluate_sequence(table, states) -> Gait
    rank_gaits(gaits, direction, tol) -> list[Gait]

    feasibility: gait_problems(robot, states) -> list[Problem], check_gait(robot, states),
                 entry_path(robot, states) -> EntryPath
    planar:      optimal_planar_gaits(table, PlanarObjective(...), kind, max_transitions)

See ``optimal.py`` for which algorithm answers which objective, docs/gait-selection.md
for what ``total`` counts (repeated walks: ``Gait.repeats``) and how ties are ranked.
"""

from .evaluate import evaluate_sequence
from .feasibility import EntryPath, Problem, check_gait, entry_path, gait_problems
from .optimal import optimal_gaits, rank_gaits
from .planar import PlanarObjective, optimal_planar_gaits
from .result import MAX_TIES, RELATIVE_TOLERANCE, Gait, GaitResult

__all__ = [
    "EntryPath", "Gait", "GaitResult", "MAX_TIES", "PlanarObjective", "Problem", "RELATIVE_TOLERANCE",
    "check_gait", "entry_path", "evaluate_sequence", "gait_problems", "optimal_gaits", "optimal_planar_gaits",
    "rank_gaits",
]
