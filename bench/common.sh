# Sourced by the bench scripts that run the shared real sequences.
# Sets `repo` and `data` (SDF_TRACKER_DATA, default ../shared/data beside the repository) and
# defines real_sequences: `real_sequences "$@"` fills the array `sequences` with the arguments, or
# with TUM fr1_xyz and 7-Scenes redkitchen from $data, saying SKIPPED for each one missing.
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
data="${SDF_TRACKER_DATA:-$repo/../shared/data}"

real_sequences() {
  sequences=("$@")
  [ ${#sequences[@]} -gt 0 ] && return 0
  for s in tum_fr1_xyz 7scenes/redkitchen; do
    if [ -f "$data/$s/depth.txt" ]; then sequences+=("$data/$s"); else echo "SKIPPED: $data/$s not found"; fi
  done
}
