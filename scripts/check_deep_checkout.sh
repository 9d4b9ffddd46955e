#!/usr/bin/env bash
# Configures the package with tests, as scripts/build.sh does, from a checkout whose path is over
# 150 characters long (a CI runner's workspace, a catkin workspace under a long home folder): every
# file CMake generates must stay within the file system's 255 characters per name, whatever the
# path. Writes a JUnit result to RESULTS_DIR (default build/deep_checkout).
#   scripts/check_deep_checkout.sh
set -euo pipefail
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
results="${RESULTS_DIR:-$repo/build/deep_checkout}"
mkdir -p "$results"
root="$(mktemp -d)"
trap 'rm -rf "$root"' EXIT
# A checkout of 150 characters or more, with scripts/build.sh's workspace inside it.
checkout="$root/a_folder_named_like_a_ci_runners_workspace_for_this_project/home/a_user_with_a_long_name"
while [ ${#checkout} -lt 150 ]; do checkout="$checkout/ros/catkin_ws/src/sdf_tracker"; done
ws="$checkout/build/ws"
mkdir -p "$ws/src/sdf_tracker"
for entry in "$repo"/*; do
  case "$(basename "$entry")" in build|output) continue ;; esac
  ln -s "$entry" "$ws/src/sdf_tracker/$(basename "$entry")"
done
length=${#checkout}
export PATH="/usr/bin:$PATH"
set +u
# shellcheck disable=SC1091
[ -f /opt/ros/noetic/setup.bash ] && source /opt/ros/noetic/setup.bash
set -u
ln -s /usr/share/catkin/cmake/toplevel.cmake "$ws/src/CMakeLists.txt"
status=0
cmake -G Ninja -S "$ws/src" -B "$ws/build" -DCATKIN_DEVEL_PREFIX="$ws/devel" -DCATKIN_ENABLE_TESTING=ON \
  -DCMAKE_BUILD_TYPE=Release -DPYTHON_EXECUTABLE=/usr/bin/python3 > "$results/cmake.log" 2>&1 || status=1
failure=""
if [ $status -ne 0 ]; then
  grep -E "CMake Error|Cannot open|error" "$results/cmake.log" | head -n 5
  failure="<failure message=\"configuring from a $length-character checkout path failed (build/deep_checkout/cmake.log)\"/>"
  echo "deep checkout: configuring from a $length-character path failed"
else
  echo "deep checkout: the package configures with its tests from a $length-character checkout path"
fi
printf '<testsuite name="build" tests="1"><testcase classname="build" name="configures_from_a_deep_checkout">%s</testcase></testsuite>\n' \
  "$failure" > "$results/deep_checkout.xml"
exit $status
