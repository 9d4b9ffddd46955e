#!/usr/bin/env bash
# The main job, end to end through ROS: installs dependencies, builds, generates the default
# synthetic sequence (unless a TUM-layout folder is given), converts it to a TUM-style rosbag,
# plays it through sdf_tracker_node under roslaunch, then prints accuracy and speed and leaves
# trajectory, mesh, cloud and plot in an output folder.
#   scripts/run_main.sh [SEQUENCE_DIR] [OUTPUT_DIR]
# RATE (default 0.3) is the playback rate: slow enough that a 2-core machine drops no frame.
set -euo pipefail
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
sequence="${1:-}"
output="$(mkdir -p "${2:-$repo/output/main}" && cd "${2:-$repo/output/main}" && pwd)"
rate="${RATE:-0.3}"

# shellcheck source=../scripts/workspace.sh
source "$repo/scripts/workspace.sh"

if [ -z "$sequence" ]; then
  sequence="$repo/output/default_sequence"
  if [ ! -f "$sequence/depth.txt" ]; then
    echo "generating the default synthetic sequence (desk motion, 300 frames, Kinect-like noise)"
    "$bin/sdf_tracker_synth" --output "$sequence" --motion desk --frames 300 --seed 1
  fi
fi

bag="$output/sequence.bag"
"$bin/tum_to_bag" "$sequence" "$bag" | tee "$output/tum_to_bag.log"
offset=$(grep -oE "shifted by [0-9.]+" "$output/tum_to_bag.log" | awk '{print $3}' || true)

echo "playing the bag through sdf_tracker_node (rate $rate) ..."
roslaunch sdf_tracker tum_bag.launch bag:="$bag" rate:="$rate" rviz:=false required:=true \
  trajectory_file:="$output/trajectory.txt" mesh_file:="$output/mesh.ply" cloud_file:="$output/cloud.ply" \
  > "$output/roslaunch.log" 2>&1 || { tail -n 30 "$output/roslaunch.log"; echo "roslaunch failed"; exit 1; }
frames=$(grep -cvE '^\s*(#|$)' "$sequence/depth.txt")
tracked=$(grep -cvE '^\s*(#|$)' "$output/trajectory.txt")
echo "the node processed $tracked of $frames frames ($((frames - tracked)) dropped)"
grep -aoE "per frame in the node: median [0-9.]+ ms, mean [0-9.]+ ms" "$output/roslaunch.log" | tail -n 1 \
  | sed 's/^/speed: /' || true
rm -f "$bag"  # large and reproducible

if [ -f "$sequence/groundtruth.txt" ]; then
  "$bin/sdf_tracker_evaluate" --groundtruth "$sequence/groundtruth.txt" --estimate "$output/trajectory.txt" \
    --estimate-time-offset "${offset:-0}" --plot "$output/trajectory.png" | tee "$output/accuracy.txt"
fi
echo "results in $output: trajectory.txt, mesh.ply, cloud.ply, trajectory.png, accuracy.txt, roslaunch.log"
