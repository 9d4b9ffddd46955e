# Sourced by the bench scripts.
# Sets `repo` and `data` (SDF_TRACKER_DATA, default ../shared/data beside the repository) and
# defines real_sequences: `real_sequences "$@"` fills the array `sequences` with the arguments, or
# with TUM fr1_xyz and 7-Scenes redkitchen from $data, saying SKIPPED for each one missing; and
# synthetic_sequence: `synthetic_sequence BIN WORK MOTION` prints the folder of the bench's synthetic
# sequence with that motion (300 frames, seed 21), generating it under WORK the first time; and
# require_matplotlib, which installs Debian's matplotlib for the reports' plots when it is missing;
# and bench_setup: `bench_setup NAME` sets `work` to build/bench/NAME (build/bench for "") and
# `results` to bench/results, creates both, and installs, builds and sources the workspace (`bin`).
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
data="${SDF_TRACKER_DATA:-$repo/../shared/data}"

real_sequences() {
  sequences=("$@")
  [ ${#sequences[@]} -gt 0 ] && return 0
  for s in tum_fr1_xyz 7scenes/redkitchen; do
    if [ -f "$data/$s/depth.txt" ]; then sequences+=("$data/$s"); else echo "SKIPPED: $data/$s not found"; fi
  done
}

synthetic_sequence() {
  local bin="$1" work="$2" motion="$3"
  local dir="$work/synthetic_$motion"
  [ -f "$dir/depth.txt" ] || "$bin/sdf_tracker_synth" --output "$dir" --motion "$motion" --frames 300 --seed 21 >/dev/null
  echo "$dir"
}

require_matplotlib() {
  dpkg-query -W -f='${Status}' python3-matplotlib 2>/dev/null | grep -q "install ok installed" ||
    { apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq python3-matplotlib >/dev/null; }
}

bench_setup() {
  work="$repo/build/bench${1:+/$1}"
  results="$repo/bench/results"
  mkdir -p "$work" "$results"
  # shellcheck source=../scripts/workspace.sh
  source "$repo/scripts/workspace.sh"
}
