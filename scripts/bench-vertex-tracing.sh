#!/usr/bin/env bash
# Vertex tracing against the CPU reference, frame by frame in one run (`specula bench`: warm-up,
# then the median of N frames of each), on every scene of the suite and on two dense meshes (the
# suite's flat-shaded mirror bunny, and bench/glass-dragon: 202,520 triangles of glass), at
# 320 x 240 and 1024 x 768. Prints one table per size: the frame medians, their ratio, and what
# vertex tracing chose for each reflector (V: by vertices, P: per pixel). Usage:
#   scripts/bench-vertex-tracing.sh [FRAMES]          (default 9)
# The CPU path is timed: no Vulkan driver is loaded (on a software rasterizer the ID buffer is
# traced anyway, and gpu-trace would only add minutes); scripts/bench-gpu.sh times GPUs.
set -euo pipefail
cd "$(dirname "$0")/.."
frames=${1:-9}
cargo build --release --bin specula -q
out=target/bench-vertex-tracing
mkdir -p "$out"
scenes=(scenes/suite/*.toml scenes/bench/glass-dragon.toml)
for size in 320x240 1024x768; do
  w=${size%x*}; h=${size#*x}
  VK_ICD_FILENAMES=/nonexistent NODEVICE_SELECT=1 target/release/specula bench "${scenes[@]}" \
    --methods vertex-tracing -W "$w" -H "$h" --frames "$frames" --json "$out/$size.json" >"$out/$size.log" 2>&1
  python3 - "$out/$size.json" "$size" <<'PY'
import json, statistics, sys
runs = json.load(open(sys.argv[1]))["runs"]
print(f"\n### {sys.argv[2]}, median of the frames, one run\n")
print("| scene | reference ms | vertex-tracing ms | ratio (vt / ref) | reflectors: choice (seen vertices / pixels, rays per path) |")
print("|---|---|---|---|---|")
ratios = []
for run in runs:
    if run["label"] != "vertex-tracing":
        continue
    ref = next(r for r in runs if r["scene"] == run["scene"] and r["label"] == "reference")
    vt, rm = run["frame"]["median_ms"], ref["frame"]["median_ms"]
    ratios.append(vt / rm)
    counters = dict(run["counters"])
    names = [n[len("reflector "):-len(": pixels")] for n in counters if n.startswith("reflector ") and n.endswith(": pixels")]
    notes = []
    for name in names:
        c = lambda what: next(v for n, v in counters.items() if n.startswith(f"reflector {name}: {what}"))
        choice = "P" if c("traced per pixel") else "V"
        rays = c("rays per pixel path") / 100
        notes.append(f"{name}: {choice} ({c('vertices')}/{c('pixels')}" + (f", {rays:.1f}" if rays else "") + ")")
    print(f"| {run['scene']} | {rm:.1f} | {vt:.1f} | {vt / rm:.2f} | {'; '.join(notes)} |")
print(f"\nmedian ratio over the scenes: {statistics.median(ratios):.2f}; worst {max(ratios):.2f}")
PY
done
