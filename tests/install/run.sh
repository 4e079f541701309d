#!/usr/bin/env bash
# Install test: installs the build tree BUILD into WORK/prefix, then configures, builds and runs a small
# project outside the tree (tests/install/consumer) against find_package(occtrack) from there.
set -euo pipefail
build=$1 work=$2 scenario=$3
here=$(cd "$(dirname "$0")" && pwd)
rm -rf "$work" && mkdir -p "$work"
cmake --install "$build" --prefix "$work/prefix" > "$work/install.log"
cmake -S "$here/consumer" -B "$work/build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH="$work/prefix"
cmake --build "$work/build"
"$work/build/consumer" "$scenario"
