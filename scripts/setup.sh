#!/usr/bin/env bash
# Installs what occtrack needs to build and test, from Debian 12 packages only. Idempotent: packages already
# present are left alone, and nothing is downloaded when nothing is missing. Needs root (uses sudo if not).
set -euo pipefail

# `setup.sh run` installs only what the main job needs (the command-line tool and the Eigen-only library);
# `setup.sh` alone installs everything: training, tests, benchmarks, fuzzers, Python, ROS and the browser test.
runtime_packages=(
  build-essential cmake ninja-build pkg-config  # compiler and build
  libeigen3-dev                                  # linear algebra (run-time library)
  nlohmann-json3-dev libyaml-cpp-dev             # case, result and scenario files
  libcli11-dev                                   # command line
)
test_packages=(
  libgtest-dev googletest libbenchmark-dev       # tests and benchmarks
  python3                                        # the command-line tests edit JSON files with it
  libtorch-dev libopenblas0-pthread              # training (src/learning); OpenBLAS: ~20x faster than reference BLAS
  clang-14 libclang-rt-14-dev                    # the fuzz targets (fuzz/, libFuzzer); CI runs them
  pybind11-dev python3-dev python3-numpy python3-pytest python3-matplotlib  # Python (python/), tests, plot
  chromium                                       # the HTML replay's browser test (headless)
  libopenmpi-dev openmpi-bin                     # `mpirun occtrack dataset generate` (docs/scaling.md)
  libgloo-dev                                    # data-parallel `occtrack train` (c10d Gloo's headers)
)
ros_packages=(  # the ROS 1 node (ros/) and its closed-loop test against a real roscore
  libroscpp-dev libstd-msgs-dev libsensor-msgs-dev libnav-msgs-dev libgeometry-msgs-dev libvisualization-msgs-dev
  python3-roslaunch rosout
)

case "${1:-all}" in
  run) packages=("${runtime_packages[@]}") ;;
  all) packages=("${runtime_packages[@]}" "${test_packages[@]}" "${ros_packages[@]}") ;;
  *) echo "usage: $0 [run|all]   (run: only what the main job needs; all, the default: everything)" >&2; exit 2 ;;
esac

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all ${#packages[@]} dependencies are installed"
  exit 0
fi

as_root=()
if [ "$(id -u)" -ne 0 ]; then
  if command -v sudo >/dev/null 2>&1; then
    as_root=(sudo)
  else
    echo "setup: these packages are missing and installing them needs root: ${missing[*]}" >&2
    echo "setup: run this script as root, or install them with apt-get" >&2
    exit 1
  fi
fi
echo "setup: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
"${as_root[@]}" apt-get update -qq
"${as_root[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
echo "setup: done"
