#!/usr/bin/env bash
# Installs the Debian 12 packages UPD-Nav needs (only those missing), then configures and
# builds the project into build/. Sourced by the quick-start scripts; safe to run repeatedly.
# libopenni2-dev is optional (the camera input of `upd live`), and so is ROS 1 (`upd ros`, bag
# playback); the rest is required.
set -euo pipefail

UPD_ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
UPD_BUILD="${UPD_BUILD:-$UPD_ROOT/build}"
PACKAGES=(build-essential cmake pkg-config
          libeigen3-dev libmrpt-dev liboctomap-dev libopenni2-dev libopencv-dev
          libpcl-dev libgtest-dev libbenchmark-dev nlohmann-json3-dev libgdal-dev zlib1g-dev
          libjpeg-dev  # the rawlog pre-check decodes a JPEG before MRPT does
          libpng-dev  # depth PNGs, decoded with error handlers of ours
          libfreenect-dev libfreenect-bin  # the Kinect v1; fakenect replays it in the tests
          libegl1 libgl1-mesa-dri  # upd render: CFBORender through EGL, Mesa's software renderer
          libx11-dev xvfb  # upd view: screenshots read from the X server; its test's X server
          octomap-tools cloudcompare gdal-bin mrpt-apps  # these four: tests open our files in them
          python3  # scripts/results.sh formats docs/RESULTS.md; the layout and results tests
          ros-core libroscpp-dev librosbag-storage-dev libsensor-msgs-dev libnav-msgs-dev
          libgeometry-msgs-dev libvisualization-msgs-dev libtf2-ros-dev libtf2-msgs-dev
          clang-14 libclang-rt-14-dev libomp-14-dev)  # libFuzzer and the sanitizers (clang's
          # OpenMP): scripts/fuzz.sh, sanitize.sh
          # ros-core ... libtf2-msgs-dev: ROS 1, `upd ros` and bags (roscore: their tests)

missing=()
for p in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "setup: installing ${missing[*]}"
  SUDO=""
  [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  install_start=$SECONDS
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
  echo "setup: ${#missing[@]} packages installed in $((SECONDS - install_start)) s"
fi

cmake -S "$UPD_ROOT" -B "$UPD_BUILD" -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$UPD_BUILD" -j"$(nproc)"
