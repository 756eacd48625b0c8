#!/usr/bin/env bash
# Installs dependencies, builds, and runs the whole test suite (ctest), the Python module's tests
# (pytest, scripts/test_python.sh), then every file reader's fuzz target for a short seeded run
# (scripts/fuzz.sh; docs/architecture.md, "Fuzzing").
#   scripts/test.sh               the above, in build/ (what CI runs)
#   scripts/test.sh --sanitize    the test suite built with ASan and UBSan in build-asan/ instead
#                                 (docs/architecture.md, "Sanitizers"); no fuzzing
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
if [ "${1:-}" = "--sanitize" ]; then
  bash scripts/install_deps.sh
  gen=()
  command -v ninja >/dev/null 2>&1 && gen=(-G Ninja)
  if [ ! -f build-asan/CMakeCache.txt ]; then
    cmake -S . -B build-asan "${gen[@]}" -DCMAKE_BUILD_TYPE=Release -DUNIQUE3D_SANITIZE=ON -DUNIQUE3D_BUILD_BENCH=OFF
  fi
  cmake --build build-asan --parallel "$(nproc)"
  cd build-asan
  export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
  ctest --output-on-failure --parallel "$(nproc)"
  exit 0
fi
[ $# -eq 0 ] || { echo "usage: scripts/test.sh [--sanitize]" >&2; exit 2; }
bash scripts/build.sh
cd build
ctest --output-on-failure --parallel "$(nproc)"
cd "$root"
bash scripts/test_python.sh
FUZZ_SEED=1 bash scripts/fuzz.sh 20
