#!/usr/bin/env bash
# Viewer frame rates per method, on a virtual X display (Xvfb) with whatever Vulkan adapter is
# found (lavapipe on a machine without a GPU): for each method, 20 still frames at full
# resolution (the technique rendered every frame) and a 40-frame orbit drag at the viewer's
# reduced interaction resolution (half the window's side). Prints one line per step.
#   scripts/bench-viewer.sh [SCENE] [WIDTHxHEIGHT] [METHODS...]
# SPECULA_INTERACTION_SCALE (default 0.5) sets the drag's resolution fraction; SPECULA_PARAMS
# (e.g. "resolution=128") are NAME=VALUE settings applied to every listed method as script
# `param` steps, so give only parameters each of them has.
set -euo pipefail
cd "$(dirname "$0")/.."
scene=${1:-door-mirror}
size=${2:-640x480}
shift $(( $# > 2 ? 2 : $# ))
methods=("$@")
[ ${#methods[@]} -gt 0 ] || methods=(reference envmap pvrr distance-maps)
cargo build --release --bin specula
script=$(mktemp --suffix .toml)
trap 'rm -f "$script"' EXIT
for m in "${methods[@]}"; do
  printf '[[step]]\nmethod = "%s"\n' "$m" >> "$script"
  for p in ${SPECULA_PARAMS:-}; do printf '[[step]]\nparam = "%s"\n' "$p" >> "$script"; done
  printf '[[step]]\nframes = 3\n[[step]]\nframes = 20\n[[step]]\ndrag = [90, 0, 40]\n' >> "$script"
done
export NODEVICE_SELECT=1
xvfb-run -a -s "-screen 0 1920x1080x24" target/release/specula view "$scene" --size "$size" \
  --interaction-scale "${SPECULA_INTERACTION_SCALE:-0.5}" --script "$script" 2>&1 \
  | grep -E '^step [0-9]+: [0-9]+ frames' | grep -v ': 3 frames'
