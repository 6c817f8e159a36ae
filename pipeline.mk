# docunfold pipeline: photos of a creased page -> flat image of it.
#
#   make -f pipeline.mk DATA=set01            run the pipeline on samples/set01
#   make -f pipeline.mk test                  build and run all tests
#   make -f pipeline.mk help                  targets and variables
#
# Every stage is a program in build/bin/ that reads and writes files in
# work/<name>/. Each stage's flags (SFM_FLAGS, ...) and REF are recorded in
# work/<name>/.flags/, so changing them reruns exactly that stage and what
# depends on it.

.DELETE_ON_ERROR:
.SUFFIXES:
.DEFAULT_GOAL := all
SHELL := /bin/bash
.SHELLFLAGS := -o pipefail -c

ROOT := $(patsubst %/,%,$(dir $(abspath $(lastword $(MAKEFILE_LIST)))))
BUILD ?= $(ROOT)/build
BIN := $(BUILD)/bin
JOBS ?= 2

# ---- data set ---------------------------------------------------------------
DATA ?= set01
# samples/<name>, then data/<name>, then DATA as a path.
DATA_DIR := $(patsubst %/images,%,$(firstword $(wildcard \
  $(ROOT)/samples/$(DATA)/images $(ROOT)/data/$(DATA)/images \
  $(abspath $(DATA))/images)))
NAME := $(notdir $(patsubst %/,%,$(DATA)))
WORK ?= $(ROOT)/work/$(NAME)
IMAGES := $(sort $(wildcard $(DATA_DIR)/images/*))

# ---- stage flags --------------------------------------------------------------
REF ?=
SFM_FLAGS ?=

# TIMER=<file>: run each stage under scripts/stage-timer, appending its wall
# time and peak memory to <file> (used by the benchmark).
TIMER ?=
timed = $(if $(TIMER),$(ROOT)/scripts/stage-timer $(TIMER) $(1))

# ---- helpers ------------------------------------------------------------------
streq = $(and $(findstring x$(1),x$(2)),$(findstring x$(2),x$(1)))

# $(call flags_rule,<stage>,<value>): work/<name>/.flags/<stage> holds the
# value; it is rewritten (and so dependents rerun) only when the value changes.
define flags_rule
$(WORK)/.flags/$(1): FORCE
	@$$(shell mkdir -p $$(@D))$$(if $$(and $$(wildcard $$@),$$(call streq,$$(file <$$@),$(2))),,$$(file >$$@,$(2)))true
endef
$(eval $(call flags_rule,sfm,$(SFM_FLAGS) $(if $(REF),--ref $(REF))))

.PHONY: all sfm help clean deps build test bench check-data FORCE
FORCE:

# ---- build ----------------------------------------------------------------------
deps:
	@$(ROOT)/scripts/install-deps.sh

$(BUILD)/CMakeCache.txt: | deps
	cmake -S $(ROOT) -B $(BUILD) -DCMAKE_BUILD_TYPE=Release

build: $(BUILD)/CMakeCache.txt deps
	cmake --build $(BUILD) -j$(JOBS)

# A stage binary is (re)built when its sources changed; stages that depend on
# it rerun only when the binary actually changes.
$(BIN)/%: $(BUILD)/CMakeCache.txt FORCE | deps
	@cmake --build $(BUILD) --target $* -j$(JOBS) | grep -v -E '^(\[|make|Consolidate|Built target)' || true
	@test -x $@

test: build
	cd $(BUILD) && ctest --output-on-failure -j$(JOBS)

# Runs the pipeline on every sample (or BENCH_SETS="set01 set02") from scratch
# and writes per-stage wall time and peak memory to bench/results.{md,json}.
BENCH_SETS ?=
bench: build
	$(ROOT)/scripts/bench.sh $(BENCH_SETS)

# ---- pipeline ---------------------------------------------------------------------
all: sfm
	@echo "docunfold: $(NAME) done; results in $(WORK)"

check-data:
	@test -n "$(DATA_DIR)" || { echo "pipeline.mk: DATA=$(DATA): no data set (looked for images/ in samples/$(DATA), data/$(DATA) and $(abspath $(DATA)))" >&2; exit 3; }

SFM_OUT := $(addprefix $(WORK)/10_sfm/,cameras.json points.ply reference.png)
sfm: check-data $(SFM_OUT)
$(SFM_OUT) &: $(BIN)/sfm $(WORK)/.flags/sfm $(IMAGES) | check-data
	$(call timed,sfm) $(BIN)/sfm --data $(DATA_DIR) --out $(WORK)/10_sfm $(if $(REF),--ref $(REF)) $(SFM_FLAGS)

# ---- housekeeping -------------------------------------------------------------------
clean:
	rm -rf $(WORK)

help:
	@echo "docunfold pipeline"
	@echo
	@echo "Targets:"
	@echo "  all (default)  run every implemented stage on DATA"
	@echo "  sfm            COLMAP structure from motion -> work/<name>/10_sfm/"
	@echo "  test           build, then run all tests (ctest)"
	@echo "  build          configure and build build/bin/*"
	@echo "  deps           install missing Debian packages (root) or print the apt-get line"
	@echo "  bench          time every stage on every sample -> bench/results.md"
	@echo "  clean          remove work/<name>/"
	@echo
	@echo "Variables:"
	@echo "  DATA=set01     data set: samples/<DATA>, data/<DATA>, or a path (default set01)"
	@echo "  WORK=dir       work directory (default work/<name>/)"
	@echo "  REF=img.jpg    reference view for sfm (default: chosen automatically)"
	@echo "  SFM_FLAGS=...  extra flags for build/bin/sfm (see build/bin/sfm --help)"
	@echo "  JOBS=2         parallel build jobs"
	@echo "  TIMER=file     append per-stage time and peak memory to file (JSON lines)"
	@echo "  BENCH_SETS=... samples for bench (default: all)"
	@echo
	@echo "Changing REF or a *_FLAGS variable reruns that stage and everything after it."
