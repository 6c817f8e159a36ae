#!/usr/bin/env bash
# run_e2e.sh SOURCE BUILD OUT: the run behind the end-to-end tests. The whole
# pipeline on every data set with ground truth (samples/*, and the
# independently rendered ../shared/realistic/* when present), with the rows
# the checks compare against (homography, oracle and its crop to what the
# photos see, docunfold-init, and both
# with the light's shading removed), through
# scripts/bench.sh; two sets side by side; then a book of three samples'
# PDFs. OCR is left out (the metrics
# reference test covers it), and so is the benchmark's Gauss-Newton against
# L-BFGS timing (10 s with one core idle; no test reads it, and
# the BenchReport tests cover its table). Exits non-zero only when the run itself fails;
# each set's outcome is for the tests to judge.
set -uo pipefail
src=$1 build=$2 out=$3
sets=()
for d in "$src"/samples/*/; do [[ -d $d/images && -f $d/ground_truth/flat.png ]] && sets+=("${d%/}"); done
realistic=${DOCUNFOLD_REALISTIC_DIR:-$src/../shared/realistic}
if [[ -d $realistic ]]; then
  for d in "$realistic"/*/; do [[ -d $d/images && -f $d/ground_truth/flat.png ]] && sets+=("${d%/}"); done
fi
rm -rf "$out"
mkdir -p "$out"
BUILD=$build BENCH_WORK=$out/work BENCH_OUT=$out BENCH_JOBS=${E2E_JOBS:-2} \
  BENCH_ONLY="homography oracle oracle-seen docunfold docunfold-init oracle-deshaded docunfold-deshaded" BENCH_EVAL_FLAGS=--no-ocr \
  BENCH_OCR_SIZE=native BENCH_SOLVER_SET=none "$src/scripts/bench.sh" "${sets[@]}" > "$out/bench.log" 2>&1
rc=$?
# A book of three samples' PDFs (made above), joined in the order given.
make -s -j2 -f "$src/pipeline.mk" NO_BUILD=1 BUILD="$build" WORK_ROOT="$out/work" book \
  BOOK=e2e-book DATASETS="set06 set01 set04" >> "$out/bench.log" 2>&1 || rc=1
tail -n 40 "$out/bench.log"
exit $rc
