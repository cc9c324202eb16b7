"""Firmware generation: board files, rendering the C project, building and flashing."""
