#!/usr/bin/env bash
# build-optiboot.sh [--copy-to FILE] — build the Nano's bootloader (optiboot 4.4) from the
# sources in Debian's arduino-core-avr with optiboot's own Makefile flags (atmega328 target,
# 16 MHz, 115200 Bd, LED flashes off so it fits the 512-byte boot section; Debian's prebuilt
# optiboot_atmega328.hex is 532 bytes). The .hex is cached under $PROLEG_CACHE/avr-emu/;
# the avr-emu Nano (python -m proleg.emu.avr.pty_nano) builds it itself when missing.
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
python=${PYTHON:-$here/.venv/bin/python}
[[ -x $python ]] || python=python3
exec "$python" -m proleg.emu.avr.optiboot "$@"
