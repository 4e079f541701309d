#!/usr/bin/env bash
# Configures and builds occtrack into ./build (Release, tuned for this machine's CPU).
#   scripts/build.sh run   only what the main job needs: the command-line tool and the Eigen-only library
#                          (no LibTorch, tests, benchmarks, Python or ROS), about 2-3 minutes on 2 cores
#   scripts/build.sh       everything that setup.sh installed the dependencies for, with tests and benchmarks
# Further arguments go to the CMake configure step, e.g. scripts/build.sh -DOCCTRACK_NATIVE=OFF.
set -euo pipefail
cd "$(dirname "$0")/.."
mode=all
case "${1:-}" in
  run | all) mode=$1; shift ;;
esac
common=(-G Ninja -DCMAKE_BUILD_TYPE=Release -DOCCTRACK_NATIVE=ON)
if [ "$mode" = run ]; then
  cmake -S . -B build "${common[@]}" -DOCCTRACK_LEARNING=OFF -DOCCTRACK_BUILD_TESTS=OFF \
    -DOCCTRACK_BUILD_BENCHMARKS=OFF -DOCCTRACK_PYTHON=OFF -DOCCTRACK_ROS=OFF -DOCCTRACK_MPI=OFF "$@"
  cmake --build build --parallel "$(nproc)" --target occtrack_cli
else
  # Every option named, so that a build folder first made by `build.sh run` gets the rest too.
  cmake -S . -B build "${common[@]}" -DOCCTRACK_LEARNING=AUTO -DOCCTRACK_BUILD_TESTS=ON \
    -DOCCTRACK_BUILD_BENCHMARKS=ON -DOCCTRACK_PYTHON=AUTO -DOCCTRACK_ROS=AUTO -DOCCTRACK_MPI=AUTO "$@"
  cmake --build build --parallel "$(nproc)"
fi
