#!/usr/bin/env bash
# Configures and builds occtrack into ./build (Release, tuned for this machine's CPU, with benchmarks).
# Extra arguments go to the CMake configure step, e.g. scripts/build.sh -DOCCTRACK_NATIVE=OFF.
set -euo pipefail
cd "$(dirname "$0")/.."
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release -DOCCTRACK_NATIVE=ON -DOCCTRACK_BUILD_BENCHMARKS=ON "$@"
cmake --build build --parallel "$(nproc)"
