# proleg — `make demo` runs the main job, `make test` the whole suite (with the focused
# hil_tests subset on each emulated MCU), `make emu` every hil test on the emulated MCUs
# (long), `make bench` the benchmarks. Each sets up what is missing first: the .venv with the package and its
# test extras, and the Debian toolchains for the three boards.

PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed-stamp
APT    := scripts/ensure-apt.sh

# Board toolchains (command:debian-package). The newlib check is a file, not a command.
# simavr (avr-emu board): the simulator and the headers/library the harness links.
# Flashing (tested end to end against the emulated boards): avrdude (Nano), stm32flash
# (bluepill ROM bootloader), and optiboot's sources (arduino-core-avr) to build the Nano's
# bootloader from.
TOOLCHAINS := cc:gcc avr-gcc:gcc-avr /usr/lib/avr/include/avr/io.h:avr-libc \
              arm-none-eabi-gcc:gcc-arm-none-eabi \
              /usr/lib/arm-none-eabi/newlib/libc_nano.a:libnewlib-arm-none-eabi \
              clang:clang /usr/lib/llvm-14/lib/clang/14.0.6/lib/linux/libclang_rt.fuzzer-x86_64.a:libclang-rt-14-dev \
              simavr:simavr /usr/include/simavr/sim_avr.h:libsimavr-dev \
              avrdude:avrdude stm32flash:stm32flash \
              /usr/share/arduino/hardware/arduino/avr/bootloaders/optiboot/optiboot.c:arduino-core-avr

.PHONY: demo test emu bench fuzz setup toolchains optiboot clean

setup: $(STAMP)

$(BIN)/python:
	@$(PYTHON) -m venv $(VENV) 2>/dev/null || { \
	  rm -rf $(VENV); echo "python3 venv support is missing: installing python3-venv"; \
	  $(APT) --install python3-venv && $(PYTHON) -m venv $(VENV); }

$(STAMP): pyproject.toml | $(BIN)/python
	$(BIN)/python -m pip install -q --upgrade pip
	$(BIN)/python -m pip install -q -e '.[test]'
	@touch $@

toolchains:
	@$(APT) $(TOOLCHAINS)

# The Nano's bootloader for avr-emu, built from Debian's optiboot sources into the cache.
optiboot: $(STAMP) toolchains
	scripts/build-optiboot.sh

demo: $(STAMP) toolchains
	$(BIN)/python -m proleg.demo

# The emulated MCUs (avr-emu: simavr, arm-emu: unicorn) run the exact firmware images much
# slower than host-sim: `make test` runs their focused hil subset (boot, link, one closed-loop
# gait, ESTOP, on-time limit, IMU loss, and on avr-emu the paper's C_T/C_L experiments; tests
# marked emu_long deselected), `make emu` all.
EMU_TARGETS := avr-emu arm-emu

test: $(STAMP) toolchains
	$(BIN)/python -m pytest -n 2 -q -m "not long"
	@for t in $(EMU_TARGETS); do \
	  echo "hil_tests on $$t (focused subset)"; \
	  $(BIN)/python -m pytest -n 2 -q hil_tests --target $$t -m "not emu_long" || exit 1; \
	done
	@echo "hil_tests over CAN (python-can virtual bus): host-sim-can, then bluepill-can on arm-emu (no gait walk)"
	$(BIN)/python -m pytest -q hil_tests --link can -m "can_link and not emu_long"
	$(BIN)/python -m pytest -q hil_tests --target arm-emu --link can -m "can_link and not emu_long and not gait_cases"

emu: $(STAMP) toolchains
	@for t in $(EMU_TARGETS); do \
	  echo "hil_tests on $$t (all)"; \
	  $(BIN)/python -m pytest -n 2 -q hil_tests --target $$t || exit 1; \
	done
	$(BIN)/python -m pytest -n 2 -q hil_tests --target arm-emu --link can -m can_link

# Long fuzzing (the short run is part of `make test`) and a longer attacker profile.
FUZZ_SECONDS ?= 300
fuzz: $(STAMP) toolchains
	$(BIN)/python tests/fuzz/run_fuzz.py --seconds $(FUZZ_SECONDS) --coverage --json bench/results/fuzz.json
	PROLEG_ATTACK_EXAMPLES=200 PROLEG_ATTACK_STEPS=40 $(BIN)/python -m pytest -q tests/test_safety_attacker.py

bench: $(STAMP) toolchains
	$(BIN)/python -m pytest -q -m long tests
	$(BIN)/python bench/run_all.py

clean:
	rm -rf $(VENV) build out .pytest_cache .hypothesis
	find . -name __pycache__ -type d -prune -exec rm -rf {} +
