#!/usr/bin/env bash
# The main job, end to end: installs dependencies, builds, generates the default synthetic
# sequence (unless a TUM-layout folder is given), runs the tracker, prints accuracy and speed,
# and writes trajectory, mesh, cloud and plot to an output folder.
#   scripts/run_main.sh [SEQUENCE_DIR] [OUTPUT_DIR] [-- extra sdf_tracker_offline options]
set -euo pipefail
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
sequence="${1:-}"
output="${2:-$repo/output/main}"
shift $(( $# > 2 ? 2 : $# ))
[ "${1:-}" = "--" ] && shift

bash "$repo/scripts/install_dependencies.sh"
bash "$repo/scripts/build.sh"
bin="$repo/build/ws/devel/lib/sdf_tracker"

if [ -z "$sequence" ]; then
  sequence="$repo/output/default_sequence"
  if [ ! -f "$sequence/depth.txt" ]; then
    echo "generating the default synthetic sequence (desk motion, 300 frames, Kinect-like noise)"
    "$bin/sdf_tracker_synth" --output "$sequence" --motion desk --frames 300 --seed 1
  fi
fi

"$bin/sdf_tracker_offline" --sequence "$sequence" --output "$output" "$@"
echo "trajectory.txt, mesh.ply, cloud.ply, frames.csv, summary.txt and trajectory.png are in $output"
