#!/usr/bin/env bash
# Builds the libFuzzer targets of fuzz/ with clang, ASan and UBSan into build-fuzz/ and runs each for
# SECONDS (default 30) from its seeds: the small ones committed in fuzz/corpus/<target>/, fixtures from
# tests/data and examples linked in by path, and what earlier runs found (build-fuzz/corpus/<target>/),
# with the keywords of fuzz/dict/<target>.dict.
# Exits non-zero when any target finds a crash, sanitizer report, leak, timeout or out-of-memory; the
# input that caused it is left in build-fuzz/artifacts/<target>/. Prints executions per second and
# coverage per target at the end.
#   scripts/fuzz.sh [SECONDS] [TARGET...]
#     targets: image obj mtl ply gltf config pickle zip safetensors onnx pth state_dict
# Environment: FUZZ_JOBS (build jobs, and targets run at once; default all cores); FUZZ_SEED (libFuzzer's
# -seed, so that a run from the same corpus repeats; scripts/test.sh sets it).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
seconds="${1:-30}"
[ $# -gt 0 ] && shift
all_targets=(image obj mtl ply gltf config pickle zip safetensors onnx pth state_dict)
targets=("$@")
[ ${#targets[@]} -eq 0 ] && targets=("${all_targets[@]}")

# Dependencies: the project's own, then clang with its sanitizer/libFuzzer runtimes and OpenMP, and python3
# (it takes the pickle seed out of a checkpoint).
bash scripts/install_deps.sh
missing=()
for p in clang libclang-rt-14-dev libomp-dev python3; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "[fuzz] apt packages: ${missing[*]}"
  SUDO=""
  if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update -qq
  $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

build=build-fuzz
if [ ! -f "$build/CMakeCache.txt" ]; then
  gen=()
  command -v ninja >/dev/null 2>&1 && gen=(-G Ninja)
  CC=clang CXX=clang++ cmake -S . -B "$build" "${gen[@]}" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DUNIQUE3D_FUZZ=ON \
    -DUNIQUE3D_WITH_TORCH=OFF -DUNIQUE3D_BUILD_TESTS=OFF -DUNIQUE3D_BUILD_BENCH=OFF
fi
cmake --build "$build" --parallel "${FUZZ_JOBS:-$(nproc)}" --target $(printf 'fuzz_%s ' "${targets[@]}")

# Seeds from the repository's fixtures, linked (not copied) into one folder per target.
seeds_from() {
  local target=$1
  shift
  local dir="$build/seeds/$target"
  rm -rf "$dir"
  mkdir -p "$dir"
  for f in "$@"; do
    [ -f "$f" ] && ln -s "$root/$f" "$dir/$(echo "$f" | tr / _)"
  done
  true
}
# (Images over 512 x 512 pixels are skipped by the image harnesses, fuzz_common.h, so the larger textures
# of the fixtures are no seeds.)
seeds_from image examples/spot/views/front_rgb.png examples/spot/views/front_normal.png \
  tests/data/nn/clip_vision/test_image_64x48.png
seeds_from obj examples/spot/spot.obj tests/data/objects/avocado/avocado.obj
seeds_from mtl examples/spot/spot.mtl tests/data/objects/avocado/avocado.mtl
seeds_from ply
seeds_from gltf
seeds_from config tests/data/nn/*/config.json tests/data/nn/*/*_config*.json tests/data/nn/scheduler/tolerances.json
seeds_from pickle
seeds_from zip tests/data/nn/unet_mv/weights.pth
seeds_from safetensors tests/data/nn/clip_text/inputs.safetensors tests/data/nn/clip_tokenizer/input_ids.safetensors \
  tests/data/nn/ip_adapter/inputs.safetensors
seeds_from onnx tests/data/nn/realesrgan_tiny/rrdbnet_tiny_op11.onnx
seeds_from pth
seeds_from state_dict fuzz/corpus/pickle/state_dict_p2.pkl fuzz/corpus/pickle/state_dict_p4.pkl
# The pickle of a real torch.save checkpoint, taken out of its zip.
python3 -c "import sys, zipfile; z = zipfile.ZipFile(sys.argv[1]); open(sys.argv[2], 'wb').write(z.read('weights/data.pkl'))" \
  tests/data/nn/unet_mv/weights.pth "$build/seeds/pickle/unet_mv_data.pkl"

# Longest input each target tries: large enough for the fixtures that matter, small enough to stay fast.
declare -A max_len=([image]=131072 [obj]=65536 [mtl]=4096 [ply]=16384 [gltf]=16384 [config]=16384 [pickle]=65536 [zip]=65536
  [safetensors]=16384 [onnx]=131072 [pth]=16384 [state_dict]=16384)

# One target: runs it and writes its summary line to $build/logs/<target>.summary ("FAILED" in it when
# libFuzzer found something).
fuzz_target() {
  local t=$1
  local corpus="$build/corpus/$t" artifacts="$build/artifacts/$t" log="$build/logs/$t.log"
  mkdir -p "$corpus" "$artifacts" "$(dirname "$log")"
  local dict=() seed=()
  [ -f "fuzz/dict/$t.dict" ] && dict=(-dict="fuzz/dict/$t.dict")
  [ -n "${FUZZ_SEED:-}" ] && seed=(-seed="$FUZZ_SEED")
  local rc=0
  "$build/fuzz/fuzz_$t" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -max_len="${max_len[$t]}" \
    "${dict[@]}" "${seed[@]}" -print_final_stats=1 -artifact_prefix="$artifacts/" "$corpus" "fuzz/corpus/$t" "$build/seeds/$t" \
    </dev/null >"$log" 2>&1 || rc=$?
  # libFuzzer's last status line: "#N DONE cov: C ft: F corp: ..."; its stats: execs and exec/s.
  local status cov ft execs rate result=ok
  status=$(grep -E '^#[0-9]+[[:space:]]+(DONE|pulse|NEW|REDUCE|INITED)' "$log" | tail -1 || true)
  cov=$(echo "$status" | grep -oE 'cov: [0-9]+' | cut -d' ' -f2 || true)
  ft=$(echo "$status" | grep -oE 'ft: [0-9]+' | cut -d' ' -f2 || true)
  execs=$(grep -E '^stat::number_of_executed_units:' "$log" | awk '{print $2}' || true)
  rate=$(grep -E '^stat::average_exec_per_sec:' "$log" | awk '{print $2}' || true)
  if [ $rc -ne 0 ]; then
    result="FAILED (exit $rc; see $log and $artifacts/)"
    grep -E '^==[0-9]+==ERROR|runtime error|^SUMMARY|deadly signal|Test unit written' "$log" | head -5 || true
  fi
  printf '%-8s %10s execs %7s exec/s  cov %6s  ft %7s  %s\n' "$t" "${execs:-?}" "${rate:-?}" "${cov:-?}" "${ft:-?}" \
    "$result" >"$build/logs/$t.summary"
}

# Each target is single-threaded: as many run at once as there are cores (FUZZ_JOBS).
jobs="${FUZZ_JOBS:-$(nproc)}"
for t in "${targets[@]}"; do
  while [ "$(jobs -rp | wc -l)" -ge "$jobs" ]; do wait -n || true; done
  echo "[fuzz] $t: ${seconds}s"
  rm -f "$build/logs/$t.summary"
  fuzz_target "$t" &
done
wait
failed=()
summary=()
for t in "${targets[@]}"; do
  line=$(cat "$build/logs/$t.summary" 2>/dev/null || echo "$t: no result (the harness did not finish)")
  summary+=("$line")
  [[ "$line" == *FAILED* || "$line" == *"no result"* ]] && failed+=("$t")
done

echo "[fuzz] ${seconds}s per target:"
printf '  %s\n' "${summary[@]}"
if [ ${#failed[@]} -gt 0 ]; then
  echo "[fuzz] findings in: ${failed[*]}"
  exit 1
fi
