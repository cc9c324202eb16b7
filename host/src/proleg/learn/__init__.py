"""Learning a robot's transition statistics on the robot (issue 15).

Modules: ``tours`` (randomised Euler exploration tours, exact min-cost balancing),
``pieces`` (thermally limited pieces of a tour), ``measure`` (append-only trial log,
ground-truth and manual sources), ``tracker`` (tracker CSV, clock offset), ``stats``
(Student t), ``estimate`` (means, variances, intervals, extra trials, penalised table),
``plan`` (extra-trial and adaptive plans), ``robotfile`` (the learned robot file) and
``runner`` (the one module that drives a robot over a link) with ``next_piece`` (which
piece it runs next).
"""

from .estimate import Estimates, estimate, extra_trials, penalised_table
from .measure import Trial, TrialLog, counts, manual_trial, remaining
from .pieces import Piece, PieceLimits, limits_for, split
from .plan import adaptive_demand, extra_plan
from .robotfile import read_learned, write_learned_robot
from .tours import Exploration, Tour, TourError, exploration
from .tracker import estimate_offset, read_track, trials_from_events

__all__ = [
    "Estimates", "Exploration", "Piece", "PieceLimits", "Tour", "TourError", "Trial", "TrialLog",
    "adaptive_demand", "counts", "estimate", "estimate_offset", "exploration", "extra_plan", "extra_trials",
    "limits_for", "manual_trial", "penalised_table", "read_learned", "read_track", "remaining", "split",
    "trials_from_events", "write_learned_robot",
]
