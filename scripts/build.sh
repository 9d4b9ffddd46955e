#!/usr/bin/env bash
# Builds the package in Release through catkin, in a workspace under build/ whose src/ links back
# to this repository (the repository root is the package). Prints where the binaries are.
#   scripts/build.sh [extra catkin_make arguments]
set -euo pipefail
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
ws="$repo/build/ws"
# The package directory in the workspace mirrors the repository entry by entry (symbolic links),
# leaving out build/ itself: a link to the whole repository would put the workspace inside its
# own package, and rospack/roslaunch would crawl round that loop forever.
pkg="$ws/src/sdf_tracker"
[ -L "$pkg" ] && rm "$pkg"
mkdir -p "$pkg"
for entry in "$repo"/* "$repo"/.ci; do
  name="$(basename "$entry")"
  case "$name" in build|output) continue ;; esac
  ln -sfn "$entry" "$pkg/$name"
done
for link in "$pkg"/*; do [ -e "$link" ] || rm -f "$link"; done  # entries removed from the repo
# catkin's Python helpers live in Debian's interpreter, not in a pyenv one that may be first on PATH.
export PATH="/usr/bin:$PATH"
set +u
# shellcheck disable=SC1091
[ -f /opt/ros/noetic/setup.bash ] && source /opt/ros/noetic/setup.bash
set -u
cd "$ws"
# Ninja compiles a part's sources while the parts it links are still being built (make waits for
# each library first): on two cores the build is a fifth shorter. A workspace configured by an
# earlier make-based build is configured again.
if [ -f build/CMakeCache.txt ] && ! grep -q "^CMAKE_GENERATOR:INTERNAL=Ninja$" build/CMakeCache.txt; then
  rm -rf build
fi
catkin_make --use-ninja -DCMAKE_BUILD_TYPE=Release -DPYTHON_EXECUTABLE=/usr/bin/python3 -j"$(nproc)" "$@" \
  > "$repo/build/catkin_make.log" 2>&1 || { tail -n 60 "$repo/build/catkin_make.log"; echo "build failed (full log: build/catkin_make.log)"; exit 1; }
grep -E "warning:" "$repo/build/catkin_make.log" | sort -u | head -20 || true
echo "built: $ws/devel/lib/sdf_tracker/"
