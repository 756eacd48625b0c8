#!/usr/bin/env bash
# Runs the Python module's tests (tests/python, docs/python.md) with pytest, on the module in
# BUILD_DIR/python (default build/) and with the interpreter it was built for. Arguments go to pytest:
#   scripts/test_python.sh -k progress
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${BUILD_DIR:-$root/build}"
python="$(sed -n 's/^Python3_EXECUTABLE:[A-Z]*=//p' "$build/CMakeCache.txt")"
[ -n "$python" ] || { echo "test_python: $build was configured without the Python module" >&2; exit 1; }
cd "$root"
PYTHONDONTWRITEBYTECODE=1 PYTHONPATH="$build/python" UNIQUE3D_CLI="$build/unique3d" \
  UNIQUE3D_MAKE_TINY_MODELS="$build/tests/make_tiny_models" "$python" -m pytest -p no:cacheprovider "$root/tests/python" "$@"
