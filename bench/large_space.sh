#!/usr/bin/env bash
# Issue 10's large-space bench: a walk of about 42 m through the synthetic house (a corridor and
# five rooms; 2,500 frames at 30 Hz, 640x480, Kinect-like noise), tracked with the sparse map, with
# the sparse map under MaxMemoryMB=48 (blocks swapped to disk), and, for comparison, the dense grid
# (a 5 m cube, which the walk leaves), and with --fuse-ground-truth: the tracker's own error per
# frame, which does not swing with one unrecovered slide as the ATE does. Reports every frame tracked
# or not, ATE, the peak resident memory, and ms per frame and map memory against the path length.
# Writes bench/results/<date>_large_space.md with a plot beside it.
#   bash bench/large_space.sh [FRAMES]     (about 10 minutes on 2 cores, half of it rendering)
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
frames="${1:-2500}"
bench_setup large_space
require_matplotlib

walk="$work/walk_$frames"
if [ ! -f "$walk/depth.txt" ]; then
  echo "rendering the walk ($frames frames)"
  "$bin/sdf_tracker_synth" --output "$walk" --motion walk --frames "$frames" --seed 7 >/dev/null
fi
# name: the offline runner's parameters for it
declare -A runs=(
  [sparse]="--param MapType=sparse"
  [sparse_48mb]="--param MapType=sparse --param MaxMemoryMB=48"
  [dense]="--param MapType=dense"
  [sparse_true_poses]="--param MapType=sparse --fuse-ground-truth"
)
for run in sparse sparse_48mb dense sparse_true_poses; do
  echo "tracking the walk with ${runs[$run]}"
  # shellcheck disable=SC2086  # the parameters are words
  "$bin/sdf_tracker_offline" --sequence "$walk" --output "$work/$run" --quiet --threads 2 ${runs[$run]} \
    > "$work/$run.log" 2>&1 || echo "  failed: see $work/$run.log"
done
report="$results/$(date +%Y-%m-%d)_large_space.md"
/usr/bin/python3 "$repo/bench/large_space_report.py" "$walk" "$work" "$report"
echo "wrote $report"
