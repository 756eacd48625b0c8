#!/usr/bin/env bash
# Installs dependencies, builds, and runs the whole test suite (ctest), then every file reader's fuzz
# target for a short seeded run (scripts/fuzz.sh; docs/architecture.md, "Fuzzing").
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
bash scripts/build.sh
cd build
ctest --output-on-failure --parallel "$(nproc)"
cd "$root"
FUZZ_SEED=1 bash scripts/fuzz.sh 20
