#!/usr/bin/env bash
# The live-camera path without a camera: each sequence is converted with tum_to_fakenect and
# tum_to_oni and replayed with the README's commands
#   roslaunch sdf_tracker kinect.launch fakenect:=... rviz:=false trajectory_file:=...
#   roslaunch sdf_tracker openni2.launch device:=... rviz:=false trajectory_file:=...
# through libfreenect's fakenect and OpenNI 2's OniFile at the recorded rate. For each it prints
# frames tracked, ATE against the ground truth and against the offline runner on the same frames.
#   bash bench/camera_replay.sh [SEQUENCE_DIR ...]   (default: fr1_xyz and redkitchen from SDF_TRACKER_DATA)
# Writes bench/results/<date>_cameras.md. No test asserts these figures.
set -euo pipefail
# shellcheck source=common.sh
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
bench_setup cameras
report="$results/$(date +%Y-%m-%d)_cameras.md"

real_sequences "$@"

# "ATE RMSE x m" of an estimate against a reference trajectory; the converters shift stamps that
# start below 1 s by 1 s.
ate() {
  "$bin/sdf_tracker_evaluate" --groundtruth "$1" --estimate "$2" --estimate-time-offset "$3" | awk '/^ATE/ {print $3 * 100}'
}
poses() { grep -vc '^#' "$1"; }

{
  echo "# Live-camera launch files replaying recordings ($(date +%Y-%m-%d))"
  echo
  echo "\`bash bench/camera_replay.sh\` on $(nproc) cores: each sequence converted with tum_to_fakenect and"
  echo "tum_to_oni, replayed at the recorded rate with \`kinect.launch fakenect:=\` and \`openni2.launch device:=\`"
  echo "(rviz off). ATE in cm after rigid alignment; the last column compares with the offline runner's trajectory."
  echo
  echo "| sequence | run | frames with a pose | ATE (cm) | difference from offline (cm) |"
  echo "|---|---|---|---|---|"
} > "$report"

for sequence in "${sequences[@]}"; do
  name="$(basename "$sequence")"
  out="$work/$name"
  rm -rf "$out"
  mkdir -p "$out"
  frames="$(grep -vc '^#' "$sequence/depth.txt")"
  offset="$(awk '!/^#/ {print ($1 < 1.0) ? 1 : 0; exit}' "$sequence/depth.txt")"
  "$bin/sdf_tracker_offline" --sequence "$sequence" --output "$out/offline" --quiet > "$out/offline.log"
  echo "| $name | offline runner | $(poses "$out/offline/trajectory.txt")/$frames | $(ate "$sequence/groundtruth.txt" "$out/offline/trajectory.txt" 0) | - |" >> "$report"

  "$bin/tum_to_fakenect" "$sequence" "$out/recording.dump" > /dev/null
  (cd "$out" && roslaunch sdf_tracker kinect.launch fakenect:=recording.dump rviz:=false trajectory_file:=kinect.txt > kinect.log 2>&1)
  "$bin/tum_to_oni" "$sequence" "$out/recording.oni" > /dev/null
  (cd "$out" && roslaunch sdf_tracker openni2.launch device:=recording.oni rviz:=false trajectory_file:=openni2.txt > openni2.log 2>&1)
  rm -rf "$out/recording.dump" "$out/recording.oni"  # 0.4-0.6 GB each for a VGA sequence
  for run in kinect openni2; do
    label="$([ "$run" = kinect ] && echo "kinect.launch (fakenect)" || echo "openni2.launch (OniFile)")"
    echo "| $name | $label | $(poses "$out/$run.txt")/$frames | $(ate "$sequence/groundtruth.txt" "$out/$run.txt" "$offset") | $(ate "$out/offline/trajectory.txt" "$out/$run.txt" "$offset") |" >> "$report"
  done
done
cat "$report"
echo "report: $report"
