#!/usr/bin/env bash
# Installs the Debian 12 packages sdf_tracker needs to build, run and test (ROS 1 from Debian).
# Skips apt entirely when everything is already there.
set -euo pipefail

packages=(
  build-essential cmake ninja-build catkin ros-base-dev
  libeigen3-dev libopencv-dev libgtest-dev libceres-dev
  libpcl-dev libpcl-conversions-dev libtf2-ros-dev libtf2-eigen-dev libcv-bridge-dev libimage-transport-dev
  libdynamic-reconfigure-config-init-mutex-dev python3-dynamic-reconfigure python3-rostest librostest-dev
  python3-rosbag python3-rospy libopenni2-dev libtf-dev libtopic-tools-dev rviz
  libcamera-info-manager-dev libdiagnostic-updater-dev libfreenect-dev libfreenect-bin
)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "dependencies: all ${#packages[@]} packages present"
  exit 0
fi
echo "dependencies: installing ${#missing[@]} packages: ${missing[*]}"
SUDO=""
[ "$(id -u)" -ne 0 ] && SUDO="sudo"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq "${missing[@]}" >/dev/null
echo "dependencies: done"
