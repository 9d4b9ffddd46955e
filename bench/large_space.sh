#!/usr/bin/env bash
# Issue 10's large-space bench: a walk of about 43 m through the synthetic house (a corridor and
# five rooms with a picture or a shelf every metre of wall; 2,500 frames at 30 Hz, 640x480,
# Kinect-like noise), tracked with the sparse map, with the sparse map under MaxMemoryMB=48 (blocks
# swapped to disk), with the dense grid (a 5 m cube, which the walk leaves), and with
# --fuse-ground-truth: the tracker's own error per frame. The same walk through the house with bare
# walls (`sdf_tracker_synth --bare-walls`; six pictures in the corridor) is tracked too: there,
# close to a wall, the view holds one plane, which depth cannot place, and the ATE is decided by
# the slides that follow.
# Reports every frame tracked or not, ATE, the peak resident memory, and ms per frame and map memory
# against the path length. Writes bench/results/<date>_large_space.md with a plot beside it.
#   bash bench/large_space.sh [FRAMES]     (about 20 minutes on 2 cores, half of it rendering)
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
frames="${1:-2500}"
bench_setup large_space
require_matplotlib

walk="$work/walk_furnished_$frames"
bare_walk="$work/walk_bare_walls_$frames"
render() {  # render DIR [sdf_tracker_synth options]
  local dir="$1"
  shift
  if [ ! -f "$dir/depth.txt" ]; then
    echo "rendering $(basename "$dir") ($frames frames)"
    "$bin/sdf_tracker_synth" --output "$dir" --motion walk --frames "$frames" --seed 7 "$@" >/dev/null
  fi
}
render "$walk"
render "$bare_walk" --bare-walls
# name: the walk and the offline runner's parameters for it
declare -A runs=(
  [sparse]="$walk --param MapType=sparse"
  [sparse_48mb]="$walk --param MapType=sparse --param MaxMemoryMB=48"
  [dense]="$walk --param MapType=dense"
  [sparse_true_poses]="$walk --param MapType=sparse --fuse-ground-truth"
  [sparse_bare_walls]="$bare_walk --param MapType=sparse"
)
for run in sparse sparse_48mb dense sparse_true_poses sparse_bare_walls; do
  echo "tracking $run"
  # shellcheck disable=SC2086  # the walk and the parameters are words
  "$bin/sdf_tracker_offline" --sequence ${runs[$run]} --output "$work/$run" --quiet --threads 2 \
    > "$work/$run.log" 2>&1 || echo "  failed: see $work/$run.log"
done
report="$results/$(date +%Y-%m-%d)_large_space.md"
/usr/bin/python3 "$repo/bench/report/large_space.py" "$walk" "$work" "$report"
echo "wrote $report"
