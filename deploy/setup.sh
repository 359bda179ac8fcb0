#!/usr/bin/env bash
# Installs the Debian 12 packages modskill builds with (only those missing; libopenblas0-pthread
# replaces the reference BLAS that Debian's torch otherwise calls, 6x faster updates), then configures
# and builds everything in build/ (Release, ccache). Safe to run again: it only does what is
# left to do.
set -euo pipefail
cd "$(dirname "$0")/.."

PACKAGES=(
  build-essential cmake ccache pkg-config
  libmujoco-dev libqhull-dev libeigen3-dev libabsl-dev zlib1g-dev libzip-dev nlohmann-json3-dev
  libgrpc++-dev protobuf-compiler-grpc libprotobuf-dev protobuf-compiler libtorch-dev
  libgloo-dev  # the Gloo headers c10d's ProcessGroupGloo.hpp includes (data-parallel learners)
  libopenblas0-pthread
  libgtest-dev libgmock-dev
  openssl  # tests/tls_server_test makes a throwaway CA and certificates with it
  clang libfuzzer-14-dev  # the fuzz targets deploy/test.sh runs (fuzz/run.sh, build-fuzz/)
  python3-grpcio python3-numpy python3-matplotlib
  python3-venv python3-pip python3-setuptools python3-wheel  # pip install ./client/python, offline
  libjs-three  # three.js, inlined into the HTML viewer pages (common/viewer)
  chromium     # tests/viewer: the viewer page in headless Chromium
  python3-yaml  # tests/k8s: deploy/k8s/check_manifests.py reads the Kubernetes manifests
  iproute2  # tests/netns: server and learner hosts as network namespaces (ip netns, veth, tc)
)

missing=()
for package in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$package" 2>/dev/null | grep -q "install ok installed" || missing+=("$package")
done
if ((${#missing[@]})); then
  echo "modskill: installing ${missing[*]}"
  SUDO=""
  if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
  $SUDO apt-get update -q
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -q --no-install-recommends "${missing[@]}"
fi

BUILD_DIR="${MODSKILL_BUILD_DIR:-build}"
JOBS="${MODSKILL_JOBS:-$(nproc)}"
# MODSKILL_UNITY_BUILD=ON (.ci/run sets it): a unity build, up to 8 .cc files of a target per
# compiler run, so torch's and Eigen's templates are instantiated once a batch instead of once a
# file (4 of the learner's files: 38 s of CPU instead of 132 s); editing a file recompiles its batch.
unity=()
if [[ -n "${MODSKILL_UNITY_BUILD:-}" ]]; then unity=(-DCMAKE_UNITY_BUILD="${MODSKILL_UNITY_BUILD}"); fi
mkdir -p "$BUILD_DIR"
cmake -S . -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=Release "${unity[@]}" > "$BUILD_DIR/cmake.log" 2>&1 || { cat "$BUILD_DIR/cmake.log"; exit 1; }
cmake --build "$BUILD_DIR" -j "$JOBS"
