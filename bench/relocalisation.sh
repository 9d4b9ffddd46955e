#!/usr/bin/env bash
# Issue 29's relocalisation bench. Each sequence is cut into a first part and a later part (the
# frames between removed), and tracked two ways with the default preset:
#   two sessions: the first part is mapped (--save-map), then the later part is run in that map
#                 (--load-volume), starting with no idea where it is;
#   kidnap:       one run over the first part and then the later part, as if the camera had been
#                 carried with its view blocked.
# The later part's poses are compared with the truth in the map's frame (the ground truth aligned
# by the first part's trajectory: sdf_tracker_evaluate --map-frame-from): the share within 5 cm and
# 5 degrees, the frames until the camera is found, ms per searching frame, false acceptances
# (the search accepted a pose more than 10 cm or 10 degrees from the truth), and frames fused more
# than 10 cm from the truth (by whatever way their pose was reached). A synthetic walk
# through the house that never comes back is cut the same way: any acceptance there is false.
# Tracking frame time with relocalisation on and off is measured on the whole sequences.
# Writes bench/results/<date>_relocalisation.md.
#   bash bench/relocalisation.sh     (about 10 minutes on 2 cores)
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
bench_setup relocalisation
report="$results/$(date +%Y-%m-%d)_relocalisation.md"

# name | folder | first part [0, A) | later part [B, end)
cases=()
[ -f "$data/7scenes/redkitchen/depth.txt" ] && cases+=("redkitchen|$data/7scenes/redkitchen|400|620") ||
  echo "SKIPPED: $data/7scenes/redkitchen not found"
[ -f "$data/tum_fr1_xyz/depth.txt" ] && cases+=("fr1_xyz|$data/tum_fr1_xyz|300|500") ||
  echo "SKIPPED: $data/tum_fr1_xyz not found"
walk="$work/walk_never_back"
[ -f "$walk/depth.txt" ] || "$bin/sdf_tracker_synth" --output "$walk" --motion walk --frames 900 --seed 7 >/dev/null
cases+=("house walk, never back|$walk|300|600")

# cut SOURCE DEST FIRST:LAST...: a TUM folder with only the frames listed (0-based, inclusive ranges)
cut_sequence() {
  local source="$1" dest="$2"
  shift 2
  mkdir -p "$dest"
  ln -sfn "$source/depth" "$dest/depth"
  for f in groundtruth.txt intrinsics.txt; do [ -f "$source/$f" ] && cp "$source/$f" "$dest/$f"; done
  grep -v '^#' "$source/depth.txt" | awk -v ranges="$*" '
    BEGIN { n = split(ranges, r, " "); for (i = 1; i <= n; i++) { split(r[i], ab, ":"); lo[i] = ab[1]; hi[i] = ab[2] } }
    { for (i = 1; i <= n; i++) if (NR - 1 >= lo[i] && NR - 1 <= hi[i]) { print; break } }' > "$dest/depth.txt"
}
# frames_until_found CSV: tracked frames before the first tracked one of the later part (frames.csv rows)
offline() { "$bin/sdf_tracker_offline" --quiet --threads 2 "$@"; }
json() { /usr/bin/python3 -c "import json,sys; d=json.load(open(sys.argv[1])); print(eval(sys.argv[2]))" "$@"; }

{
  echo "# Relocalisation bench ($(date +%Y-%m-%d))"
  echo
  echo "Default preset, 640x480, 2 threads; \`bash bench/relocalisation.sh\`. Later-part frames within 5 cm and"
  echo "5 degrees of the truth in the map's frame (the ground truth aligned by the first part's trajectory),"
  echo "frames the search took until the camera was found, CPU ms per searching frame (median / max), and"
  echo "accepted candidates more than 10 cm or 10 degrees from the truth, and later-part frames fused at a pose"
  echo "more than 10 cm from the truth (whether accepted by the search or tracked from the held pose)."
  echo
  echo "| sequence | protocol | first / later part | within 5 cm, 5 deg | frames until found | ms per search frame | false acceptances | fused > 10 cm off |"
  echo "|---|---|---|---|---|---|---|---|"
} > "$report.table"

for entry in "${cases[@]}"; do
  IFS='|' read -r name folder first later <<< "$entry"
  total=$(grep -vc '^#' "$folder/depth.txt")
  tag=$(echo "$name" | tr -c 'a-z0-9_\n' '_')
  dir="$work/$tag"
  cut_sequence "$folder" "$dir/part1" "0:$((first - 1))"
  cut_sequence "$folder" "$dir/part2" "$later:$((total - 1))"
  cut_sequence "$folder" "$dir/kidnap" "0:$((first - 1))" "$later:$((total - 1))"
  echo "$name: mapping frames 0-$((first - 1)), then frames $later-$((total - 1))"
  offline --sequence "$dir/part1" --output "$dir/out_part1" --save-map > "$dir/part1.log" 2>&1
  offline --sequence "$dir/part2" --output "$dir/out_session2" --load-volume "$dir/out_part1/map.sdfmap" \
    > "$dir/session2.log" 2>&1 || true
  offline --sequence "$dir/kidnap" --output "$dir/out_kidnap" > "$dir/kidnap.log" 2>&1 || true
  # The kidnap run's later part, and its first part as the map's frame.
  split_at=$(awk -v n="$first" 'NR == n + 1 { print $1 }' <(grep -v '^#' "$dir/kidnap/depth.txt"))
  awk -v t="$split_at" '/^#/ || $1 < t' "$dir/out_kidnap/trajectory.txt" > "$dir/kidnap_part1.txt"
  awk -v t="$split_at" '/^#/ || $1 >= t' "$dir/out_kidnap/trajectory.txt" > "$dir/kidnap_part2.txt"
  for protocol in session2 kidnap; do
    if [ "$protocol" = session2 ]; then
      estimate="$dir/out_session2/trajectory.txt"; reference="$dir/out_part1/trajectory.txt"
      frames_csv="$dir/out_session2/frames.csv"; summary="$dir/out_session2/summary.json"; label="two sessions"
    else
      estimate="$dir/kidnap_part2.txt"; reference="$dir/kidnap_part1.txt"
      frames_csv="$dir/out_kidnap/frames.csv"; summary="$dir/out_kidnap/summary.json"; label="kidnap"
    fi
    "$bin/sdf_tracker_evaluate" --groundtruth "$folder/groundtruth.txt" --estimate "$estimate" \
      --map-frame-from "$reference" --errors "$dir/${protocol}_errors.csv" > "$dir/${protocol}_eval.txt"
    within=$(sed -n 's/.*: \([0-9]* of [0-9]* poses\) within .*(\(.*\)).*/\1 (\2)/p' "$dir/${protocol}_eval.txt")
    # Frames of the later part until the first one tracked; accepted poses more than 10 cm / 10 deg off;
    # frames fused more than 10 cm off.
    read -r until_found false_accepts fused_far <<< "$(/usr/bin/python3 - "$frames_csv" "$dir/${protocol}_errors.csv" "$split_at" "$protocol" <<'PY'
import csv, sys
frames, errors, split_at, protocol = sys.argv[1], sys.argv[2], float(sys.argv[3]), sys.argv[4]
rows = [r for r in csv.DictReader(open(frames)) if protocol == "session2" or float(r["timestamp"]) >= split_at - 1e-9]
err = {round(float(r["timestamp"]), 4): (float(r["error_m"]), float(r["error_deg"])) for r in csv.DictReader(open(errors))}
found = next((i for i, r in enumerate(rows) if r["status"] in ("ok", "degenerate")), None)
false = fused_far = 0
previous = None
for r in rows:
    e = err.get(round(float(r["timestamp"]), 4))
    # An acceptance: a tracked frame right after one that searched.
    if previous in ("relocalising", "ambiguous") and r["status"] in ("ok", "degenerate"):
        if e and (e[0] > 0.10 or e[1] > 10.0): false += 1
    if r["fused"] == "1" and e and e[0] > 0.10: fused_far += 1
    previous = r["status"]
print("never" if found is None else found, false, fused_far)
PY
)"
    ms=$(json "$summary" '"%.0f / %.0f" % (d["relocalisation"]["ms_median"], d["relocalisation"]["ms_max"])')
    echo "| $name | $label | $first / $((total - later)) | $within | $until_found | $ms | $false_accepts | $fused_far |" >> "$report.table"
  done
done

# Frame time with the search on and off on the whole sequences (it runs only when lost: this is
# the place memory's cost while tracking works).
{
  echo
  echo "Tracking frame time on the whole sequences (median ms per frame, same run):"
  echo
  echo "| sequence | Relocalise=true | Relocalise=false | keyframes | bytes per keyframe |"
  echo "|---|---|---|---|---|"
} >> "$report.table"
for entry in "${cases[@]}"; do
  IFS='|' read -r name folder _ _ <<< "$entry"
  case "$name" in house*) continue ;; esac
  tag=$(echo "$name" | tr -c 'a-z0-9_\n' '_')
  offline --sequence "$folder" --output "$work/$tag/whole_on" > /dev/null 2>&1
  offline --sequence "$folder" --output "$work/$tag/whole_off" --param Relocalise=false > /dev/null 2>&1
  on=$(json "$work/$tag/whole_on/summary.json" '"%.2f" % d["ms"]["frame_median"]')
  off=$(json "$work/$tag/whole_off/summary.json" '"%.2f" % d["ms"]["frame_median"]')
  keyframes=$(json "$work/$tag/whole_on/summary.json" 'd["relocalisation"]["keyframes"]')
  bytes=$(sed -n 's/^place memory: .* keyframes, \([0-9]*\) bytes each.*/\1/p' "$work/$tag/whole_on/summary.txt")
  echo "| $name | $on | $off | $keyframes | $bytes |" >> "$report.table"
done
mv "$report.table" "$report"
cat "$report"
echo "wrote $report"
