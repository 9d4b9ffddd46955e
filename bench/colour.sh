#!/usr/bin/env bash
# Issue 45's bench: colour in the map, each sequence run with Colour on and off, interleaved
# (ROUNDS times, default 3), default preset, 640x480, 2 threads. Sequences: the real ones in
# SDF_TRACKER_DATA that have colour (rgb.txt), and a synthetic desk sequence with registered colour
# (sdf_tracker_synth --colour).
#   same trajectory   trajectory.txt byte for byte equal with colour on and off (every round)
#   fusion ms         median per frame, each round's on / off, and the median ratio
#   tracking ms       median per frame, on / off
#   map MiB           the map's memory at the end, on / off (4 bytes a voxel more with colour)
#   colour agreement  mesh.ply's vertex colours against the colour images (sdf_tracker_evaluate
#                     --mesh, every 10th frame, at the estimated poses): mean difference per
#                     channel, mean and median RGB distance, in levels of 255
# Writes bench/results/<date>_colour.md.
#   bash bench/colour.sh      (about 5 minutes on 2 cores)
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
bench_setup colour
report="$results/$(date +%Y-%m-%d)_colour.md"
rounds="${ROUNDS:-3}"
py=/usr/bin/python3

synthetic="$work/synthetic_desk_colour"
[ -f "$synthetic/rgb.txt" ] || "$bin/sdf_tracker_synth" --output "$synthetic" --motion desk --frames 300 --seed 21 --colour >/dev/null
cases=()
real_sequences
for s in "${sequences[@]}"; do
  if [ -f "$s/rgb.txt" ]; then cases+=("$s"); else echo "SKIPPED: $s has no rgb.txt (no colour to fuse)"; fi
done
cases+=("$synthetic")

json() { "$py" -c "import json,sys; d=json.load(open(sys.argv[1])); print(eval(sys.argv[2]))" "$@"; }

{
  echo "# Colour in the map ($(date +%Y-%m-%d), $(git -C "$repo" rev-parse --short HEAD))"
  echo
  echo "bench/colour.sh: default preset, 640x480, $(nproc) cores, 2 threads; Colour on and off"
  echo "interleaved, $rounds rounds. ms: medians per frame (runner's clock); fusion includes"
  echo "undistorting the colour image."
  echo
  echo "| sequence | same trajectory | fusion ms on / off (each round) | fusion ratio (median) | tracking ms on / off | map MiB on / off | colour agreement: channel, mean, median |"
  echo "|---|---|---|---|---|---|---|"
} > "$report"

for s in "${cases[@]}"; do
  name="$(basename "$s")"
  fusion_pairs=() ratios=() same=yes
  for round in $(seq "$rounds"); do
    for colour in true false; do
      "$bin/sdf_tracker_offline" --sequence "$s" --output "$work/$name.$colour" --threads 2 --quiet \
        --param Colour=$colour >/dev/null
    done
    cmp -s "$work/$name.true/trajectory.txt" "$work/$name.false/trajectory.txt" || same=no
    on=$(json "$work/$name.true/summary.json" "d['ms']['fusion_median']")
    off=$(json "$work/$name.false/summary.json" "d['ms']['fusion_median']")
    fusion_pairs+=("$(printf '%.2f / %.2f' "$on" "$off")")
    ratios+=("$("$py" -c "print($on / $off)")")
  done
  ratio=$(printf '%s\n' "${ratios[@]}" | sort -g | awk '{ a[NR] = $1 } END { printf "%.2f", a[int((NR + 1) / 2)] }')
  track=$(printf '%.2f / %.2f' "$(json "$work/$name.true/summary.json" "d['ms']['tracking_median']")" \
    "$(json "$work/$name.false/summary.json" "d['ms']['tracking_median']")")
  memory=$(printf '%.1f / %.1f' "$(json "$work/$name.true/summary.json" "d['grid_mb']")" \
    "$(json "$work/$name.false/summary.json" "d['grid_mb']")")
  agreement=$("$bin/sdf_tracker_evaluate" --mesh "$work/$name.true/mesh.ply" --sequence "$s" \
    --estimate "$work/$name.true/trajectory.txt" |
    sed -E 's/.*per channel ([0-9.]+) levels.*mean ([0-9.]+), median ([0-9.]+).*/\1, \2, \3/')
  echo "| $name | $same | $(IFS=';'; echo "${fusion_pairs[*]}" | sed 's/;/; /g') | $ratio | $track | $memory | $agreement |" >> "$report"
  echo "$name done"
done
{
  echo
  echo "Bytes per voxel: 8 (distance, weight) without colour, 12 with (VoxelColour: red, green, blue, weight);"
  echo "a sparse block of 8^3 voxels takes 4160 bytes without and 6208 with; a map fused without any"
  echo "colour image holds none (Colour on costs nothing then)."
} >> "$report"
echo "wrote $report"
