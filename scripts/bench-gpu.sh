#!/usr/bin/env bash
# The GPU benchmark: every method on every built-in scene (methods with scene-only maps timed
# static and dynamic; each run's speed-up over the CPU reference and over gpu-trace), then
# gpu-trace's rays per second on the Stanford dragon beside the CPU reference's, then
# vertex-tracing's composition on the CPU against the GPU raster (truck-cover, the ID buffer
# drawn by the GPU, the cover by its vertices). Writes one JSON
# and one markdown file (adapter, driver, date) into the output folder.
#
#   scripts/bench-gpu.sh [--small] [--out DIR]
#
# Full size: 1920x1080, 3 timed frames after 2 warm-up frames: meant for a machine with a real
# GPU, where it takes a few minutes. --small: 160x90 and 1 timed frame, for lavapipe (and the
# test that runs this script).
#
# SPECULA   the binary to run. Default: built here with `cargo build --profile dist` (a
#           stripped release binary, target/dist/specula: the one to carry to a GPU machine
#           that cannot build; see docs/benchmarks.md).
# DRAGON    the dragon mesh, .obj or .obj.gz. Default: ../shared/meshes/dragon_res2.obj.gz
#           (202,520 triangles) when present, else scenes/meshes/dragon_res4.obj (11,102), said
#           loudly.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
size=(-W 1920 -H 1080)
frames=3
out=bench-gpu
while [ $# -gt 0 ]; do
  case "$1" in
    --small) size=(-W 160 -H 90); frames=1 ;;
    --out) out="$2"; shift ;;
    *) echo "usage: $0 [--small] [--out DIR]" >&2; exit 2 ;;
  esac
  shift
done
if [ -z "${SPECULA:-}" ]; then
  (cd "$root" && cargo build --profile dist --bin specula)
  SPECULA="$root/target/dist/specula"
fi
mkdir -p "$out"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

dragon="${DRAGON:-}"
if [ -z "$dragon" ]; then
  dragon="$root/../shared/meshes/dragon_res2.obj.gz"
  if [ ! -f "$dragon" ]; then
    echo "NOTE: $dragon is absent; measuring rays per second on the small dragon (dragon_res4, 11,102 triangles)" >&2
    dragon="$root/scenes/meshes/dragon_res4.obj"
  fi
fi
case "$dragon" in
  *.gz) gunzip -c "$dragon" > "$work/dragon.obj" ;;
  *) cp "$dragon" "$work/dragon.obj" ;;
esac
# A glass dragon on a checkered floor under a point light: closest-hit rays (primary,
# reflected, refracted) and shadow rays, counted alike.
cat > "$work/dragon.toml" <<TOML
name = "stanford-dragon"
ambient = 0.1
[camera]
eye = [0.0, 0.55, 1.4]
target = [0.0, 0.3, 0.0]
fov_y_deg = 40
[materials.floor]
type = "diffuse"
checker = { squares = 8, colors = [[0.8, 0.8, 0.8], [0.2, 0.25, 0.4]] }
[materials.glass]
type = "dielectric"
ior = 1.5
[[lights]]
type = "point"
position = [1.0, 2.0, 1.5]
intensity = 6.0
[[objects]]
name = "floor"
material = "floor"
shape = { type = "room", size = [4.0, 3.0, 4.0] }
[[objects]]
name = "dragon"
material = "glass"
translate = [0.0, 0.3, 0.0]
shape = { type = "mesh", file = "dragon.obj", fit = 0.9 }
TOML

export NODEVICE_SELECT=1
mapfile -t scenes < <("$SPECULA" scenes | awk '/^[^ ]/ {print $1}')
echo "every method on ${#scenes[@]} built-in scenes at ${size[1]}x${size[3]}, $frames timed frames" >&2
"$SPECULA" bench "${scenes[@]}" --frames "$frames" "${size[@]}" \
  --json "$work/scenes.json" --markdown "$work/scenes.md"
echo "gpu-trace rays per second on the dragon ($(grep -c '^f ' "$work/dragon.obj") triangles)" >&2
"$SPECULA" bench "$work/dragon.toml" --methods gpu-trace --frames "$frames" "${size[@]}" \
  --json "$work/dragon.json" --markdown "$work/dragon.md"
for composition in cpu gpu; do
  echo "vertex-tracing composed on the $composition (truck-cover)" >&2
  "$SPECULA" bench truck-cover --methods vertex-tracing --frames "$frames" "${size[@]}" \
    -p composition=$composition -p visibility=gpu -p tracing=vertices \
    --json "$work/composition-$composition.json" --markdown "$work/composition-$composition.md"
done

printf '{\n"scenes": %s,\n"dragon": %s,\n"composition_cpu": %s,\n"composition_gpu": %s\n}\n' \
  "$(cat "$work/scenes.json")" "$(cat "$work/dragon.json")" \
  "$(cat "$work/composition-cpu.json")" "$(cat "$work/composition-gpu.json")" \
  > "$out/bench-gpu.json"
{
  echo "# specula bench-gpu ($(date -u +%Y-%m-%d))"
  echo
  echo "## Every method on every built-in scene"
  echo
  cat "$work/scenes.md"
  echo
  echo "## gpu-trace rays per second on the Stanford dragon ($(grep -c '^f ' "$work/dragon.obj") triangles)"
  echo
  cat "$work/dragon.md"
  echo
  echo "## vertex-tracing: composition on the CPU, then on the GPU raster (truck-cover)"
  echo
  cat "$work/composition-cpu.md"
  echo
  cat "$work/composition-gpu.md"
} > "$out/bench-gpu.md"
echo "wrote $out/bench-gpu.json and $out/bench-gpu.md" >&2
