#!/usr/bin/env bash
# The relocalisation bench (issues 29 and 42), default preset, 640x480, 2 threads.
#
# Cases. Each real sequence is cut into a first part and a later part (the frames between
# removed), and tracked two ways:
#   two sessions: the first part is mapped (--save-map), then the later part is run in that map
#                 (--load-volume), starting with no idea where it is;
#   kidnap:       one run over the first part and then the later part, as if the camera had been
#                 carried with its view blocked.
# A synthetic walk through the house that never comes back is cut the same way: any acceptance
# there is false. The synthetic relocalisation cases (sdf_tracker_synth --relocalisation-case:
# a half-new first view, two identical rooms, a room a half turn maps onto itself, two identical
# desks) are two sessions, the first mapped at its true poses; in the ambiguous ones (two rooms,
# the symmetric room) any acceptance is false.
#
# Per case: the later part's poses against the truth in the map's frame (the ground truth aligned
# by the first part's trajectory: sdf_tracker_evaluate --map-frame-from), the share within 5 cm and
# 5 degrees, the frames until the camera is found, ms per searching frame, false acceptances (an
# accepted pose more than 10 cm or 10 degrees from the truth, or any in an ambiguous case), and
# frames fused more than 10 cm from the truth.
#
#   bash bench/relocalisation.sh          every case at the defaults, and the tracking frame time
#                                         with the search on and off (about 12 minutes on 2 cores):
#                                         bench/results/<date>_relocalisation.md
#   bash bench/relocalisation.sh --sweep  the two sessions of every case at each value of
#                                         RelocaliseMaxContradiction and of RelocaliseMinOverlap
#                                         (the other at its default; about 20 minutes):
#                                         bench/results/<date>_relocalisation_sweep.md
#   bash bench/relocalisation.sh --node   the two sessions of the real sequences through the node,
#                                         as a user runs them: each part made a bag (tum_to_bag, fr1 as
#                                         TUM's 2011 bags), the first played with tum_bag.launch and
#                                         its map saved with ~save_volume, the second played PLAYS
#                                         times (default 3) with map_file:= (about 4 minutes):
#                                         bench/results/<date>_relocalisation_node.md
#
# The truth of redkitchen is the uncut run (the whole sequence tracked in one go): its KinectFusion
# ground truth differs from the first part's own map by up to 8.5 cm, which is the map's error and
# not the search's. Its share against the ground truth is given beside it.
set -euo pipefail
mode="${1:-defaults}"
case "$mode" in defaults|--sweep|--node) ;; *) echo "usage: bash bench/relocalisation.sh [--sweep|--node]" >&2; exit 2 ;; esac
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
bench_setup relocalisation

# name | kind | folder | first part [0, A) | later part [B, end) | truth (groundtruth or uncut)
# (synthetic cases: their two folders, and the truth they were rendered at)
cases=()
[ -f "$data/7scenes/redkitchen/depth.txt" ] && cases+=("redkitchen|real|$data/7scenes/redkitchen|400|620|uncut") ||
  echo "SKIPPED: $data/7scenes/redkitchen not found"
[ -f "$data/tum_fr1_xyz/depth.txt" ] && cases+=("fr1_xyz|real|$data/tum_fr1_xyz|300|500|groundtruth") ||
  echo "SKIPPED: $data/tum_fr1_xyz not found"
walk="$work/walk_never_back"
[ -f "$walk/depth.txt" ] || "$bin/sdf_tracker_synth" --output "$walk" --motion walk --frames 900 --seed 7 >/dev/null
cases+=("house walk, never back|never_back|$walk|300|600|groundtruth")
for name in half-new two-rooms symmetric-room two-desks; do
  dir="$work/case_$name"
  rm -rf "$dir"  # written anew: they are the code's, and change with it
  "$bin/sdf_tracker_synth" --output "$dir" --relocalisation-case "$name" --seed 5 >/dev/null
  cases+=("$name|$(grep -q '^ambiguous' "$dir/case.txt" && echo ambiguous || echo synthetic)|$dir|||groundtruth")
done

# cut SOURCE DEST FIRST:LAST...: a TUM folder with only the frames listed (0-based, inclusive ranges)
cut_sequence() {
  local source="$1" dest="$2"
  shift 2
  mkdir -p "$dest"
  ln -sfn "$source/depth" "$dest/depth"
  for f in groundtruth.txt intrinsics.txt accelerometer.txt; do [ -f "$source/$f" ] && cp "$source/$f" "$dest/$f"; done
  grep -v '^#' "$source/depth.txt" | awk -v ranges="$*" '
    BEGIN { n = split(ranges, r, " "); for (i = 1; i <= n; i++) { split(r[i], ab, ":"); lo[i] = ab[1]; hi[i] = ab[2] } }
    { for (i = 1; i <= n; i++) if (NR - 1 >= lo[i] && NR - 1 <= hi[i]) { print; break } }' > "$dest/depth.txt"
}
offline() { "$bin/sdf_tracker_offline" --quiet --threads 2 "$@"; }
# publish PART REPORT: the finished report put in place (a run stopped half-way leaves only PART).
publish() { mv "$1" "$2"; cat "$2"; echo "wrote $2"; }
json() { /usr/bin/python3 -c "import json,sys; d=json.load(open(sys.argv[1])); print(eval(sys.argv[2]))" "$@"; }
frames_in() { grep -vc '^#' "$1/depth.txt"; }

# prepare ENTRY: sets tag, dir (the case's work folder), part1, part2, truth, ground_truth (the
# sequence's own, when truth is the uncut run) and, for the real sequences and the walk, kidnap
# and split_at (the later part's first stamp); maps the first part (dir/out_part1/map.sdfmap), and
# tracks the uncut sequence where it is the truth, once a run of this script.
declare -A mapped=()
prepare() {
  local truth_kind
  IFS='|' read -r name kind folder first later truth_kind <<< "$1"
  tag=$(echo "$name" | tr -c 'a-z0-9_\n' '_')
  dir="$work/$tag"
  mkdir -p "$dir"
  if [ "$kind" = real ] || [ "$kind" = never_back ]; then
    local total
    total=$(frames_in "$folder")
    part1="$dir/part1"; part2="$dir/part2"; kidnap="$dir/kidnap"; ground_truth="$folder/groundtruth.txt"
    truth="$ground_truth"
    if [ "$truth_kind" = uncut ]; then
      truth="$dir/out_uncut/trajectory.txt"
      [ -n "${mapped[$tag]:-}" ] || offline --sequence "$folder" --output "$dir/out_uncut" > "$dir/uncut.log" 2>&1
    fi
    cut_sequence "$folder" "$part1" "0:$((first - 1))"
    cut_sequence "$folder" "$part2" "$later:$((total - 1))"
    cut_sequence "$folder" "$kidnap" "0:$((first - 1))" "$later:$((total - 1))"
    split_at=$(awk -v n="$first" 'NR == n + 1 { print $1 }' <(grep -v '^#' "$kidnap/depth.txt"))
    [ -n "${mapped[$tag]:-}" ] || offline --sequence "$part1" --output "$dir/out_part1" --save-map > "$dir/part1.log" 2>&1
  else
    part1="$folder/mapping"; part2="$folder/session"; kidnap=""; truth="$folder/session/groundtruth.txt"
    ground_truth="$truth"
    [ -n "${mapped[$tag]:-}" ] ||
      offline --sequence "$part1" --output "$dir/out_part1" --save-map --fuse-ground-truth > "$dir/part1.log" 2>&1
  fi
  mapped[$tag]=1
  first_frames=$(frames_in "$part1"); later_frames=$(frames_in "$part2")
}

# measure KIND TRUTH ESTIMATE REFERENCE FRAMES_CSV SUMMARY FROM_STAMP LABEL: evaluates one run and
# prints "within|frames until found|ms median / max|false acceptances|fused > 10 cm off".
measure() {
  local kind="$1" truth="$2" estimate="$3" reference="$4" frames_csv="$5" summary="$6" from="$7" label="$8"
  "$bin/sdf_tracker_evaluate" --groundtruth "$truth" --estimate "$estimate" --map-frame-from "$reference" \
    --errors "$label.errors.csv" > "$label.eval.txt"
  local within rest ms
  within=$(sed -n 's/.*: \([0-9]* of [0-9]* poses\) within .*(\(.*\)).*/\1 (\2)/p' "$label.eval.txt")
  [ -n "$within" ] || within="0 of 0 poses"
  [ "$kind" = ambiguous ] && within="- (${within%% *} accepted)"
  rest=$(/usr/bin/python3 - "$frames_csv" "$label.errors.csv" "$from" "$kind" <<'PY'
import csv, sys
frames, errors, start, kind = sys.argv[1], sys.argv[2], float(sys.argv[3]), sys.argv[4]
rows = [r for r in csv.DictReader(open(frames)) if float(r["timestamp"]) >= start - 1e-9]
err = {round(float(r["timestamp"]), 4): (float(r["error_m"]), float(r["error_deg"])) for r in csv.DictReader(open(errors))}
found = next((i for i, r in enumerate(rows) if r["status"] in ("ok", "degenerate")), None)
false = fused_far = 0
previous = None
for r in rows:
    e = err.get(round(float(r["timestamp"]), 4))
    # An acceptance: a tracked frame right after one that searched.
    if previous in ("relocalising", "ambiguous") and r["status"] in ("ok", "degenerate"):
        if kind in ("ambiguous", "never_back") or (e and (e[0] > 0.10 or e[1] > 10.0)): false += 1
    if r["fused"] == "1" and (kind == "ambiguous" or (e and e[0] > 0.10)): fused_far += 1
    previous = r["status"]
print(f"{'never' if found is None else found}|{false}|{fused_far}")
PY
)
  ms=$(json "$summary" '"%.0f / %.0f" % (d["relocalisation"]["ms_median"], d["relocalisation"]["ms_max"])')
  IFS='|' read -r until_found false_accepts fused_far <<< "$rest"
  echo "$within|$until_found|$ms|$false_accepts|$fused_far"
}

# second_session OUT [--param ...]: the later part in the first part's map; prints measure's line.
second_session() {
  local out="$1"
  shift
  offline --sequence "$part2" --output "$out" --load-volume "$dir/out_part1/map.sdfmap" "$@" > "$out.log" 2>&1 || true
  measure "$kind" "$truth" "$out/trajectory.txt" "$dir/out_part1/trajectory.txt" "$out/frames.csv" \
    "$out/summary.json" 0 "$out"
}

# unshift OFFSET IN OUT: a trajectory with OFFSET seconds taken off its stamps.
unshift() { awk -v d="$1" '/^#/ { print; next } NF { $1 = sprintf("%.6f", $1 - d); print }' "$2" > "$3"; }

# node_share TRUTH ESTIMATE REFERENCE LATER_PART LABEL OFFSET: a node run's later part, evaluated
# as measure does but from the trajectory alone (the node writes only the poses it published), its
# and the reference's stamps first put back on the sequence's clock (tum_to_bag's shift OFFSET):
# prints "within, of the later frames|frames until found|poses more than 10 cm or 10 degrees off".
node_share() {
  local truth="$1" later="$4" label="$5" offset="$6"
  local estimate="$label.unshifted.txt" reference="$label.reference.unshifted.txt"
  [ -f "$2" ] && unshift "$offset" "$2" "$estimate"
  unshift "$offset" "$3" "$reference"
  "$bin/sdf_tracker_evaluate" --groundtruth "$truth" --estimate "$estimate" --map-frame-from "$reference" \
    --errors "$label.errors.csv" > "$label.eval.txt" 2>&1 || true
  /usr/bin/python3 - "$later/depth.txt" "$estimate" "$label.errors.csv" <<'PY'
import csv, os, sys
depth, estimate, errors = sys.argv[1:4]
stamps = [float(l.split()[0]) for l in open(depth) if l.strip() and not l.startswith("#")]
poses = [float(l.split()[0]) for l in open(estimate) if l.strip() and not l.startswith("#")] if os.path.exists(estimate) else []
rows = list(csv.DictReader(open(errors))) if os.path.exists(errors) else []
within = sum(1 for r in rows if float(r["error_m"]) <= 0.05 and float(r["error_deg"]) <= 5.0)
far = sum(1 for r in rows if float(r["error_m"]) > 0.10 or float(r["error_deg"]) > 10.0)
found = next((i for i, t in enumerate(stamps) if poses and abs(t - poses[0]) < 0.02), None)
print(f"{within} of {len(stamps)} frames ({100.0 * within / len(stamps):.1f} %), {len(poses)} with a pose"
      f"|{'never' if found is None else found}|{far}")
PY
}

# node_play BAG OUT [ARG:=VALUE ...]: plays BAG through tum_bag.launch as the README says (no rviz),
# writing OUT/trajectory.txt; with save:=FILE the map is saved with ~save_volume once playback has
# ended and before the node is stopped, as a user does.
node_play() {
  local bag="$1" out="$2" save="" a
  shift 2
  local args=()
  for a in "$@"; do case "$a" in save:=*) save="${a#save:=}" ;; *) args+=("$a") ;; esac; done
  mkdir -p "$out"
  local launch=(roslaunch sdf_tracker tum_bag.launch bag:="$bag" rviz:=false trajectory_file:="$out/trajectory.txt")
  if [ -z "$save" ]; then
    "${launch[@]}" "${args[@]}" > "$out/roslaunch.log" 2>&1 || true
    return
  fi
  "${launch[@]}" required:=false "${args[@]}" > "$out/roslaunch.log" 2>&1 &
  local pid=$!
  sleep 8
  while rosnode list 2>/dev/null | grep -q '^/player$'; do sleep 1; done
  sleep 3  # the frames still queued in the tracker
  rosservice call /sdf_tracker/save_volume "{path: '$save'}" > "$out/save_volume.log" 2>&1 || true
  kill -INT "$pid" 2>/dev/null || true
  wait "$pid" 2>/dev/null || true
}

if [ "$mode" = --node ]; then
  plays="${PLAYS:-3}"
  report="$results/$(date +%Y-%m-%d)_relocalisation_node.md"
  roscore > "$work/roscore.log" 2>&1 &
  roscore_pid=$!
  trap 'kill "$roscore_pid" 2>/dev/null || true' EXIT
  sleep 3
  {
    echo "# Relocalisation through the node ($(date +%Y-%m-%d))"
    echo
    echo "\`bash bench/relocalisation.sh --node\`: default preset, 640x480, 2 threads, rate 1, no rviz. Each part of a"
    echo "real sequence made a bag with tum_to_bag (fr1: named rgbd_dataset_freiburg1_*, the OpenNI driver's default"
    echo "intrinsics in camera_info and the accelerometer on /imu, as TUM's 2011 bags); the first part played with"
    echo "\`roslaunch sdf_tracker tum_bag.launch bag:=...\` and its map saved with \`rosservice call"
    echo "/sdf_tracker/save_volume\` after playback; the later part then played $plays times with \`map_file:=\` that"
    echo "map. Share: later-part frames with a published pose within 5 cm and 5 degrees of the truth in the"
    echo "first session's map frame (redkitchen: of the uncut offline run), of all later-part frames. Frames"
    echo "until found: later-part frames before the first published pose. Off: published poses more than 10 cm"
    echo "or 10 degrees from the truth."
    echo
    echo "| sequence | play | within 5 cm, 5 deg | frames until found | off > 10 cm / 10 deg |"
    echo "|---|---|---|---|---|"
  } > "$report.part"
  for entry in "${cases[@]}"; do
    IFS='|' read -r name kind _ <<< "$entry"
    [ "$kind" = real ] || continue
    prepare "$entry"
    bag_name="$name"
    as_recorded=()
    case "$name" in fr1_*) bag_name="rgbd_dataset_freiburg1_${name#fr1_}"; as_recorded=(--openni-default-intrinsics) ;; esac
    for part in part1 part2; do
      "$bin/tum_to_bag" "$dir/$part" "$dir/${bag_name}_$part.bag" "${as_recorded[@]}" > "$dir/${part}_bag.log"
    done
    offset=$(grep -oE "shifted by [0-9.]+" "$dir/part2_bag.log" | awk '{print $3}' || true)
    echo "$name: the first session through the node" >&2
    node_play "$dir/${bag_name}_part1.bag" "$dir/node_part1" save:="$dir/node_part1/map.sdfmap"
    if [ ! -s "$dir/node_part1/map.sdfmap" ]; then
      echo "| $name | - | no map saved: $(tail -c 300 "$dir/node_part1/save_volume.log" | tr '\n|' '  ') | | |" >> "$report.part"
      continue
    fi
    for play in $(seq 1 "$plays"); do
      echo "$name: second session, play $play" >&2
      out="$dir/node_part2_play$play"
      node_play "$dir/${bag_name}_part2.bag" "$out" map_file:="$dir/node_part1/map.sdfmap"
      line=$(node_share "$truth" "$out/trajectory.txt" "$dir/node_part1/trajectory.txt" "$part2" "$out" "${offset:-0}")
      echo "| $name | $play | ${line//|/ | } |" >> "$report.part"
    done
  done
  publish "$report.part" "$report"
  exit 0
fi

if [ "$mode" = --sweep ]; then
  report="$results/$(date +%Y-%m-%d)_relocalisation_sweep.md"
  contradiction_values="0.01 0.02 0.03 0.05 0.08 0.12 0.2 0.3"
  overlap_values="0.1 0.2 0.3 0.4 0.5 0.6 0.7 0.85"
  names=()
  for entry in "${cases[@]}"; do prepare "$entry"; names+=("$name"); done
  {
    echo "# Relocalisation sweep ($(date +%Y-%m-%d))"
    echo
    echo "Default preset, 640x480, 2 threads; \`bash bench/relocalisation.sh --sweep\`. The second session of every"
    echo "case, at each value of one acceptance parameter with the other at its default (RelocaliseMaxContradiction"
    echo "0.05, RelocaliseMinOverlap 0.4). Each cell: later-part frames within 5 cm and 5 degrees (ambiguous"
    echo "cases: -), frames until found, false acceptances (an accepted pose more than 10 cm or 10 degrees off; in"
    echo "the ambiguous cases and the walk that never comes back, any acceptance)."
  } > "$report.part"
  for parameter in RelocaliseMaxContradiction RelocaliseMinOverlap; do
    values="$contradiction_values"
    [ "$parameter" = RelocaliseMinOverlap ] && values="$overlap_values"
    {
      echo
      echo "## $parameter"
      echo
      printf "| value |"; printf " %s |" "${names[@]}"; echo " false acceptances, all cases |"
      printf "|---|"; for _ in "${names[@]}"; do printf -- "---|"; done; echo "---|"
    } >> "$report.part"
    for value in $values; do
      row="| $value |"
      total_false=0
      for entry in "${cases[@]}"; do
        prepare "$entry"
        echo "$parameter=$value: $name" >&2
        IFS='|' read -r within until_found _ false_accepts _ <<< \
          "$(second_session "$dir/sweep_${parameter}_$value" --param "$parameter=$value")"
        share=$(echo "$within" | sed -n 's/.*(\(.*\)).*/\1/p')
        [ "$kind" = ambiguous ] && share="-"
        row="$row ${share:-0.0 %}, $until_found, $false_accepts |"
        total_false=$((total_false + false_accepts))
      done
      echo "$row $total_false |" >> "$report.part"
    done
  done
  publish "$report.part" "$report"
  exit 0
fi

report="$results/$(date +%Y-%m-%d)_relocalisation.md"
notes=()
{
  echo "# Relocalisation bench ($(date +%Y-%m-%d))"
  echo
  echo "Default preset, 640x480, 2 threads; \`bash bench/relocalisation.sh\`. Later-part frames within 5 cm and"
  echo "5 degrees of the truth in the map's frame (the ground truth, redkitchen's the uncut run, aligned by the first part's trajectory),"
  echo "frames the search took until the camera was found, CPU ms per searching frame (median / max), and"
  echo "accepted candidates more than 10 cm or 10 degrees from the truth (in an ambiguous case or the walk that"
  echo "never comes back: any), and later-part frames fused at a pose more than 10 cm from the truth (whether"
  echo "accepted by the search or tracked from the held pose)."
  echo
  echo "| sequence | protocol | first / later part | within 5 cm, 5 deg | frames until found | ms per search frame | false acceptances | fused > 10 cm off |"
  echo "|---|---|---|---|---|---|---|---|"
} > "$report.table"

for entry in "${cases[@]}"; do
  prepare "$entry"
  echo "$name: mapping $first_frames frames, then $later_frames"
  line=$(second_session "$dir/out_session2")
  echo "| $name | two sessions | $first_frames / $later_frames | ${line//|/ | } |" >> "$report.table"
  if [ "$truth" != "$ground_truth" ]; then
    "$bin/sdf_tracker_evaluate" --groundtruth "$ground_truth" --estimate "$dir/out_session2/trajectory.txt" \
      --map-frame-from "$dir/out_part1/trajectory.txt" > "$dir/out_session2.ground_truth.txt" 2>&1 || true
    notes+=("- $name: the truth is the uncut run; against the sequence's own ground truth, two sessions:
  $(sed -n 's/.*: \([0-9]* of [0-9]* poses\) within .*(\(.*\)).*/\1 (\2)/p' "$dir/out_session2.ground_truth.txt")")
  fi
  [ -n "$kidnap" ] || continue
  offline --sequence "$kidnap" --output "$dir/out_kidnap" > "$dir/kidnap.log" 2>&1 || true
  # The kidnap run's later part, and its first part as the map's frame.
  awk -v t="$split_at" '/^#/ || $1 < t' "$dir/out_kidnap/trajectory.txt" > "$dir/kidnap_part1.txt"
  awk -v t="$split_at" '/^#/ || $1 >= t' "$dir/out_kidnap/trajectory.txt" > "$dir/kidnap_part2.txt"
  line=$(measure "$kind" "$truth" "$dir/kidnap_part2.txt" "$dir/kidnap_part1.txt" "$dir/out_kidnap/frames.csv" \
    "$dir/out_kidnap/summary.json" "$split_at" "$dir/out_kidnap")
  echo "| $name | kidnap | $first_frames / $later_frames | ${line//|/ | } |" >> "$report.table"
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
  IFS='|' read -r name kind folder _ _ <<< "$entry"
  [ "$kind" = real ] || continue
  tag=$(echo "$name" | tr -c 'a-z0-9_\n' '_')
  offline --sequence "$folder" --output "$work/$tag/whole_on" > /dev/null 2>&1
  offline --sequence "$folder" --output "$work/$tag/whole_off" --param Relocalise=false > /dev/null 2>&1
  on=$(json "$work/$tag/whole_on/summary.json" '"%.2f" % d["ms"]["frame_median"]')
  off=$(json "$work/$tag/whole_off/summary.json" '"%.2f" % d["ms"]["frame_median"]')
  keyframes=$(json "$work/$tag/whole_on/summary.json" 'd["relocalisation"]["keyframes"]')
  bytes=$(sed -n 's/^place memory: .* keyframes, \([0-9]*\) bytes each.*/\1/p' "$work/$tag/whole_on/summary.txt")
  echo "| $name | $on | $off | $keyframes | $bytes |" >> "$report.table"
done
[ ${#notes[@]} -eq 0 ] || { echo; printf '%s\n' "${notes[@]}"; } >> "$report.table"
publish "$report.table" "$report"
