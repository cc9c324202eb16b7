"""Learning a robot's transition statistics on the robot (issue 15): exploration tours
(``tours``, ``pieces``), trial logs and position sources (``measure``, ``tracker``),
estimation and the learned robot file (``stats``, ``estimate``, ``robotfile``), and the
thin layer that drives a robot through a link (``runner``)."""
