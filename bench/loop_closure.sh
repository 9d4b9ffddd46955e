#!/usr/bin/env bash
# Issue 43's bench: loop closure, each sequence run with one map (--param SubmapSize=0 --param
# LoopClosure=false) and with the default preset's 1 m submaps and loop closure, default preset,
# 640x480, 2 threads. Sequences: the synthetic round trip through the house (ends where and as it
# started) with a depth error fixed in the image of 1 % and 3 % at the corners (Kinect-like noise
# on), the round trip's first 14 s (down the corridor into a room: it never comes back, so any
# loop there is false), the house walk's first 30 s (round two rooms, whose views it sees again),
# and the real sequences in SDF_TRACKER_DATA.
#   ATE           RMSE after rigid alignment (sdf_tracker_evaluate): one map; with loops as
#                 optimised at the end (trajectory.txt) and as published at the time
#                 (trajectory_online.txt)
#   end to start  the estimated motion from the first frame to the last against the true one
#   loops         kept by the pose graph / rejected by it; false: kept loops more than three of
#                 their standard deviations (LoopClosureConfig) from the truth at the two submaps'
#                 anchors, and the worst kept loop's error
#   ms            frame time median (track + fuse + loop search, runner's clock) without / with;
#                 loop search per searched frame (median, max); graph solve (median, off the
#                 tracking thread)
#   memory        peak resident MiB without / with
# Writes bench/results/<date>_loop_closure.md.
#   bash bench/loop_closure.sh      (about 40 minutes on 2 cores, half of it rendering the first time)
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
bench_setup loop_closure
report="$results/$(date +%Y-%m-%d)_loop_closure.md"
py=/usr/bin/python3
errors="$repo/bench/report/loop_errors.py"
loop_sigma_m=0.02 loop_sigma_deg=1.0  # LoopClosureConfig's defaults

# name | sdf_tracker_synth options
synthetic=("round trip, depth bias 1 %|--motion round-trip --frames 2300 --depth-bias 0.01 --seed 1"
  "round trip, depth bias 3 %|--motion round-trip --frames 2300 --depth-bias 0.03 --seed 1"
  "house walk, 30 s|--motion walk --frames 900 --seed 21")
cases=()
for entry in "${synthetic[@]}"; do
  name="${entry%%|*}"
  options="${entry#*|}"
  dir="$work/$(echo "$name" | tr -c 'a-z0-9\n' '_')"
  if [ ! -f "$dir/depth.txt" ]; then
    echo "rendering $name ..."
    # shellcheck disable=SC2086
    "$bin/sdf_tracker_synth" --output "$dir" $options >/dev/null
  fi
  cases+=("$name|$dir|")
done
# name | folder | sdf_tracker_offline options
cases+=("round trip, first 14 s (never returns)|${cases[0]#*|}--frames 420")
real_sequences
for s in "${sequences[@]}"; do cases+=("$(basename "$s") (real)|$s|"); done

json() { "$py" -c "import json,sys; d=json.load(open(sys.argv[1])); print(eval(sys.argv[2]))" "$@"; }
ate_of() { "$bin/sdf_tracker_evaluate" --groundtruth "$1" --estimate "$2" | awk '$1 == "ATE" { printf "%.2f", 100 * $3 }'; }
end_of() { "$py" "$errors" end "$1" "$2" | awk '{ printf "%.1f cm, %.2f deg", 100 * $1, $2 }'; }

{
  echo "# Loop closure ($(date +%Y-%m-%d), $(git -C "$repo" rev-parse --short HEAD))"
  echo
  echo "bench/loop_closure.sh: default preset (1 m submaps, loop closure), 640x480, 2 threads; one map:"
  echo "--param SubmapSize=0 --param LoopClosure=false. ATE and end-to-start error in cm."
  echo
  echo "| sequence | ATE one map | ATE loops (optimised / as published) | end to start, one map | end to start, loops | loops kept / rejected | false loops (worst kept: cm, deg) | frame ms one map / loops | loop search ms (median, max) | graph solve ms | peak MiB one map / loops |"
  echo "|---|---|---|---|---|---|---|---|---|---|---|"
} > "$report"
for entry in "${cases[@]}"; do
  name="${entry%%|*}"
  rest="${entry#*|}"
  dir="${rest%%|*}"
  options="${rest#*|}"
  out="$work/runs/$(echo "$name" | tr -c 'a-z0-9\n' '_')"
  mkdir -p "$out"
  echo "$name ..."
  # shellcheck disable=SC2086
  "$bin/sdf_tracker_offline" --sequence "$dir" --output "$out/one_map" --threads 2 --quiet $options \
    --param SubmapSize=0 --param LoopClosure=false >/dev/null
  # shellcheck disable=SC2086
  "$bin/sdf_tracker_offline" --sequence "$dir" --output "$out/loops" --threads 2 --quiet $options >/dev/null
  gt="$dir/groundtruth.txt"
  read -r kept false worst_m worst_deg < <("$py" "$errors" loops "$gt" "$out/loops/loops.csv" "$loop_sigma_m" "$loop_sigma_deg")
  one="$out/one_map/summary.json" loops="$out/loops/summary.json"
  echo "| $name | $(ate_of "$gt" "$out/one_map/trajectory.txt") |" \
    "$(ate_of "$gt" "$out/loops/trajectory.txt") / $(ate_of "$gt" "$out/loops/trajectory_online.txt") |" \
    "$(end_of "$gt" "$out/one_map/trajectory.txt") | $(end_of "$gt" "$out/loops/trajectory.txt") |" \
    "$kept / $(json "$loops" "d['loops_rejected']") |" \
    "$false ($(awk -v m="$worst_m" -v d="$worst_deg" 'BEGIN { printf "%.1f, %.2f", 100 * m, d }')) |" \
    "$(json "$one" "'%.1f' % d['ms']['frame_median']") / $(json "$loops" "'%.1f' % d['ms']['frame_median']") |" \
    "$(json "$loops" "'%.0f, %.0f' % (d['loop_search']['ms_median'], d['loop_search']['ms_max'])") |" \
    "$(json "$loops" "'%.1f' % d['graph_solve']['ms_median']") |" \
    "$(json "$one" "'%.0f' % d['peak_rss_mb']") / $(json "$loops" "'%.0f' % d['peak_rss_mb']") |" >> "$report"
done
echo >> "$report"
cat "$report"
