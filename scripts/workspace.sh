# Sourced by the scripts that run the package: installs what it needs, builds it, and sources the
# workspace. Sets `bin` to the folder of the executables.
#   source "$repo/scripts/workspace.sh"
# (A sourced file sees its caller's arguments: none of them may reach catkin_make, which would take
# a sequence folder given to run_main.sh for a make target and build nothing.)
bash "$repo/scripts/install_dependencies.sh"
bash "$repo/scripts/build.sh"
# catkin's Python helpers live in Debian's interpreter, not in a pyenv one that may be first on PATH.
export PATH="/usr/bin:$PATH"
set +u
# shellcheck disable=SC1091
source "$repo/build/ws/devel/setup.bash"
set -u
bin="$repo/build/ws/devel/lib/sdf_tracker"
