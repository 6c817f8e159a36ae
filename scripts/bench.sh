#!/usr/bin/env bash
# Benchmark: runs the pipeline from scratch on each data set with per-stage
# timing, makes the reference methods' images, evaluates every row against
# the ground truth and writes bench/results.md and bench/results.json.
# Speed, memory and accuracy live here, never in tests.
#
#   scripts/bench.sh [SET...]      (make -f pipeline.mk bench BENCH_SETS="...")
#
# SET is a name (samples/<SET>, data/<SET>), a path (/work/shared/realistic/r01)
# or set01-48mp: set01 with one photo at 8000 x 6000, as a 48 MP phone takes
# it (made by build/tests/phone-photos into BENCH_WORK/.data/), for the peak
# memory of every stage on such a photo.
# Default: every samples/*, data/*, ../shared/realistic/* and
# ../shared/realistic-hard/* with ground_truth/flat.png, and set01-48mp.
#
# Environment:
#   BUILD=dir            build directory with bin/ (default <root>/build)
#   BENCH_WORK=dir       work directories, one per set (default <root>/work/bench)
#   BENCH_OUT=dir        where results.{md,json} go (default <root>/bench)
#   BENCH_FRONTEND=truth replace sfm and segment-boundary by the ground truth
#                        (build/tests/truth-frontend): measures the later stages
#                        alone, or shows the table before the front end exists
#   BENCH_EVAL_FLAGS=... extra evaluate flags for every row (e.g. --no-ocr)
#   BENCH_OCR_SIZE=native  OCR every result as it is; default "truth": OCR it
#                        at flat.png's size (evaluate --ocr-at-truth-size), so
#                        that CER compares geometry, not the output resolution
#                        each method picked (render keeps the photo's density)
#   BENCH_JOBS=N         data sets run side by side (default 1: timings are
#                        then undisturbed; the end-to-end tests use 2)
#   BENCH_ONLY="row ..." make only these built-in rows (default: all)
#   BENCH_SOLVER_SET=name the set on which optimize runs once with Gauss-Newton
#                        and once with L-BFGS on the same inputs (default: set05
#                        when benched, else the first set; "none" skips it)
#   BENCH_ROWS="name=path/in/work.png[:mesh dir in work] ..."
#                        further rows: any image the pipeline leaves in the work
#                        directory, evaluated like the others
#
# Per set, the front end (20_boundary/, 30_features/) is measured against the
# truth in sfm's reference view (evaluate --front-end -> 70_eval/front_end.json).
# Rows per set: homography, oracle, oracle-seen and oracle-multiview
# (build/bin/baseline), docunfold (60_render/rectified.png) when render ran,
# and, when the binaries exist, docunfold-reference (render --texture
# reference), docunfold-init (render on 40_init), docunfold-nofeatures and
# docunfold-boundary (optimize --no-feature-lines / --boundary-only, then render),
# docunfold-from-truth (optimize started from the true surface, then render),
# and docunfold-deshaded and oracle-deshaded (render / baseline --shading
# remove: the light's shading divided out of the final meshes' rendering and
# of the oracle alike).
# To add a built-in row, write a make_row_<name> function below and list it
# in ROWS: it makes the image (through `timed`) and sets `image` (and
# `mesh_dir` for geometry), or returns 1 with `reason` set when not applicable.
set -uo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
BUILD=${BUILD:-$root/build}
bin=$BUILD/bin
bench_work=${BENCH_WORK:-$root/work/bench}
bench_out=${BENCH_OUT:-$root/bench}
frontend=${BENCH_FRONTEND:-pipeline}
read -r -a eval_flags <<< "${BENCH_EVAL_FLAGS:-}"
ocr_size=${BENCH_OCR_SIZE:-truth}
case $ocr_size in
  truth) eval_flags+=(--ocr-at-truth-size) ;;
  native) ;;
  *) echo "bench: BENCH_OCR_SIZE=$ocr_size: expected truth or native" >&2; exit 2 ;;
esac
# Every row also scored after one affine map (evaluate --registered): the
# share of its loss that is the crop's sides and the page's scale.
eval_flags+=(--registered)
timer=$root/scripts/stage-timer

case $frontend in pipeline|truth) ;; *)
  echo "bench: BENCH_FRONTEND=$frontend: expected pipeline or truth" >&2; exit 2 ;;
esac

# ---- data sets -----------------------------------------------------------------
resolve() {  # name or path -> absolute data-set folder ("" if none)
  local s=$1
  if [[ $s == set01-48mp ]]; then
    local made=$bench_work/.data/set01-48mp
    if [[ ! -d $made && -x $BUILD/tests/phone-photos ]]; then
      mkdir -p "$bench_work/.data"
      "$BUILD/tests/phone-photos" "$root/samples/set01" "$made" --scale 3:5 >&2 || return
    fi
    [[ -d $made/images ]] && (cd "$made" && pwd)
    return
  fi
  for d in "$root/samples/$s" "$root/data/$s" "$s"; do
    if [[ -d $d/images ]]; then (cd "$d" && pwd); return; fi
  done
}
sets=("$@")
if [[ ${#sets[@]} -eq 0 ]]; then
  # The independent renderer's sets beside the repository, when present.
  for d in "$root"/samples/*/ "$root"/data/*/ "$root"/../shared/realistic/*/ \
           "$root"/../shared/realistic-hard/*/; do
    [[ -f $d/ground_truth/flat.png && -d $d/images ]] && sets+=("$d")
  done
  [[ -d $root/samples/set01 && -x $BUILD/tests/phone-photos ]] && sets+=(set01-48mp)
fi
if [[ ${#sets[@]} -eq 0 ]]; then
  echo "bench: no data set with ground truth in samples/ or data/" >&2; exit 3
fi
data_dirs=() names=()
for s in "${sets[@]}"; do
  d=$(resolve "$s")
  if [[ -z $d ]]; then
    echo "bench: $s: no data set (looked for images/ in samples/$s, data/$s and $s)" >&2; exit 3
  fi
  n=$(basename "$d")
  # Two sets with the same folder name (samples/r01, realistic/r01) get
  # distinct work directories.
  while printf '%s\n' "${names[@]}" | grep -qx -- "$n"; do n="$n+"; done
  data_dirs+=("$d") names+=("$n")
done
if [[ $frontend == truth ]]; then
  cmake --build "$BUILD" --target truth-frontend -j2 > /dev/null ||
    { echo "bench: cannot build truth-frontend" >&2; exit 1; }
fi
for b in baseline evaluate; do
  [[ -x $bin/$b ]] || { echo "bench: $bin/$b is missing; run make -f pipeline.mk build" >&2; exit 1; }
done

# ---- pipeline stages ----------------------------------------------------------------
# The pipeline.mk targets to run: every stage whose program is built and whose
# inputs some runnable stage makes (so a stage that is being written, or one
# whose predecessor is, is simply absent). evaluate is the bench's own
# business (one run per row).
declare -A program_of=([sfm]=sfm [boundary]=segment-boundary [points]=densify
                       [features]=detect-features [init]=init-mesh [optimize]=optimize
                       [render]=render [pdf]=pdf)
declare -A needs=([sfm]="" [boundary]="sfm" [points]="sfm boundary" [features]="sfm boundary"
                  [init]="sfm boundary"
                  [optimize]="features init" [render]="sfm boundary init" [pdf]="render")
# pipeline.mk renders the optimised meshes as soon as stages/optimize exists.
[[ -d $root/stages/optimize ]] && needs[render]+=" optimize"
declare -A runnable=()
if [[ $frontend == truth ]]; then runnable[sfm]=1 runnable[boundary]=1; fi
pipeline_targets=() absent=()
for s in sfm boundary points features init optimize render pdf; do
  [[ -n ${runnable[$s]:-} ]] && continue
  ok=1
  [[ -x $bin/${program_of[$s]} ]] || ok=""
  for n in ${needs[$s]}; do [[ -n ${runnable[$n]:-} ]] || ok=""; done
  if [[ -n $ok ]]; then runnable[$s]=1; pipeline_targets+=("$s"); else absent+=("$s"); fi
done
echo "bench: front end: $frontend; stages run: ${pipeline_targets[*]:-none}; absent: ${absent[*]:-none}" >&2

# ---- rows ------------------------------------------------------------------------
# Set by run_set for the row functions: data, work, reason, image, mesh_dir.
timed() {  # timed <row> <command...>: time one command of making a row's image
  local row=$1; shift
  "$timer" "$work/bench/timings.jsonl" "make:$row" "$@" >> "$work/bench/$row.log" 2>&1
}
have() { [[ -x $bin/$1 ]]; }

make_row_homography() {
  [[ -f $work/10_sfm/cameras.json && -f $work/20_boundary/boundary.json ]] ||
    { reason="no 10_sfm/ or 20_boundary/boundary.json"; return 1; }
  image=$work/bench/homography.png
  # Read the same way up as docunfold's result (a scanner app turns its page
  # upright too): segment-boundary's corner labels are a quarter or half turn
  # off wherever it cannot read the text.
  local turns=0
  if [[ -f $work/60_render/render.json ]]; then
    turns=$(/usr/bin/python3 -c 'import json, sys
print(json.load(open(sys.argv[1])).get("orientation", {}).get("quarter_turns_clockwise", 0))' \
      "$work/60_render/render.json" 2>/dev/null) || turns=0
  fi
  timed homography "$bin/baseline" --method homography --data "$data" --work "$work" \
    --quarter-turns "${turns:-0}" --out "$image"
}
make_row_oracle() {
  [[ -f $work/10_sfm/cameras.json ]] || { reason="no 10_sfm/cameras.json"; return 1; }
  [[ -f $data/ground_truth/mesh.ply ]] || { reason="no ground_truth/mesh.ply"; return 1; }
  image=$work/bench/oracle.png
  timed oracle "$bin/baseline" --method oracle --data "$data" --work "$work" --out "$image"
}
# The oracle cropped to the part of the page some photo sees: where a page is
# cut off in every photo, the plain oracle still knows from the true surface
# where it ends; no method working from the photos can.
make_row_oracle-seen() {
  [[ -f $work/10_sfm/cameras.json ]] || { reason="no 10_sfm/cameras.json"; return 1; }
  [[ -f $data/ground_truth/mesh.ply ]] || { reason="no ground_truth/mesh.ply"; return 1; }
  image=$work/bench/oracle-seen.png
  timed oracle-seen "$bin/baseline" --method oracle --crop-to-seen --data "$data" \
    --work "$work" --out "$image"
}
# The true surface textured from every photo through the true cameras by
# render's texture fusion, cropped like oracle-seen to the part some photo
# sees: the ceiling for texturing from all the photos.
make_row_oracle-multiview() {
  [[ -f $work/10_sfm/cameras.json ]] || { reason="no 10_sfm/cameras.json"; return 1; }
  [[ -f $data/ground_truth/mesh.ply ]] || { reason="no ground_truth/mesh.ply"; return 1; }
  image=$work/bench/oracle-multiview.png
  timed oracle-multiview "$bin/baseline" --method oracle-multiview --crop-to-seen \
    --data "$data" --work "$work" --out "$image"
}
make_row_docunfold() {
  [[ -f $work/60_render/rectified.png ]] || { reason="render did not run"; return 1; }
  image=$work/60_render/rectified.png
}
# The same meshes rendered with the light's shading divided out, and the
# oracle with it divided out the same way (the fair ceiling for that row).
# The final meshes (init-mesh's without optimize) rendered again with other
# render flags: render_variant <row> <suffix> <render flag...>.
render_variant() {
  local row=$1 suffix=$2
  shift 2
  have render || { reason="no render binary"; return 1; }
  local meshes=$work/50_optimize
  [[ -f $meshes/mesh3d.ply ]] || meshes=$work/40_init
  [[ -f $meshes/mesh3d.ply ]] || { reason="no meshes"; return 1; }
  mesh_dir=$meshes
  timed "$row" "$bin/render" --sfm "$work/10_sfm" --boundary "$work/20_boundary" \
    --meshes "$meshes" --out "$work/60_render_$suffix" --images "$data/images" \
    --features "$work/30_features/features.json" "$@" || return
  image=$work/60_render_$suffix/rectified.png
}
make_row_docunfold-deshaded() { render_variant docunfold-deshaded deshaded --shading remove; }
make_row_oracle-deshaded() {
  [[ -f $work/10_sfm/cameras.json ]] || { reason="no 10_sfm/cameras.json"; return 1; }
  [[ -f $data/ground_truth/mesh.ply ]] || { reason="no ground_truth/mesh.ply"; return 1; }
  image=$work/bench/oracle-deshaded.png
  timed oracle-deshaded "$bin/baseline" --method oracle --data "$data" --work "$work" \
    --out "$image" --shading remove
}
# The final meshes textured from the reference photo alone (render
# --texture reference), as the paper does: what texture fusion adds.
make_row_docunfold-reference() { render_variant docunfold-reference reference --texture reference; }
make_row_docunfold-init() {
  have render || { reason="no render binary"; return 1; }
  [[ -f $work/40_init/mesh3d.ply ]] || { reason="no 40_init/mesh3d.ply"; return 1; }
  [[ -d $work/50_optimize ]] || { reason="same as docunfold (no optimize)"; return 1; }
  mesh_dir=$work/40_init
  timed docunfold-init "$bin/render" --sfm "$work/10_sfm" --boundary "$work/20_boundary" \
    --meshes "$work/40_init" --out "$work/60_render_init" --images "$data/images" \
    --features "$work/30_features/features.json" || return
  image=$work/60_render_init/rectified.png
}
# The point cloud pipeline.mk gave init-mesh and optimize (densify's when it ran).
points_args() {
  if [[ -f $work/25_points/points.ply ]]; then echo --points "$work/25_points/points.ply"; fi
}
optimize_variant() {  # optimize_variant <row> <suffix> <init dir> [optimize flag...]
  local row=$1 suffix=$2 init=$3
  shift 3
  { have optimize && have render; } || { reason="no optimize or render binary"; return 1; }
  [[ -f $init/mesh3d.ply && -f $work/30_features/features.json ]] ||
    { reason="no $(basename "$init")/ or 30_features/"; return 1; }
  mesh_dir=$work/50_optimize_$suffix
  timed "$row" "$bin/optimize" --sfm "$work/10_sfm" --boundary "$work/20_boundary" \
    --features "$work/30_features/features.json" --init "$init" \
    $(points_args) --out "$mesh_dir" "$@" || return
  timed "$row" "$bin/render" --sfm "$work/10_sfm" --boundary "$work/20_boundary" \
    --meshes "$mesh_dir" --out "$work/60_render_$suffix" --images "$data/images" \
    --features "$work/30_features/features.json" || return
  image=$work/60_render_$suffix/rectified.png
}
make_row_docunfold-nofeatures() {
  optimize_variant docunfold-nofeatures nofeatures "$work/40_init" --no-feature-lines
}
make_row_docunfold-boundary() {
  optimize_variant docunfold-boundary boundary "$work/40_init" --boundary-only
}
# Optimize started from the true surface instead of init-mesh's meshes (the
# truth on init-mesh's grid, taken into sfm's frame by build/tests/truth-init):
# what optimize itself loses, apart from what init-mesh and the points lose.
make_row_docunfold-from-truth() {
  [[ -x $BUILD/tests/truth-init ]] || { reason="no $BUILD/tests/truth-init"; return 1; }
  [[ -f $data/ground_truth/mesh.ply ]] || { reason="no ground_truth/mesh.ply"; return 1; }
  [[ -f $work/40_init/mesh3d.ply ]] || { reason="no 40_init/mesh3d.ply"; return 1; }
  timed docunfold-from-truth "$BUILD/tests/truth-init" "$data" "$work" "$work/40_init_truth" ||
    { reason="truth-init failed: $(tail -n 1 "$work/bench/docunfold-from-truth.log")"; return 1; }
  optimize_variant docunfold-from-truth truth "$work/40_init_truth"
}

ROWS=(homography oracle oracle-seen oracle-multiview docunfold docunfold-reference docunfold-init
      docunfold-nofeatures docunfold-boundary docunfold-from-truth oracle-deshaded
      docunfold-deshaded)
if [[ -n ${BENCH_ONLY:-} ]]; then read -r -a ROWS <<< "$BENCH_ONLY"; fi
read -r -a extra_rows <<< "${BENCH_ROWS:-}"

# Appends one line to the set's rows.tsv: method status image metrics mesh_dir note.
record() { printf '%s\t%s\t%s\t%s\t%s\t%s\n' "$@" >> "$work/bench/rows.tsv"; }

evaluate_row() {  # evaluate_row <method> <image> <mesh dir or "">
  local method=$1 img=$2 mesh=$3 metrics=$work/70_eval/metrics-$1.json geometry=()
  if [[ -n $mesh ]]; then geometry=(--mesh-dir "$mesh")
  elif [[ $method != docunfold ]]; then geometry=(--no-geometry); fi
  if "$timer" "$work/bench/timings.jsonl" "evaluate:$method" "$bin/evaluate" --data "$data" \
       --work "$work" --result "$img" --out "$metrics" --method "$method" \
       "${geometry[@]}" "${eval_flags[@]}" >> "$work/bench/$method.log" 2>&1; then
    record "$method" ok "$img" "$metrics" "$mesh" ""
  else
    record "$method" failed "$img" "" "$mesh" "evaluate failed: $(tail -n 1 "$work/bench/$method.log")"
  fi
}

run_set() {  # run_set <data dir> <work dir>
  data=$1 work=$2
  rm -rf "$work"
  mkdir -p "$work/bench" "$work/70_eval"
  : > "$work/bench/rows.tsv"
  local make_args=(-f "$root/pipeline.mk" NO_BUILD=1 BUILD="$BUILD" DATA="$data" WORK="$work"
                   TIMER="$work/timings.jsonl")
  local targets=("${pipeline_targets[@]}")
  if [[ $frontend == truth ]]; then
    "$timer" "$work/timings.jsonl" truth-frontend "$BUILD/tests/truth-frontend" "$data" "$work" \
      >> "$work/bench/pipeline.log" 2>&1 || echo "bench: truth front end failed" >&2
    # make must not remake (nor rerun anything because of) the front end's files.
    for f in 10_sfm/cameras.json 10_sfm/points.ply 10_sfm/reference.png \
             20_boundary/boundary.json 20_boundary/mask.png 20_boundary/overlay.png; do
      make_args+=(-o "$work/$f")
    done
  fi
  local status=0
  if [[ ${#targets[@]} -gt 0 ]]; then
    make -s "${make_args[@]}" "${targets[@]}" >> "$work/bench/pipeline.log" 2>&1 || status=$?
  fi
  echo "$status" > "$work/bench/pipeline.exit"
  [[ $status -eq 0 ]] || echo "bench: pipeline failed (exit $status; see $work/bench/pipeline.log)" >&2
  # The front end against the truth in sfm's reference view: boundary IoU,
  # corners, real sides; features precision, recall.
  if [[ -f $work/10_sfm/cameras.json && -f $data/ground_truth/mesh.ply ]]; then
    "$timer" "$work/bench/timings.jsonl" "evaluate:front-end" "$bin/evaluate" --front-end \
      --data "$data" --work "$work" --out "$work/70_eval/front_end.json" \
      >> "$work/bench/front_end.log" 2>&1 ||
      echo "bench: evaluate --front-end failed: $(tail -n 1 "$work/bench/front_end.log")" >&2
  fi
  # The searchable PDF read back as a viewer reads it: words a search finds,
  # CER in reading order, page size.
  local pdf_file=$work/80_pdf/$(basename "$work").pdf
  if [[ -f $pdf_file && -f $data/ground_truth/text.txt ]]; then
    "$timer" "$work/bench/timings.jsonl" "evaluate:pdf" "$bin/evaluate" --pdf "$pdf_file" \
      --data "$data" --out "$work/70_eval/pdf.json" >> "$work/bench/pdf_eval.log" 2>&1 ||
      echo "bench: evaluate --pdf failed: $(tail -n 1 "$work/bench/pdf_eval.log")" >&2
  fi
  if [[ ! -f $data/ground_truth/flat.png ]]; then
    record "-" skipped "" "" "" "no ground_truth/flat.png: not evaluated"
    return
  fi
  local row
  for row in "${ROWS[@]}"; do
    image="" mesh_dir="" reason=""
    if "make_row_$row"; then
      if [[ -f $image ]]; then evaluate_row "$row" "$image" "$mesh_dir"
      else record "$row" failed "" "" "" "no image made"; fi
    elif [[ -n $reason ]]; then
      record "$row" skipped "" "" "" "$reason"
    else
      record "$row" failed "" "" "" "making the image failed: $(tail -n 1 "$work/bench/$row.log" 2>/dev/null)"
    fi
  done
  local spec name rest path mesh
  for spec in "${extra_rows[@]}"; do
    name=${spec%%=*} rest=${spec#*=}
    path=${rest%%:*} mesh=""
    [[ $rest == *:* ]] && mesh=$work/${rest#*:}
    if [[ -f $work/$path ]]; then evaluate_row "$name" "$work/$path" "$mesh"
    else record "$name" skipped "" "" "" "no $path in the work directory"; fi
  done
}

jobs=${BENCH_JOBS:-1}
for i in "${!data_dirs[@]}"; do
  # At most $jobs sets at once; each set's run is a subshell of its own.
  while [[ $(jobs -rp | wc -l) -ge $jobs ]]; do wait -n; done
  echo "bench: ${names[$i]} (${data_dirs[$i]})" >&2
  run_set "${data_dirs[$i]}" "$bench_work/${names[$i]}" &
done
wait

# Gauss-Newton against L-BFGS: optimize twice on one set's inputs, nothing
# else running; bench_report.py reads both log.json files (time to reach the
# same F in the last round).
solver_set=${BENCH_SOLVER_SET:-}
if [[ -z $solver_set ]]; then
  solver_set=${names[0]}
  for n in "${names[@]}"; do [[ $n == set05 ]] && solver_set=set05; done
fi
solver_args=()
if [[ $solver_set != none ]] && have optimize; then
  sw=$bench_work/$solver_set
  if [[ -f $sw/40_init/mesh3d.ply && -f $sw/30_features/features.json ]]; then
    for solver in gn lbfgs; do
      echo "bench: optimize --solver $solver on $solver_set" >&2
      "$timer" "$sw/bench/timings.jsonl" "solver:$solver" "$bin/optimize" --sfm "$sw/10_sfm" \
        --boundary "$sw/20_boundary" --features "$sw/30_features/features.json" \
        --init "$sw/40_init" $(work=$sw points_args) --out "$sw/bench/solver_$solver" --solver "$solver" --no-scene \
        >> "$sw/bench/solver_$solver.log" 2>&1 || echo "bench: optimize --solver $solver failed" >&2
    done
    solver_args=(--solver-set "$solver_set")
  fi
fi

args=()
for i in "${!data_dirs[@]}"; do args+=("${names[$i]}=${data_dirs[$i]}"); done
/usr/bin/python3 "$root/scripts/bench_report.py" --root "$root" --work "$bench_work" \
  --out "$bench_out" --frontend "$frontend" --eval-flags="${eval_flags[*]}" \
  "${solver_args[@]}" "${args[@]}"
