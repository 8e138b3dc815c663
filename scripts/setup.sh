#!/usr/bin/env bash
# Installs every Debian package binloop needs to build, test, demo and render.
# Idempotent: packages already present are skipped quickly; `apt-get update` runs first as Debian requires.
set -euo pipefail

PACKAGES=(
  # build tools and ROS 1 as Debian ships it (no /opt/ros, nothing to source)
  build-essential cmake pkg-config clang-format clang-tidy catkin ros-base-dev ros-message-generation
  # the core is compiled by both builds (ROS-free and catkin): the second takes the first's objects
  ccache
  libnodelet-dev libnodeletlib-dev pluginlib-dev libtf2-ros-dev libtf2-eigen-dev
  librosbag-dev python3-rosbag python3-rospy python3-std-srvs python3-geometry-msgs python3-diagnostic-msgs libdynamic-reconfigure-config-init-mutex-dev python3-dynamic-reconfigure
  libcv-bridge-dev libimage-transport-dev libmessage-filters-dev
  libsensor-msgs-dev libgeometry-msgs-dev libnav-msgs-dev libvisualization-msgs-dev libstd-msgs-dev
  libdiagnostic-msgs-dev libdiagnostic-updater-dev
  python3-rostest python3-nose rosout python3-roslaunch rosbash python3-catkin-pkg
  # the robot-style rostest's URDF
  ros-robot-state-publisher
  # rviz (launch files' rviz:=true) and a virtual display + screenshots for looking at it headless
  rviz xvfb imagemagick
  # numerics and vision
  libopencv-dev libeigen3-dev libceres-dev libsuitesparse-dev libgtest-dev libgmock-dev libbenchmark-dev
  # real photographs used as texture banks and vocabulary training data
  opencv-doc python3-skimage plasma-workspace-wallpapers
  # real photographs of the held-out loop set (data/loop_sets/real_heldout.txt)
  mate-backgrounds ukui-wallpapers visp-images-data
)

SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi

missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all ${#PACKAGES[@]} packages already installed"
  exit 0
fi

echo "setup: installing ${#missing[@]} packages: ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -q
$SUDO apt-get install -y -q --no-install-recommends "${missing[@]}"
echo "setup: done"
