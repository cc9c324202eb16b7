"""Boards emulated at the instruction level: the exact MCU firmware images on CPU emulators
(``avr``: simavr, ``arm``: unicorn)."""
