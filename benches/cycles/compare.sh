#!/usr/bin/env bash
# The whole-process comparison with Blender Cycles (docs/performance.md, "Against Cycles"):
# the paper-low mesh with vertex normals, 1024 x 512, 16 spp, 10 bounces, 2 threads, the
# shipped map sky. Runs vastocean's whole process and Cycles' render in turn RUNS times and
# prints, per pair, our wall time, Cycles' own render time (sync + BVH + trace, without
# Blender's start-up and the PLY import) and their ratio; then the medians.
#
#   benches/cycles/compare.sh [RUNS]      (needs `blender`: Debian's package; not a project
#                                           dependency, install it yourself to run this)
set -euo pipefail
runs=${1:-5}
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
bin="$root/target/release/vastocean"
sky="$root/skies/clear-sun03.exr"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
command -v blender >/dev/null || { echo "compare.sh: blender is not installed (apt-get install blender)" >&2; exit 2; }
[ -x "$bin" ] || { echo "compare.sh: build first (make build)" >&2; exit 2; }
"$bin" mesh --lod paper-low --ply "$work/mesh.ply" >/dev/null
echo "pair ours_wall_s cycles_render_s ratio"
for i in $(seq "$runs"); do
  start=$(date +%s.%N)
  "$bin" render --sky "$sky" --width 1024 --spp 16 --normals vertex --threads 2 --out "$work/ours" >/dev/null 2>&1
  ours=$(awk -v a="$start" -v b="$(date +%s.%N)" 'BEGIN {print b - a}')
  cycles=$(blender -b --factory-startup -P "$here/cycles_render.py" -- "$work/mesh.ply" "$sky" \
    "$work/cycles.png" 1024 16 2 2>/dev/null | awk '/^cycles_render_seconds/ {print $2}')
  awk -v i="$i" -v o="$ours" -v c="$cycles" 'BEGIN {printf "%d %.3f %.3f %.3f\n", i, o, c, o / c}'
done | tee "$work/pairs"
median() { sort -n | awk '{a[NR]=$1} END {print (NR % 2) ? a[(NR+1)/2] : (a[NR/2] + a[NR/2+1]) / 2}'; }
printf "median ours %.3f s, cycles %.3f s, ratio %.3f (Cycles / ours = %.2fx)\n" \
  "$(awk '{print $2}' "$work/pairs" | median)" \
  "$(awk '{print $3}' "$work/pairs" | median)" \
  "$(awk '{print $4}' "$work/pairs" | median)" \
  "$(awk '{print $3 / $2}' "$work/pairs" | median)"
