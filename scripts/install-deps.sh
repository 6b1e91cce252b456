#!/usr/bin/env bash
# Installs the Debian packages r1 needs, and only those that are missing.
# Usage: scripts/install-deps.sh [--check]   (--check lists what is missing, installs nothing)
set -euo pipefail

# Why each package is here:
#   build: compiler, CMake, Ninja, ccache; clang-14 + its runtime for libFuzzer and the sanitizer build
#   numerics: Boost.Multiprecision (references in property tests), Eigen + Spectra (eigensolvers)
#   input/CLI: toml++, CLI11, nlohmann-json; TBB for the parallel paths; OpenSSL's libcrypto for
#     the SHA-256 of snapshot record chunks (an incremental epoch's digest, R1-EPO-017); zstd for
#     the layout graph's arrays parked during the spectral solve (R1-EPO-006)
#   images: OpenImageIO (+ the tools and OpenCV core its CMake config asks for), OpenColorIO,
#     DejaVu fonts for the T1 labels OpenImageIO draws
#   tests/bench: GoogleTest/GoogleMock, RapidCheck, Google Benchmark, SciPy for peer comparisons
#   viewer: cpp-httplib (r1 view's server); Chromium for the page's browser tests (Node.js and
#     playwright-core come after the packages, below)
#   vulkan: the loader and headers, shaderc (GLSL to SPIR-V at run time, the 13.1 trait's
#     shader_compile), Mesa's lavapipe (a Vulkan device on the CPU, so CI runs the Vulkan tests)
#   portability (x86-64 hosts only): the aarch64 cross compiler, with which every source is compiled
#     for ARM, syntax only (scripts/check-aarch64.py, R1-BKD-045)
PACKAGES=(
  g++ cmake ninja-build make pkg-config ccache
  clang-14 libclang-rt-14-dev lld
  libboost-dev libeigen3-dev libspectra-dev
  libtomlplusplus-dev libcli11-dev nlohmann-json3-dev libtbb-dev libssl-dev libzstd-dev
  libopenimageio-dev openimageio-tools libopencv-core-dev libopencolorio-dev fonts-dejavu-core
  libgtest-dev libgmock-dev librapidcheck-dev libbenchmark-dev
  python3 python3-numpy python3-scipy
  libvulkan-dev libshaderc-dev mesa-vulkan-drivers
  libcpp-httplib-dev chromium
)
if [ "$(uname -m)" = "x86_64" ]; then PACKAGES+=(g++-aarch64-linux-gnu); fi

missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q '^install ok installed$'; then
    missing+=("$p")
  fi
done

# The browser tests' driver: Node.js (Debian's, unless one is installed) and playwright-core,
# pinned by viewer/tests/package-lock.json, from the npm registry into viewer/tests/node_modules.
ROOT=$(cd "$(dirname "$0")/.." && pwd)
if ! command -v node >/dev/null 2>&1; then missing+=(nodejs npm); fi
need_npm=0
[ -d "$ROOT/viewer/tests/node_modules/playwright-core" ] || need_npm=1

if [ "${1:-}" = "--check" ]; then
  [ $need_npm = 1 ] && missing+=("npm:playwright-core")
  if [ ${#missing[@]} -eq 0 ]; then echo "all dependencies present"; else echo "missing: ${missing[*]}"; fi
  exit 0
fi
if [ ${#missing[@]} -gt 0 ]; then
  echo "r1: installing missing packages: ${missing[*]}" >&2
  SUDO=""
  if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update -qq
  $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi
if [ $need_npm = 1 ]; then
  echo "r1: installing playwright-core (viewer/tests, the browser tests' driver)" >&2
  npm ci --prefix "$ROOT/viewer/tests" --no-audit --no-fund --loglevel=error >&2
fi
