#!/usr/bin/env bash
# Issue 9's accuracy bench: where the error comes from and what each improvement buys, on every
# sequence at hand (TUM fr1_xyz and 7-Scenes redkitchen from SDF_TRACKER_DATA, the synthetic desk,
# loop and planar sequences generated here), all frames, 640x480, 2 threads:
#   - the default preset against the paper's and the reference's;
#   - an ablation: the default preset with one improvement switched off in turn;
#   - a sweep of CellSize (0.01 .. 0.03 m) and truncation (3 and 5 cells in front of a surface, 0.6
#     of that behind, as in the default band): the default preset should lose no frame anywhere in it;
#   - on fr1_xyz: the error against time and against a shift of the estimate's clock.
# Writes bench/results/<date>_accuracy.md with plots beside it.
#   bash bench/accuracy.sh [SEQUENCE_DIR ...]     (about 40 minutes on 2 cores)
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
bench_setup accuracy
mkdir -p "$work/runs"
require_matplotlib

real_sequences "$@"
if [ $# -eq 0 ]; then
  for motion in desk loop planar; do sequences+=("$(synthetic_sequence "$bin" "$repo/build/bench" "$motion")"); done
fi

run() {  # run NAME SEQUENCE [options...]: one offline run into $work/runs/NAME__<sequence>
  local name="$1" sequence="$2"
  shift 2
  local out
  out="$work/runs/${name}__$(basename "$sequence")"
  echo "  $name $(basename "$sequence")"
  "$bin/sdf_tracker_offline" --sequence "$sequence" --output "$out" --quiet --threads 2 "$@" > "$out.log" 2>&1 ||
    echo "    failed: see $out.log"
}

for sequence in "${sequences[@]}"; do
  echo "presets: $(basename "$sequence")"
  for preset in default paper reference; do run "preset_$preset" "$sequence" --preset "$preset"; done
  echo "ablation: the default preset with one improvement off"
  run "off_undistortion" "$sequence" --distortion 0,0,0,0,0
  run "off_motion_prediction" "$sequence" --param MotionPrediction=false
  run "off_constrained_directions" "$sequence" --param SolveConstrainedDirections=false
  run "off_tracking_noise_weights" "$sequence" --param TrackingSensorWeights=false
  run "off_normalized_residuals" "$sequence" --param NormalizeResiduals=false
  run "off_fusion_noise_weights" "$sequence" --param DepthWeighting=constant
  run "with_symmetric_band" "$sequence" --param NegativeTruncationDistance=-0.1
  echo "CellSize x truncation"
  for cell in 0.01 0.015 0.02 0.03; do
    for k in 3 5; do
      # k cells in front of the surface and 0.6 k behind: the default band's shape (0.1 m, -0.06 m).
      front=$(awk -v c="$cell" -v k="$k" 'BEGIN { printf "%.4f", c * k }')
      behind=$(awk -v c="$cell" -v k="$k" 'BEGIN { printf "%.4f", 0.6 * c * k }')
      run "sweep_cell${cell}_band${k}" "$sequence" --param CellSize="$cell" \
        --param PositiveTruncationDistance="$front" --param NegativeTruncationDistance="-$behind"
    done
  done
done

# fr1_xyz's error against time and against a shift of the estimate's clock (motion capture and
# depth are stamped by different clocks).
xyz="$work/runs/preset_default__tum_fr1_xyz"
if [ -f "$xyz/trajectory.txt" ]; then
  gt="$data/tum_fr1_xyz/groundtruth.txt"
  "$bin/sdf_tracker_evaluate" --groundtruth "$gt" --estimate "$xyz/trajectory.txt" --errors "$work/fr1_xyz_errors.csv" >/dev/null
  : > "$work/fr1_xyz_clock_shift.txt"
  for shift in -0.04 -0.03 -0.02 -0.01 0 0.005 0.01 0.015 0.02 0.025 0.03 0.04; do
    echo "$shift $("$bin/sdf_tracker_evaluate" --groundtruth "$gt" --estimate "$xyz/trajectory.txt" \
      --estimate-time-offset "$shift" | awk '/ATE/ { print $3 }')" >> "$work/fr1_xyz_clock_shift.txt"
  done
fi

/usr/bin/python3 "$repo/bench/report/accuracy.py" "$work" "$results"
