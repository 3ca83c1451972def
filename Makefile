# The README's commands. Each one installs missing system packages, configures and builds first.
PRESET ?= release
BUILD_DIR := build/$(PRESET)
BIN := $(BUILD_DIR)/bin
CONFIG ?= configs/default.json
JOBS ?= $(shell nproc)
# Debian's interpreter, which has python3-matplotlib (a python3 earlier on PATH may not).
PYTHON ?= /usr/bin/python3

.PHONY: deps configure build test bench figures format clean

deps:
	@tools/install-deps.sh

configure: deps
	@cmake --preset $(PRESET)

build: configure
	@cmake --build --preset $(PRESET) -j $(JOBS)

test: build
	@ctest --preset $(PRESET)

bench: build
	@$(BIN)/canopy-bench --config $(CONFIG)

figures: deps
	@$(PYTHON) paper_figures/make_figures.py results

format:
	@find common methods bench viewer tests -name '*.cpp' -o -name '*.h' | xargs clang-format -i

clean:
	@rm -rf build
