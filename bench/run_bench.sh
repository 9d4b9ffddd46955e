#!/usr/bin/env bash
# The benchmark: runs sdf_tracker_offline over sequences (7-Scenes redkitchen from
# SDF_TRACKER_DATA when present, and a synthetic suite generated here: desk, slow, fast, planar,
# loop), presets, thread counts and grid sizes, then writes a dated markdown + JSON report and
# plots under bench/results/.
#   bash bench/run_bench.sh            (about 15 minutes on 2 cores)
# Speed figures are medians of per-frame times measured inside the runner (tracking + fusion, and
# ray casting where listed); no test asserts any of them.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
bench_setup ""
mkdir -p "$work/runs"
require_matplotlib

sequences=()
for motion in desk slow fast planar loop; do
  sequences+=("$(synthetic_sequence "$bin" "$work" "$motion")")
done
redkitchen="$data/7scenes/redkitchen"
ablation_sequences=("$work/synthetic_desk")
if [ -f "$redkitchen/depth.txt" ]; then
  sequences+=("$redkitchen")
  ablation_sequences+=("$redkitchen")
else
  echo "SKIPPED: redkitchen not found at $redkitchen (set SDF_TRACKER_DATA)"
fi

run() {  # run NAME SEQUENCE [options...]
  local name="$1" sequence="$2"
  shift 2
  echo "  $name"
  "$bin/sdf_tracker_offline" --sequence "$sequence" --output "$work/runs/$name" --quiet "$@" > "$work/runs/$name.log" 2>&1 ||
    echo "    failed: see $work/runs/$name.log"
}

echo "presets x sequences (2 threads)"
for sequence in "${sequences[@]}"; do
  for preset in default paper reference; do
    run "preset_${preset}__$(basename "$sequence")" "$sequence" --preset "$preset" --threads 2
  done
done
echo "what each improvement of the default preset buys (each one switched off in turn)"
for sequence in "${ablation_sequences[@]}"; do
  base="$(basename "$sequence")"
  run "ablation_no_normalized_residuals__$base" "$sequence" --threads 2 --param NormalizeResiduals=false
  run "ablation_no_tracking_noise_weights__$base" "$sequence" --threads 2 --param TrackingSensorWeights=false
  run "ablation_constant_fusion_weights__$base" "$sequence" --threads 2 --param DepthWeighting=constant
  run "ablation_negative_band_0.04__$base" "$sequence" --threads 2 --param NegativeTruncationDistance=-0.04
done
if [ -f "$redkitchen/depth.txt" ]; then
  echo "threads, ray casting, dense grid sizes and compact voxels on redkitchen"
  run "threads_1" "$redkitchen" --threads 1
  run "raycast_default" "$redkitchen" --threads 2 --raycast
  # Grid sizes and compact voxels are the dense grid's (the default map is sparse).
  dense=(--param MapType=dense)
  for n in 128 200 256 320 400; do
    run "grid_${n}" "$redkitchen" --threads 2 "${dense[@]}" --param GridSizeX=$n --param GridSizeY=$n --param GridSizeZ=$n
  done
  run "reference_200_2cm" "$redkitchen" --threads 2 "${dense[@]}" --param GridSizeX=200 --param GridSizeY=200 \
    --param GridSizeZ=200
  run "compact_256" "$redkitchen" --threads 2 "${dense[@]}" --param CompactVoxels=true
  run "compact_512_1cm" "$redkitchen" --threads 2 "${dense[@]}" --param CompactVoxels=true --param CellSize=0.01 \
    --param GridSizeX=512 --param GridSizeY=512 --param GridSizeZ=512
fi

/usr/bin/python3 "$repo/bench/report/run_bench.py" "$work/runs" "$results"
