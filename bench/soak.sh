#!/usr/bin/env bash
# The soak: 10,000+ frames through sdf_tracker_node (a synthetic closed-loop sequence converted with
# tum_to_bag and played again and again by soak_player.py, stamps increasing across loops), with the
# node's resident memory and ms per frame every 1,000 frames. Both should stay flat: the map is a
# fixed grid, ~path is bounded (~path_length) and the trajectory grows by one pose per frame.
#   bash bench/soak.sh [FRAMES]       (default 10000; about 4 minutes on 2 cores)
# Writes bench/results/<date>_soak.md.
set -euo pipefail
# shellcheck source=common.sh
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
frames="${1:-10000}"
bench_setup soak
report="$results/$(date +%Y-%m-%d)_soak.md"

sequence="$work/loop_qvga"
[ -f "$sequence/depth.txt" ] || "$bin/sdf_tracker_synth" --output "$sequence" --motion loop --frames 300 --seed 9 \
  --size 320x240 > /dev/null
[ -f "$work/loop_qvga.bag" ] || "$bin/tum_to_bag" "$sequence" "$work/loop_qvga.bag" > /dev/null

pids=()
cleanup() { for pid in "${pids[@]}"; do kill "$pid" 2>/dev/null || true; done; }
trap cleanup EXIT
roscore > "$work/roscore.log" 2>&1 &
pids+=($!)
sleep 3
OMP_WAIT_POLICY=PASSIVE "$bin/sdf_tracker_node" __name:=sdf_tracker _c_name:=camera _trajectory_file:="$work/trajectory.txt" \
  > "$work/node.log" 2>&1 &
node=$!
pids+=("$node")
"$repo/bench/soak_player.py" "$work/loop_qvga.bag" "$frames" "$node" 1000 | tee "$work/soak.txt"

/usr/bin/python3 - "$work/soak.txt" "$report" "$frames" <<'PY'
import sys
rows = [l.split() for l in open(sys.argv[1]) if l.strip() and l.split()[0].isdigit()]
first, last = rows[0], rows[-1]
def change(a, b):
    return 100.0 * (float(b) - float(a)) / float(a)
# Flatness from frame 1,000 (after start-up) to the end.
with open(sys.argv[2], "w") as out:
    out.write(f"# Soak: {sys.argv[3]} frames through sdf_tracker_node\n\n")
    out.write("`bash bench/soak.sh` (QVGA synthetic closed loop of 300 frames, played again and again with stamps\n"
              "increasing; one frame at a time; default preset). Every 1,000 frames: the node's resident memory and\n"
              "its mean tracking + fusion time over those frames.\n\n")
    out.write("| frames | resident MB | ms per frame | failed frames |\n|---|---|---|---|\n")
    for r in rows:
        out.write(f"| {r[0]} | {r[1]} | {r[2]} | {r[3]} |\n")
    out.write(f"\nFrom frame {first[0]} to {last[0]}: resident memory {change(first[1], last[1]):+.1f} %, "
              f"ms per frame {change(first[2], last[2]):+.1f} %.\n")
print(open(sys.argv[2]).read().splitlines()[-1])
PY
echo "report: $report"
