#!/usr/bin/env bash
# Makes samples/set01 ... set08 with build/bin/synth. Each set also keeps the
# exact command that made it in its COMMAND file. The sets cover the paper's
# three classes (text pages; statements and posters with tables; receipts
# and tickets), from one fold to several creases plus a curl, 3 to 6 views,
# plain and textured tables, one set at 4000x3000 and one cut-off page.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
synth="$root/build/bin/synth"
s="$root/samples"
"$synth" --force --out "$s/set01" --seed 101 --kind text    --creases 1 --angle-min 40 --angle-max 80 --views 5 --background plain
"$synth" --force --out "$s/set02" --seed 102 --kind table   --creases 2 --angle-min 25 --angle-max 70 --views 4 --background wood
"$synth" --force --out "$s/set03" --seed 103 --kind receipt --creases 2 --angle-min 30 --angle-max 90 --views 4 --background cloth
"$synth" --force --out "$s/set04" --seed 104 --kind poster  --creases 1 --curl --angle-min 30 --angle-max 70 --views 5 --background granite
"$synth" --force --out "$s/set05" --seed 105 --kind text    --creases 4 --angle-min 15 --angle-max 50 --views 6 --background plain
"$synth" --force --out "$s/set06" --seed 106 --kind table   --creases 3 --curl --angle-min 20 --angle-max 60 --views 3 --background cloth --width 4000 --height 3000 --jpeg-quality 85
"$synth" --force --out "$s/set07" --seed 107 --kind receipt --page-size 100x150 --creases 3 --angle-min 30 --angle-max 110 --views 4 --background wood
"$synth" --force --out "$s/set08" --seed 108 --kind text    --creases 2 --angle-min 25 --angle-max 60 --views 4 --background granite --cut-off
du -sh "$s"
