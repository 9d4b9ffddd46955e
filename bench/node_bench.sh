#!/usr/bin/env bash
# The node path at the bag's real rate: each sequence is converted with tum_to_bag into a bag shaped
# like the TUM RGB-D benchmark's and played with the README's command
#   roslaunch sdf_tracker tum_bag.launch bag:=... rviz:=false
# on an idle machine, beside one busy process (a CPU-bound loop, as another program on a robot), and
# with rviz:=true. A TUM freiburg1 sequence (tum_fr1_*) becomes the bag TUM published for it: named
# rgbd_dataset_freiburg1_*.bag, so tum_bag.launch picks freiburg1's calibration from the name, and
# with the OpenNI driver's default intrinsics in camera_info, as the 2011 bags are expected to have
# (README, "Calibration"). For each run it prints frames processed, the node's ms per frame
# (conversion, tracking, fusion, publishing), ATE against the ground truth, and whether any frame on
# /tf had two parents; the offline runner on the same frames gives the reference ATE and ms per frame.
#   bash bench/node_bench.sh [SEQUENCE_DIR ...]   (default: fr1_xyz and redkitchen from SDF_TRACKER_DATA)
#   RUNS="idle busy" picks the runs (default: idle busy rviz); rviz runs with rviz on, under xvfb-run
#   (installed from Debian when missing), rendering in software on the same cores.
# Writes bench/results/<date>_node.md (<date>_node_<runs>.md with RUNS). No test asserts these figures.
set -euo pipefail
# shellcheck source=common.sh
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
bench_setup node
runs_name="${RUNS:-}"
report="$results/$(date +%Y-%m-%d)_node${runs_name:+_${runs_name// /_}}.md"
read -r -a runs <<< "${RUNS:-idle busy rviz}"
if [[ " ${runs[*]} " == *" rviz "* ]] && ! command -v xvfb-run > /dev/null; then
  apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq xvfb > /dev/null
fi

real_sequences "$@"

roscore_pid=""
cleanup() {
  [ -n "${busy_pid:-}" ] && kill "$busy_pid" 2>/dev/null || true
  [ -n "$roscore_pid" ] && kill "$roscore_pid" 2>/dev/null || true
}
trap cleanup EXIT
roscore > "$work/roscore.log" 2>&1 &
roscore_pid=$!
sleep 3

# Frames that got two parents in a recorded /tf (+ /tf_static); prints "none" or the list.
two_parents() {
  /usr/bin/python3 - "$1" <<'PY'
import sys, rosbag
parents = {}
for _, msg, _ in rosbag.Bag(sys.argv[1]).read_messages(topics=["/tf", "/tf_static"]):
    for t in msg.transforms:
        parents.setdefault(t.child_frame_id.lstrip("/"), set()).add(t.header.frame_id.lstrip("/"))
bad = {c: p for c, p in parents.items() if len(p) > 1}
print("none" if not bad else "; ".join(f"{c} <- {sorted(p)}" for c, p in bad.items()))
PY
}

{
  echo "# The node at the bag's real rate ($(date +%Y-%m-%d))"
  echo
  echo "\`roslaunch sdf_tracker tum_bag.launch bag:=... rviz:=false\` (rviz:=true in the \"rviz\" run; default preset,"
  echo "rate 1.0) on $(nproc) cores;"
  echo "\"busy\": one CPU-bound process running beside it. ms per frame: the node's whole cost of a frame"
  echo "(median). Offline: \`sdf_tracker_offline\` on the same frames (median tracking + fusion). \"rviz\":"
  echo "with rviz on, under xvfb-run (it renders in software on the same cores). fr1 sequences are played"
  echo "as TUM's 2011 bags: named rgbd_dataset_freiburg1_*.bag, the driver's default in camera_info."
  echo
  echo "| sequence | bag | run | frames processed | node ms/frame | ATE | frames with two parents |"
  echo "|---|---|---|---|---|---|---|"
} > "$report"

for sequence in "${sequences[@]}"; do
  name="$(basename "$sequence")"
  case "$name" in
    tum_fr1_*) bag="$work/rgbd_dataset_freiburg1_${name#tum_fr1_}.bag"; as_recorded=(--openni-default-intrinsics) ;;
    *) bag="$work/$name.bag"; as_recorded=() ;;
  esac
  [ -f "$bag" ] || "$bin/tum_to_bag" "$sequence" "$bag" "${as_recorded[@]}" > "$work/$name.tum_to_bag.log"
  offset=$(grep -oE "shifted by [0-9.]+" "$work/$name.tum_to_bag.log" | awk '{print $3}' || true)
  frames=$(grep -cvE '^\s*(#|$)' "$sequence/depth.txt")

  "$bin/sdf_tracker_offline" --sequence "$sequence" --output "$work/$name.offline" --quiet > /dev/null
  off_ms=$(grep -oE "per frame \(ms\): median [0-9.]+" "$work/$name.offline/summary.txt" | awk '{print $5}')
  off_ate=$(grep -oE "ATE  RMSE [0-9.]+" "$work/$name.offline/summary.txt" | awk '{print $3}')
  echo "| $name | - | offline | $frames of $frames | $off_ms | ${off_ate} m | - |" >> "$report"

  for run in "${runs[@]}"; do
    out="$work/$name.$run"
    mkdir -p "$out"
    busy_pid=""
    if [ "$run" = busy ]; then
      bash -c 'while :; do :; done' &
      busy_pid=$!
    fi
    rosbag record -O "$out/tf.bag" /tf /tf_static __name:=tf_recorder > /dev/null 2>&1 &
    recorder=$!
    sleep 1
    launch=(roslaunch sdf_tracker tum_bag.launch bag:="$bag" trajectory_file:="$out/trajectory.txt")
    if [ "$run" = rviz ]; then
      xvfb-run -a -s "-screen 0 1280x1024x24" "${launch[@]}" rviz:=true > "$out/roslaunch.log" 2>&1 || true
    else
      "${launch[@]}" rviz:=false > "$out/roslaunch.log" 2>&1 || true
    fi
    rosnode kill /tf_recorder > /dev/null 2>&1 || true
    wait "$recorder" 2>/dev/null || true
    [ -n "$busy_pid" ] && { kill "$busy_pid"; wait "$busy_pid" 2>/dev/null || true; busy_pid=""; }
    tracked=$(grep -cvE '^\s*(#|$)' "$out/trajectory.txt" 2>/dev/null || echo 0)
    node_ms=$(grep -aoE "per frame in the node: median [0-9.]+" "$out/roslaunch.log" | awk '{print $7}' | tail -n 1)
    ate=$("$bin/sdf_tracker_evaluate" --groundtruth "$sequence/groundtruth.txt" --estimate "$out/trajectory.txt" \
            --estimate-time-offset "${offset:-0}" 2>/dev/null | grep -oE "ATE  RMSE [0-9.]+" | awk '{print $3}' || echo "?")
    parents=$(two_parents "$out/tf.bag" 2>/dev/null || echo "?")
    line="| $name | $(basename "$bag") | $run | $tracked of $frames ($((100 * tracked / frames)) %) | ${node_ms:-?} | ${ate} m | $parents |"
    echo "$line" | tee -a "$report"
  done
done
echo "report: $report"
