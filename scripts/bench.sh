#!/usr/bin/env bash
# Benchmark: runs the pipeline from scratch on each sample (default: every
# samples/set*) with per-stage timing, then writes bench/results.md and
# bench/results.json. Speed and memory live here, never in tests.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
sets=("$@")
if [[ ${#sets[@]} -eq 0 ]]; then
  for d in "$root"/samples/set*/; do sets+=("$(basename "$d")"); done
fi
bench_work="$root/work/bench"
rm -rf "$bench_work"
for s in "${sets[@]}"; do
  echo "bench: $s" >&2
  make -s -f "$root/pipeline.mk" DATA="$s" WORK="$bench_work/$s" \
    TIMER="$bench_work/$s/timings.jsonl" all >&2 ||
    echo "bench: $s failed (recorded)" >&2
done
/usr/bin/python3 "$root/scripts/bench_report.py" "$root" "$bench_work" "${sets[@]}"
