"""Emulated microcontrollers running the exact firmware binaries (``avr``: simavr)."""
