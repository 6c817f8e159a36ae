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
WORK_ROOT ?= $(ROOT)/work
# Make cannot carry a space, ":" or "%" in a target's path, so a work root
# (or the repository's own path) with one is refused here, before anything is
# written, rather than split into words that become stray folders.
make_unsafe = $(or $(word 2,$(1)),$(findstring :,$(1)),$(findstring %,$(1)))
$(if $(or $(call make_unsafe,$(ROOT)),$(if $(wildcard $(ROOT)/pipeline.mk),,missing)),$(error the repository's path has a space, ":" or "%", which Make cannot carry; clone it to a path without))
$(foreach v,WORK_ROOT WORK BUILD,$(if $(call make_unsafe,$($(v))),$(error $(v)=$($(v)): a path with a space, ":" or "%", which Make cannot carry; give one without (a link to the folder will do))))
# samples/<name>, then data/<name>, then DATA as a path, which may have
# spaces, accents, "." or "..": scripts/data-dir resolves it (a folder whose
# path Make cannot carry is reached through the link WORK/.data) and names
# the work directory after the data set's own folder.
DATA_RESOLVED := $(shell $(ROOT)/scripts/data-dir '$(ROOT)' '$(WORK_ROOT)' '$(subst ','\'',$(WORK))' '$(subst ','\'',$(DATA))')
DATA_DIR := $(word 1,$(DATA_RESOLVED))
NAME := $(word 2,$(DATA_RESOLVED))
# (When DATA names nothing, check-data stops the run; WORK is then one word
# all the same, so that a DATA with spaces cannot turn into stray targets.)
override WORK := $(patsubst %/,%,$(or $(word 3,$(DATA_RESOLVED)),$(WORK_ROOT)/$(lastword $(notdir $(DATA)))))
# The photos' names, sizes and times (names may have spaces, which Make's
# prerequisites cannot): sfm and densify rerun when a photo changes. Files
# only, links followed: a folder beside the photos is not read, and its time
# changes with whatever is written in it (a WORK_ROOT there).
IMAGES_LIST := $(if $(DATA_DIR),$(shell cd '$(DATA_DIR)/images' && find -L . -mindepth 1 -maxdepth 1 ! -type d -printf '%s %T@ %p\n' | LC_ALL=C sort | md5sum))

# ---- stage flags --------------------------------------------------------------
REF ?=
SFM_FLAGS ?=
BOUNDARY_FLAGS ?=
FEATURES_FLAGS ?=
# FEATURES=file.json: use another detector's feature segments instead of
# running detect-features (validated against schemas/, then copied).
FEATURES ?=
DENSIFY_FLAGS ?=
# DENSIFY=0: init-mesh and optimize fit sfm's sparse points only (the paper's
# input) instead of 25_points/points.ply.
DENSIFY ?= 1
INIT_FLAGS ?=
OPTIMIZE_FLAGS ?=
RENDER_FLAGS ?=
PDF_FLAGS ?=
EVAL_FLAGS ?=

# Every stage runs under scripts/stage-timer, which appends its wall time and
# peak memory to TIMER (the report shows them; the benchmark sets its own).
TIMER ?= $(WORK)/timings.jsonl
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
$(eval $(call flags_rule,boundary,$(BOUNDARY_FLAGS)))
$(eval $(call flags_rule,features,$(if $(FEATURES),FEATURES=$(abspath $(FEATURES)),$(FEATURES_FLAGS))))
# The point cloud init-mesh and optimize fit: densify's when it is built in.
POINTS_FILE := $(if $(and $(wildcard $(ROOT)/stages/densify),$(filter-out 0,$(DENSIFY))),$(WORK)/25_points/points.ply,$(WORK)/10_sfm/points.ply)
$(eval $(call flags_rule,points,$(DENSIFY_FLAGS)))
# (recorded relative to the work directory, so a copied work directory is
# still up to date)
POINTS_FROM := $(notdir $(patsubst %/points.ply,%,$(POINTS_FILE)))
$(eval $(call flags_rule,init,$(INIT_FLAGS) points=$(POINTS_FROM)))
$(eval $(call flags_rule,optimize,$(OPTIMIZE_FLAGS) points=$(POINTS_FROM)))
$(eval $(call flags_rule,render,$(RENDER_FLAGS)))
$(eval $(call flags_rule,pdf,$(PDF_FLAGS)))
$(eval $(call flags_rule,evaluate,$(EVAL_FLAGS)))
$(eval $(call flags_rule,images,$(IMAGES_LIST)))

.PHONY: all sfm boundary points features init optimize render pdf evaluate report book help clean deps build test bench fuzz check-data FORCE
FORCE:

# ---- build ----------------------------------------------------------------------
deps:
	@$(ROOT)/scripts/install-deps.sh

$(BUILD)/CMakeCache.txt: | deps
	cmake -S $(ROOT) -B $(BUILD) -G Ninja -DCMAKE_BUILD_TYPE=Release

build: $(BUILD)/CMakeCache.txt deps
	cmake --build $(BUILD) -j$(JOBS)

# A stage binary is (re)built when its sources changed; stages that depend on
# it rerun only when the binary actually changes. One cmake call builds or
# checks every program a run uses (PROGRAMS, below): with Ninja it takes 0.1 s
# when nothing is to be built, where a call per program made every run 4 s
# longer (0.4 s a call with CMake's Makefiles).
ifeq ($(NO_BUILD),)
.PHONY: programs
programs: $(BUILD)/CMakeCache.txt | deps
	@cmake --build $(BUILD) --target $(PROGRAMS) -j$(JOBS) > $(BUILD)/.build-programs.log 2>&1 || \
	  { cat $(BUILD)/.build-programs.log >&2; echo "pipeline.mk: building $(PROGRAMS) failed" >&2; exit 1; }
$(BIN)/%: programs
	@test -x $@ || { echo "pipeline.mk: $@ is not among the programs built ($(PROGRAMS))" >&2; exit 1; }
else
# Batches build once, up front; the per-data-set makes only check.
$(BIN)/%:
	@test -x $@ || { echo "pipeline.mk: $@ is missing; run make -f pipeline.mk build" >&2; exit 1; }
endif

test: build
	cd $(BUILD) && ctest --output-on-failure -j$(JOBS)

# Runs the pipeline on every sample (or BENCH_SETS="set01 set02") from scratch
# and writes per-stage wall time and peak memory to bench/results.{md,json}.
BENCH_SETS ?=
bench: build
	$(ROOT)/scripts/bench.sh $(BENCH_SETS)

# libFuzzer targets of fuzz/ (ASan, UBSan) in a clang build of their own; each
# runs FUZZ_SECONDS on a copy of its seeds, JOBS at a time; any finding fails
# (scripts/fuzz: logs in build-fuzz/logs/, inputs in build-fuzz/findings/).
FUZZ_BUILD ?= $(ROOT)/build-fuzz
FUZZ_SECONDS ?= 600
FUZZ_TARGETS ?=
fuzz: deps
	CC=clang CXX=clang++ cmake -S $(ROOT) -B $(FUZZ_BUILD) $(if $(wildcard $(FUZZ_BUILD)/CMakeCache.txt),,-G Ninja) -DDOCUNFOLD_FUZZ=ON \
	  -DCMAKE_BUILD_TYPE=RelWithDebInfo > /dev/null
	cmake --build $(FUZZ_BUILD) -j$(JOBS)
	$(ROOT)/scripts/fuzz $(FUZZ_BUILD) $(FUZZ_SECONDS) $(JOBS) $(FUZZ_TARGETS)

# ---- pipeline ---------------------------------------------------------------------
# The chain of stages, in order. `all` runs every stage whose program exists
# in stages/ (so the pipeline runs as far as it is implemented), plus
# evaluate when the data set has ground truth.
CHAIN := sfm:sfm boundary:segment-boundary points:densify features:detect-features \
  init:init-mesh optimize:optimize render:render
# The two halves of a `name:value` pair.
pair_name = $(word 1,$(subst :, ,$(1)))
pair_value = $(word 2,$(subst :, ,$(1)))
CHAIN_PROGRAMS := $(foreach s,$(CHAIN),$(call pair_value,$(s)))
IMPLEMENTED := $(foreach s,$(CHAIN),$(if $(wildcard $(ROOT)/stages/$(call pair_value,$(s))),$(call pair_name,$(s))))
# The programs of the implemented stages a run may use.
PROGRAMS := $(notdir $(wildcard $(addprefix $(ROOT)/stages/,$(CHAIN_PROGRAMS) pdf evaluate report)))
HAS_GT := $(wildcard $(DATA_DIR)/ground_truth/flat.png)
all: $(lastword $(IMPLEMENTED)) $(if $(wildcard $(ROOT)/stages/pdf),pdf pages) $(if $(and $(HAS_GT),$(wildcard $(ROOT)/stages/evaluate)),evaluate) $(if $(wildcard $(ROOT)/stages/report),report)
	@echo "docunfold: $(NAME) done; results in $(WORK)$(if $(wildcard $(ROOT)/stages/report),; open $(WORK)/report.html)$(if $(wildcard $(BOOK_PDF)),; all its pages in $(BOOK_PDF))"

# Photos of several pages in one folder: the page with most photos is made
# here, and each other page sfm found (cameras.json's colmap.other_pages) as
# a data set of its own, WORK-p<k> beside WORK (WORK_ROOT/<NAME>-p<k> by
# default), all joined by scripts/book into WORK.pdf in the order of their
# photos' names. One page: nothing to do.
BOOK_PDF = $(WORK).pdf
.PHONY: pages
pages: check-data pdf
	+@$(ROOT)/scripts/pages '$(ROOT)' '$(WORK)' '$(NAME)' '$(DATA_DIR)' '$(MAKE)'

check-data:
	@test -n "$(DATA_DIR)" || { if test -d '$(subst ','\'',$(DATA))'; then \
	  echo "pipeline.mk: DATA=$(DATA): no photos in it (a run takes one document's photos; for a folder of such folders: all-samples DATASETS=\"...\" or the workflow's sets_dir=)"; else \
	  echo "pipeline.mk: DATA=$(DATA): no data set or folder of photos $(if $(filter /%,$(firstword $(DATA))),there,(looked in samples/ and data/ and from $(CURDIR)))"; fi >&2; exit 3; }

SFM_OUT := $(addprefix $(WORK)/10_sfm/,cameras.json points.ply reference.png)
sfm: check-data $(SFM_OUT)
$(SFM_OUT) &: $(BIN)/sfm $(WORK)/.flags/sfm $(WORK)/.flags/images | check-data
	$(call timed,sfm) $(BIN)/sfm --data $(DATA_DIR) --out $(WORK)/10_sfm $(if $(REF),--ref $(REF)) $(SFM_FLAGS)

BOUNDARY_OUT := $(addprefix $(WORK)/20_boundary/,boundary.json mask.png overlay.png)
boundary: check-data $(BOUNDARY_OUT)
# The other views' pages too (20_boundary/views/): render looks there past a
# side the reference image cuts off.
$(BOUNDARY_OUT) &: $(BIN)/segment-boundary $(WORK)/.flags/boundary $(WORK)/10_sfm/reference.png $(WORK)/10_sfm/cameras.json
	$(call timed,segment-boundary) $(BIN)/segment-boundary --image $(WORK)/10_sfm/reference.png --out $(WORK)/20_boundary --views $(DATA_DIR)/images --cameras $(WORK)/10_sfm/cameras.json $(BOUNDARY_FLAGS)

POINTS_OUT := $(addprefix $(WORK)/25_points/,points.ply points.json overlay.png)
points: check-data boundary $(POINTS_OUT)
$(POINTS_OUT) &: $(BIN)/densify $(WORK)/.flags/points $(WORK)/10_sfm/cameras.json $(WORK)/10_sfm/points.ply $(WORK)/10_sfm/reference.png $(WORK)/20_boundary/boundary.json $(WORK)/20_boundary/mask.png $(WORK)/.flags/images
	$(call timed,densify) $(BIN)/densify --data $(DATA_DIR) --sfm $(WORK)/10_sfm --boundary $(WORK)/20_boundary --out $(WORK)/25_points $(DENSIFY_FLAGS)

ifeq ($(FEATURES),)
FEATURES_OUT := $(addprefix $(WORK)/30_features/,features.json overlay.png)
$(FEATURES_OUT) &: $(BIN)/detect-features $(WORK)/.flags/features $(WORK)/10_sfm/reference.png $(WORK)/20_boundary/mask.png
	$(call timed,detect-features) $(BIN)/detect-features --image $(WORK)/10_sfm/reference.png --mask $(WORK)/20_boundary/mask.png --out $(WORK)/30_features $(FEATURES_FLAGS)
else
FEATURES_OUT := $(WORK)/30_features/features.json
# The stale overlay of an earlier detector run would mislead: remove it.
$(FEATURES_OUT): $(abspath $(FEATURES)) $(WORK)/.flags/features $(WORK)/10_sfm/reference.png
	@test -f $< || { echo "$<: no such file (FEATURES=)" >&2; exit 3; }
	$(ROOT)/scripts/validate-json --format docunfold.features $<
	@mkdir -p $(@D) && rm -f $(@D)/overlay.png
	cp $< $@.tmp && mv $@.tmp $@
endif
features: check-data boundary $(FEATURES_OUT)

SFM_IN := $(addprefix $(WORK)/10_sfm/,cameras.json points.ply reference.png)
BOUNDARY_IN := $(WORK)/20_boundary/boundary.json $(WORK)/20_boundary/mask.png

INIT_OUT := $(addprefix $(WORK)/40_init/,mesh3d.ply mesh2d.ply init.json)
init: check-data boundary $(if $(findstring 25_points,$(POINTS_FILE)),points) $(INIT_OUT)
$(INIT_OUT) &: $(BIN)/init-mesh $(WORK)/.flags/init $(SFM_IN) $(POINTS_FILE) $(BOUNDARY_IN)
	$(call timed,init-mesh) $(BIN)/init-mesh --sfm $(WORK)/10_sfm --boundary $(WORK)/20_boundary --points $(POINTS_FILE) --out $(WORK)/40_init $(INIT_FLAGS)

OPTIMIZE_OUT := $(addprefix $(WORK)/50_optimize/,mesh3d.ply mesh2d.ply lines.json log.json scene.glb)
optimize: check-data features init $(OPTIMIZE_OUT)
$(OPTIMIZE_OUT) &: $(BIN)/optimize $(WORK)/.flags/optimize $(INIT_OUT) $(SFM_IN) $(POINTS_FILE) $(BOUNDARY_IN) $(WORK)/30_features/features.json
	$(call timed,optimize) $(BIN)/optimize --sfm $(WORK)/10_sfm --boundary $(WORK)/20_boundary --features $(WORK)/30_features/features.json --init $(WORK)/40_init --points $(POINTS_FILE) --out $(WORK)/50_optimize $(OPTIMIZE_FLAGS)

# render textures the newest meshes there are: 50_optimize/ once optimize
# exists, else 40_init/.
MESH_STAGE := $(if $(wildcard $(ROOT)/stages/optimize),50_optimize,40_init)
RENDER_OUT := $(addprefix $(WORK)/60_render/,rectified.png rectified_grid.png)
render: check-data $(if $(wildcard $(ROOT)/stages/optimize),optimize,init) $(RENDER_OUT)
$(RENDER_OUT) &: $(BIN)/render $(WORK)/.flags/render $(WORK)/$(MESH_STAGE)/mesh3d.ply $(WORK)/$(MESH_STAGE)/mesh2d.ply $(SFM_IN) $(BOUNDARY_IN) $(WORK)/30_features/features.json
	$(call timed,render) $(BIN)/render --sfm $(WORK)/10_sfm --boundary $(WORK)/20_boundary --meshes $(WORK)/$(MESH_STAGE) --out $(WORK)/60_render --images $(DATA_DIR)/images --features $(WORK)/30_features/features.json $(RENDER_FLAGS)

# The searchable PDF at the page's paper size, with ALTO XML and hOCR.
PDF_OUT := $(addprefix $(WORK)/80_pdf/,$(NAME).pdf $(NAME).alto.xml $(NAME).hocr pdf.json)
pdf: check-data render $(PDF_OUT)
$(PDF_OUT) &: $(BIN)/pdf $(WORK)/.flags/pdf $(WORK)/60_render/rectified.png
	$(call timed,pdf) $(BIN)/pdf --render $(WORK)/60_render --out $(WORK)/80_pdf --name $(NAME) $(PDF_FLAGS)

EVAL_OUT := $(WORK)/70_eval/metrics.json
# The front end (20_boundary/, 30_features/) against the truth in the
# reference view, where the data set has a true surface.
HAS_TRUE_SURFACE := $(wildcard $(DATA_DIR)/ground_truth/mesh.ply)
FRONT_END_OUT := $(if $(HAS_TRUE_SURFACE),$(WORK)/70_eval/front_end.json)
# The searchable PDF's text layer and page size, where the data set has its
# true text.
HAS_TRUE_TEXT := $(wildcard $(DATA_DIR)/ground_truth/text.txt)
PDF_EVAL_OUT := $(if $(and $(HAS_TRUE_TEXT),$(wildcard $(ROOT)/stages/pdf)),$(WORK)/70_eval/pdf.json)
evaluate: check-data render $(EVAL_OUT) $(FRONT_END_OUT) $(PDF_EVAL_OUT)
$(EVAL_OUT): $(BIN)/evaluate $(WORK)/.flags/evaluate $(WORK)/60_render/rectified.png
	@test -n "$(HAS_GT)" || { echo "pipeline.mk: $(DATA_DIR): no ground_truth/flat.png to evaluate against" >&2; exit 3; }
	$(call timed,evaluate) $(BIN)/evaluate --data $(DATA_DIR) --work $(WORK) --result $(WORK)/60_render/rectified.png --out $@ $(EVAL_FLAGS)
$(WORK)/70_eval/front_end.json: $(BIN)/evaluate $(SFM_IN) $(BOUNDARY_IN) $(WORK)/30_features/features.json
	$(call timed,evaluate-front-end) $(BIN)/evaluate --front-end --data $(DATA_DIR) --work $(WORK) --out $@
$(WORK)/70_eval/pdf.json: $(BIN)/evaluate $(WORK)/80_pdf/$(NAME).pdf
	$(call timed,evaluate-pdf) $(BIN)/evaluate --pdf $(WORK)/80_pdf/$(NAME).pdf --data $(DATA_DIR) --out $@

# The report is redrawn whenever a stage's output is newer.
REPORT_OUT := $(WORK)/report.html
report: check-data $(REPORT_OUT)
STAGE_OUTPUTS := sfm:SFM_OUT boundary:BOUNDARY_OUT points:POINTS_OUT features:FEATURES_OUT init:INIT_OUT \
  optimize:OPTIMIZE_OUT render:RENDER_OUT pdf:PDF_OUT
REPORT_IN := $(foreach s,$(STAGE_OUTPUTS),$(if $(filter $(call pair_name,$(s)),$(IMPLEMENTED) $(if $(wildcard $(ROOT)/stages/pdf),pdf)),$($(call pair_value,$(s))))) \
  $(if $(and $(HAS_GT),$(wildcard $(ROOT)/stages/evaluate)),$(EVAL_OUT) $(FRONT_END_OUT) $(PDF_EVAL_OUT))
$(REPORT_OUT): $(BIN)/report $(REPORT_IN) | check-data
	$(BIN)/report --data $(DATA_DIR) --work $(WORK) --out $@

# ---- batches ------------------------------------------------------------------
# Several data sets at once, each in its own work directory; with -j2 two run
# side by side. DATASETS takes names (samples/, data/) or paths.
DATASETS ?= $(notdir $(patsubst %/images,%,$(wildcard $(ROOT)/samples/*/images)))
.PHONY: all-samples datasets
all-samples: datasets
datasets: build
	@$(MAKE) --no-print-directory -f $(ROOT)/pipeline.mk NO_BUILD=1 $(addprefix dataset/,$(DATASETS))
dataset/%:
	@$(MAKE) --no-print-directory -f $(ROOT)/pipeline.mk NO_BUILD=1 DATA=$* WORK=$(WORK_ROOT)/$(notdir $*) all

# A document of several pages: each data set of DATASETS (in that order) is
# run as far as its PDF, two at a time with -j2, and the pages are joined into
# WORK_ROOT/<BOOK>.pdf, with each page's ALTO file and image in
# WORK_ROOT/<BOOK>.alto/. A page that fails stops the book.
BOOK ?=
.PHONY: book-pages
book: $(if $(NO_BUILD),,build)
	@test -n "$(BOOK)" || { echo "pipeline.mk: book needs BOOK=<name> and DATASETS=\"page1 page2 ...\"" >&2; exit 2; }
	@$(MAKE) --no-print-directory -f $(ROOT)/pipeline.mk NO_BUILD=1 book-pages
	$(ROOT)/scripts/book '$(ROOT)' '$(WORK_ROOT)' '$(BOOK)' $(DATASETS)
book-pages: $(addprefix book-page/,$(DATASETS))
book-page/%:
	@$(MAKE) --no-print-directory -f $(ROOT)/pipeline.mk NO_BUILD=1 DATA=$* pdf || \
	  { echo "pipeline.mk: book $(BOOK): page $* failed" >&2; exit 1; }

# ---- housekeeping -------------------------------------------------------------------
clean:
	rm -rf $(WORK)

help:
	@echo "docunfold pipeline"
	@echo
	@echo "Targets:"
	@echo "  all (default)  run every implemented stage on DATA"
	@echo "  sfm            COLMAP structure from motion -> work/<name>/10_sfm/"
	@echo "  boundary       document region and its four sides -> 20_boundary/"
	@echo "  points         more 3D points of the page (texture, outline) -> 25_points/"
	@echo "  features       straight text and edge segments -> 30_features/"
	@echo "  init           initial 3D mesh M and flat mesh M' -> 40_init/"
	@echo "  optimize       joint isometric optimisation with feature lines -> 50_optimize/"
	@echo "  render         the rectified, cropped page -> 60_render/"
	@echo "  pdf            searchable PDF at the paper's size, ALTO XML, hOCR -> 80_pdf/"
	@echo "  pages          photos of several pages in DATA: the others, each to work/<name>-p<k>,"
	@echo "                 all joined into work/<name>.pdf (WORK=dir: dir-p<k>, dir.pdf; part of all)"
	@echo "  evaluate       metrics against ground truth -> 70_eval/ (sets with ground_truth/;"
	@echo "                 front_end.json: boundary and features in the reference view;"
	@echo "                 pdf.json: the PDF's text layer and page size)"
	@echo "  report         one HTML page with every stage's output -> work/<name>/report.html"
	@echo "  test           build, then run all tests (ctest)"
	@echo "  build          configure and build build/bin/*"
	@echo "  deps           install missing Debian packages (root) or print the apt-get line"
	@echo "  bench          time every stage on every sample -> bench/results.md"
	@echo "  fuzz           build-fuzz/: fuzz every file reader (clang, ASan, UBSan) for FUZZ_SECONDS"
	@echo "  all-samples    run every sample (or DATASETS=\"a b c\"), in parallel with -j2"
	@echo "  book           BOOK=letter DATASETS=\"p1 p2 p3\": one PDF of those pages, in that order,"
	@echo "                 -> work/letter.pdf (and work/letter.alto/); with -j2 two pages at a time"
	@echo "  clean          remove work/<name>/"
	@echo
	@echo "Variables:"
	@echo "  DATA=set01     data set: samples/<DATA>, data/<DATA>, or a path (default set01;"
	@echo "                 spaces, accents, . and .. work: DATA=\"My Scans/letter 1\"): a folder"
	@echo "                 with the photos in its images/, or the folder of photos itself"
	@echo "  WORK=dir       work directory (default work/<name>/)"
	@echo "  WORK_ROOT=dir  where work directories go (default work/)"
	@echo "  DATASETS=...   data sets for all-samples (default: every samples/*)"
	@echo "  REF=img.jpg    reference view for sfm (default: chosen automatically)"
	@echo "  SFM_FLAGS=...  extra flags for build/bin/sfm (see build/bin/sfm --help)"
	@echo "  BOUNDARY_FLAGS=...  extra flags for build/bin/segment-boundary"
	@echo "  FEATURES_FLAGS=...  extra flags for build/bin/detect-features"
	@echo "  FEATURES=f.json     use another detector's segments (docunfold.features) instead"
	@echo "  DENSIFY_FLAGS=...   extra flags for build/bin/densify"
	@echo "  DENSIFY=0           fit sfm's sparse points only (skip densify)"
	@echo "  INIT_FLAGS=...      extra flags for build/bin/init-mesh"
	@echo "  OPTIMIZE_FLAGS=...  extra flags for build/bin/optimize"
	@echo "  RENDER_FLAGS=...    extra flags for build/bin/render"
	@echo "  PDF_FLAGS=...       extra flags for build/bin/pdf (e.g. --lang deu, --enhance even-light)"
	@echo "  EVAL_FLAGS=...      extra flags for build/bin/evaluate"
	@echo "  JOBS=2         parallel build jobs"
	@echo "  TIMER=file     where per-stage time and peak memory go (default work/<name>/timings.jsonl)"
	@echo "  BENCH_SETS=... samples for bench (default: all)"
	@echo "  FUZZ_SECONDS=600    seconds per fuzz target (JOBS targets at a time)"
	@echo "  FUZZ_TARGETS=...    fuzz only these (ply cameras ...; default: every fuzz/*_fuzzer.cc)"
	@echo
	@echo "Changing REF or a *_FLAGS variable reruns that stage and everything after it."
