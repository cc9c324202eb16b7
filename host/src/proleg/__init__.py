"""proleg: gaits, firmware and simulation for soft crawling robots."""

__version__ = "0.1.0"
