# The README's commands. Each one installs missing system packages, configures and builds first.
PRESET ?= release
BUILD_DIR := build/$(PRESET)
BIN := $(BUILD_DIR)/bin
CONFIG ?= configs/default.json
JOBS ?= $(shell nproc)
# Debian's interpreter, which has python3-matplotlib (a python3 earlier on PATH may not).
PYTHON ?= /usr/bin/python3
# The run folder of CONFIG: results/<its "name">, read when a target needs it.
RUN = $(shell $(PYTHON) -c "import json; print(json.load(open('$(CONFIG)'))['name'])")

.PHONY: deps configure build test lint sanitize fuzz bench figures format docs clean

deps:
	@tools/install-deps.sh

configure: deps
	@cmake --preset $(PRESET)

build: configure
	@cmake --build --preset $(PRESET) -j $(JOBS)

test: build
	@ctest --preset $(PRESET)

# clang-format, clang-tidy and the function-length check (tools/lint.sh); CI runs it.
lint: build
	@tools/lint.sh

# The CPU-only tests built with AddressSanitizer and UndefinedBehaviorSanitizer (preset "debug");
# CI runs it after make test.
sanitize: deps
	@cmake --preset debug
	@cmake --build --preset debug -j $(JOBS) --target canopy_tests canopy-bench
	@ctest --preset debug

# libFuzzer harnesses (tests/fuzz), each run FUZZ_SECONDS, FUZZ_JOBS at a time; fails on a crash.
FUZZ_SECONDS ?= 60
FUZZ_JOBS ?= 1
fuzz:
	@tools/fuzz.sh $(FUZZ_SECONDS) $(FUZZ_JOBS)

# Rewrites docs/METHODS.md's parameter tables from the code (a test checks they match).
docs: build
	@tools/update-method-docs.sh

# Resumes an interrupted run of the same config and code; otherwise (a fresh clone's committed
# results, or a finished run) moves the old run aside and measures anew. Then its figures.
bench: build
	@$(BIN)/canopy-bench --config $(CONFIG) --resume-or-fresh
	@$(PYTHON) paper_figures/make_figures.py results/$(RUN)
	@echo "canopy: results in results/$(RUN)/ (summary.md), figures in paper_figures/$(RUN)/"

figures: deps
	@$(PYTHON) paper_figures/make_figures.py results

format:
	@find common methods bench viewer tests -name '*.cpp' -o -name '*.h' | xargs clang-format -i

clean:
	@rm -rf build
