#!/usr/bin/env bash
# Issue 30's bench: a robot's wheel odometry as the tracker's prediction. Synthetic sequences a robot
# drives, each with the drifting wheel odometry sdf_tracker_synth --odometry writes (every metre 2 %
# too long, the heading drifting 1 degree per metre, noise), tracked with the default preset (VGA,
# Kinect-like noise, all cores):
#   with wheels     the odometry as the prediction (sdf_tracker_offline --odometry);
#   tracker alone   without it (constant velocity; a degenerate view keeps the last pose along the
#                   directions it does not constrain);
# against the wheel odometry alone and a camera standing still (its first pose throughout). ATE is
# the RMSE after rigid alignment, as sdf_tracker_evaluate gives it. Then the covariance's
# calibration: --fuse-ground-truth tracks every frame from its true pose against a map fused at true
# poses, and counts the frames whose position error lies within the two-sigma ellipsoid of the
# covariance stated for them (95 % when it is calibrated).
# Writes bench/results/<date>_odometry_prior.md.
#   bash bench/odometry_prior.sh     (about 10 minutes on 2 cores)
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
bench_setup odometry_prior
report="$results/$(date +%Y-%m-%d)_odometry_prior.md"

# name | sdf_tracker_synth options
cases=("single wall|--motion planar --frames 300"
  "single wall, exact depth|--motion planar --frames 300 --no-noise"
  "corridor, bare walls|--motion corridor --bare-walls --frames 900"
  "house walk, bare walls|--motion walk --bare-walls --frames 900"
  "house walk, furnished|--motion walk --frames 900")

ate_of() {  # GROUNDTRUTH ESTIMATE: the ATE RMSE in metres
  "$bin/sdf_tracker_evaluate" --groundtruth "$1" --estimate "$2" | awk '$1 == "ATE" { print $3 }'
}
cm() { awk -v m="$1" 'BEGIN { printf "%.2f", 100 * m }'; }

{
  echo "# Wheel odometry as the prediction ($(date +%Y-%m-%d), $(git -C "$repo" rev-parse --short HEAD))"
  echo
  echo "bench/odometry_prior.sh: default preset, 640x480 with Kinect-like noise unless said, seed 21;"
  echo "the wheel odometry errs 2 % per metre in distance and 1 degree per metre in heading, with noise."
  echo
  echo "| sequence | with wheels | tracker alone | wheels alone | standing still | frames lost (with / alone) | degenerate (with / alone) |"
  echo "|---|---|---|---|---|---|---|"
} > "$report"
calibration=()
for entry in "${cases[@]}"; do
  name="${entry%%|*}"
  options="${entry#*|}"
  dir="$work/$(echo "$name" | tr -c 'a-z0-9\n' '_')"
  # shellcheck disable=SC2086
  [ -f "$dir/odometry.txt" ] || "$bin/sdf_tracker_synth" --output "$dir" $options --seed 21 --odometry >/dev/null
  echo "$name ..."
  "$bin/sdf_tracker_offline" --sequence "$dir" --output "$dir/with" --odometry "$dir/odometry.txt" --quiet >/dev/null
  "$bin/sdf_tracker_offline" --sequence "$dir" --output "$dir/alone" --quiet >/dev/null
  "$bin/sdf_tracker_offline" --sequence "$dir" --output "$dir/single" --fuse-ground-truth --quiet >/dev/null
  awk '!/^#/ && NF >= 8 { if (!p) p = $2 " " $3 " " $4 " " $5 " " $6 " " $7 " " $8; print $1, p }' \
    "$dir/groundtruth.txt" > "$dir/standing_still.txt"
  gt="$dir/groundtruth.txt"
  lost() { grep -oE "failed [0-9]+" "$1/summary.txt" | awk '{ print $2 }'; }
  degenerate() { grep -oE "degenerate [0-9]+" "$1/summary.txt" | awk '{ print $2 }' || echo 0; }
  echo "| $name | $(cm "$(ate_of "$gt" "$dir/with/trajectory.txt")") | $(cm "$(ate_of "$gt" "$dir/alone/trajectory.txt")") |" \
    "$(cm "$(ate_of "$gt" "$dir/odometry.txt")") | $(cm "$(ate_of "$gt" "$dir/standing_still.txt")") |" \
    "$(lost "$dir/with") / $(lost "$dir/alone") | $(degenerate "$dir/with") / $(degenerate "$dir/alone") |" >> "$report"
  mean_mm=$(grep -oE "per frame \(mm\) mean [0-9.e+-]+" "$dir/single/summary.txt" | awk '{ print $5 }')
  within=$(grep -oE "2 sigma: [0-9]+ %" "$dir/single/summary.txt" | awk '{ print $3 }')
  calibration+=("| $name | $mean_mm | $within % |")
done
{
  echo
  echo "ATE in cm. The covariance's calibration (--fuse-ground-truth: each frame tracked from its true pose"
  echo "against a map fused at true poses; share of frames whose position error lies within the two-sigma"
  echo "ellipsoid of the covariance stated for it, 95 % if it is calibrated):"
  echo
  echo "| sequence | mean error per frame (mm) | within 2 sigma |"
  echo "|---|---|---|"
  printf '%s\n' "${calibration[@]}"
  echo
} >> "$report"
cat "$report"
