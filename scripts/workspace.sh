# Sourced by the scripts that run the package: installs what it needs, builds it (extra arguments
# go to catkin_make), and sources the workspace. Sets `bin` to the folder of the executables.
#   source "$repo/scripts/workspace.sh" [catkin_make arguments]
bash "$repo/scripts/install_dependencies.sh"
bash "$repo/scripts/build.sh" "$@"
# catkin's Python helpers live in Debian's interpreter, not in a pyenv one that may be first on PATH.
export PATH="/usr/bin:$PATH"
set +u
# shellcheck disable=SC1091
source "$repo/build/ws/devel/setup.bash"
set -u
bin="$repo/build/ws/devel/lib/sdf_tracker"
