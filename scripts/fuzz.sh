#!/usr/bin/env bash
# Coverage-guided fuzzing of every scene loader with cargo-fuzz (libFuzzer, nightly toolchain):
# glTF/GLB, OBJ, PLY, STL, STEP and TOML scene files, each for SECONDS (default 600), seeded with the
# meshes in ../shared/meshes and scenes/ and, where installed, the assimp-testmodels corpus.
# A run fails on a panic, a hang over 10 s or an allocation over 2 GB; the input that caused it
# is written to fuzz/artifacts/TARGET/ (make it a regression test in
# crates/specula-scene/tests/fuzz_regressions.rs). Logs go to fuzz/logs/TARGET.log.
#   scripts/fuzz.sh [SECONDS] [TARGET...]
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-600}
[ $# -gt 0 ] && shift
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(gltf obj ply stl step toml_scene)
command -v cargo-fuzz >/dev/null || cargo install cargo-fuzz --locked
shared=../shared/meshes
assimp=/usr/share/assimp/models
mkdir -p fuzz/logs
failed=()
for target in "${targets[@]}"; do
  corpus=fuzz/corpus/$target
  mkdir -p "$corpus"
  case $target in
    gltf) seeds=$(find "$assimp/glTF2" \( -name '*.gltf' -o -name '*.glb' \) 2>/dev/null || true) ;;
    obj) seeds="$(ls "$shared"/*.obj scenes/meshes/*.obj 2>/dev/null || true) $(find "$assimp/OBJ" -name '*.obj' 2>/dev/null || true)" ;;
    ply) seeds=$(find "$assimp/PLY" -name '*.ply' 2>/dev/null || true) ;;
    stl) seeds=$(find "$assimp/STL" -name '*.stl' 2>/dev/null || true) ;;
    step) seeds="$(ls scenes/cad/*.step crates/specula-scene/tests/data/step/*.step)" ;;
    toml_scene) seeds=scenes/example.toml ;;
    *) echo "unknown target $target" >&2; exit 2 ;;
  esac
  for seed in $seeds; do
    cp "$seed" "$corpus/seed-$(echo "$seed" | md5sum | cut -c1-8)-$(basename "$seed")"
  done
  echo "== $target: $(ls "$corpus" | wc -l) inputs in the corpus, $seconds s"
  cargo +nightly fuzz run "$target" "$corpus" -- \
    -max_total_time="$seconds" -rss_limit_mb=2048 -malloc_limit_mb=2048 -timeout=10 \
    -max_len=262144 -print_final_stats=1 > "fuzz/logs/$target.log" 2>&1 || {
      echo "$target: FOUND A FAILURE, see fuzz/logs/$target.log and fuzz/artifacts/$target/"
      grep -E "panicked|ERROR|SUMMARY|Test unit written" "fuzz/logs/$target.log" | head -5
      failed+=("$target")
      continue
    }
  grep -E "stat::number_of_executed_units|stat::peak_rss_mb|cov:" "fuzz/logs/$target.log" | tail -3
done
if [ ${#failed[@]} -gt 0 ]; then
  echo "failures in: ${failed[*]}"
  exit 1
fi
