#!/usr/bin/env bash
# Wyman's Table 1 analogue: frame times of image-space beside envmap, distance-maps and
# gpu-trace on a sphere, the bunny and the dragon as refractors, alone and with nearby geometry
# (scenes/table1), at 512² and 1024²; bench times the methods with scene-only maps both static
# and redrawn every frame (dynamic, as a moving scene needs), and both exact methods. One bench
# run per size: ratios within a run are what to compare. Writes table1-SIZE.json and .md into
# --out (default table1-report).
#   scripts/table1.sh [--out DIR] [--frames N]
set -euo pipefail
cd "$(dirname "$0")/.."
out=table1-report
frames=5
while [ $# -gt 0 ]; do
    case "$1" in
        --out) out="$2"; shift 2 ;;
        --frames) frames="$2"; shift 2 ;;
        *) echo "usage: scripts/table1.sh [--out DIR] [--frames N]" >&2; exit 2 ;;
    esac
done
mkdir -p "$out"
specula="${SPECULA:-}"
if [ -z "$specula" ]; then
    cargo build --release --bin specula
    specula=target/release/specula
fi
export NODEVICE_SELECT=1
for size in 512 1024; do
    "$specula" bench scenes/table1/*.toml \
        --methods image-space,envmap,distance-maps,gpu-trace \
        --frames "$frames" -W "$size" -H "$size" \
        --json "$out/table1-$size.json" --markdown "$out/table1-$size.md"
done
