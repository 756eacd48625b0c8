#!/usr/bin/env bash
# Installs dependencies, builds, and runs the whole test suite (ctest), the Python module's tests
# (pytest, scripts/test_python.sh), then every file reader's fuzz target for a short seeded run
# (scripts/fuzz.sh; docs/architecture.md, "Fuzzing").
#   scripts/test.sh               the above, in build/ (what CI runs)
#   scripts/test.sh --sanitize    the test suite built with ASan and UBSan in build-asan/ instead
#                                 (docs/architecture.md, "Sanitizers"); no pytest, no fuzzing
# The output ends with one block saying how many tests skipped and why (scripts/skipped_tests.sh).
# Tests that skip where a machine lacks something fail instead where it has it
# (tests/nn/required_skip.h): bf16 tests on a CPU with avx512_bf16, the real-ISNet test once
# scripts/fetch_imgly_isnet.sh has the model.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
build=build
if [ "${1:-}" = "--sanitize" ]; then
  build=build-asan
  bash scripts/install_deps.sh
  gen=()
  command -v ninja >/dev/null 2>&1 && gen=(-G Ninja)
  if [ ! -f build-asan/CMakeCache.txt ]; then
    cmake -S . -B build-asan "${gen[@]}" -DCMAKE_BUILD_TYPE=Release -DUNIQUE3D_SANITIZE=ON -DUNIQUE3D_BUILD_BENCH=OFF
  fi
  cmake --build build-asan --parallel "$(nproc)"
  export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
else
  [ $# -eq 0 ] || { echo "usage: scripts/test.sh [--sanitize]" >&2; exit 2; }
  bash scripts/build.sh
fi
if grep -qw avx512_bf16 /proc/cpuinfo; then export UNIQUE3D_REQUIRE_BF16=1; fi
if bash scripts/fetch_imgly_isnet.sh --cached >/dev/null; then export UNIQUE3D_REQUIRE_REAL_ISNET=1; fi
rm -f "$build/ctest-junit.xml"
status=0
(cd "$build" && ctest --output-on-failure --parallel "$(nproc)" --output-junit "$root/$build/ctest-junit.xml") ||
  status=$?
if [ "$build" = build ]; then
  bash scripts/test_python.sh || status=$?
  if [ $status -eq 0 ]; then FUZZ_SEED=1 bash scripts/fuzz.sh 20 || status=$?; fi
fi
bash scripts/skipped_tests.sh "$build/ctest-junit.xml"
exit $status
