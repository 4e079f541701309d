#!/usr/bin/env bash
# Installs what occtrack needs to build and test, from Debian 12 packages only. Idempotent: packages already
# present are left alone, and nothing is downloaded when nothing is missing. Needs root (uses sudo if not).
set -euo pipefail

packages=(
  build-essential cmake ninja-build pkg-config  # compiler and build
  libeigen3-dev                                  # linear algebra (run-time library)
  nlohmann-json3-dev libyaml-cpp-dev             # case, result and scenario files
  libcli11-dev                                   # command line
  libgtest-dev googletest libbenchmark-dev       # tests and benchmarks
  python3                                        # the command-line tests edit JSON files with it
  libtorch-dev libopenblas0-pthread              # training (src/learning); OpenBLAS: ~20x faster than reference BLAS
  clang-14 libclang-rt-14-dev                    # the fuzz targets (fuzz/, libFuzzer); CI runs them
)

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
