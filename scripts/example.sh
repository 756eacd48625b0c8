#!/usr/bin/env bash
# Installs dependencies, builds, and runs unique3d on the bundled example (examples/).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
bash scripts/build.sh --target unique3d
out="${1:-out/example}"
mkdir -p "$out"
# The bundled example: four 512 px views of Spot (CC0) rendered by `unique3d render` from examples/spot/spot.obj.
./build/unique3d reconstruct examples/spot/views -o "$out/spot.glb" --preview
echo
echo "Reconstructed mesh: $out/spot.glb (opens in Blender / three.js)"
echo "Previews:           $out/spot_views.png (four views) and $out/spot_turntable.png"
