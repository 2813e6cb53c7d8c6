#!/usr/bin/env bash
# Mei, Popescu and Sacks' Tables 1 and 2 for c3rc: the 4,096-triangle Utah teapot reflecting
# the Stanford bunny (147k and 37k points) and dragon (437k and 100k points), scenes/c3rc. For
# each row one `specula bench` run of c3rc at 640 × 480; from its JSON (stage medians and the
# last frame's counters) one markdown table of both: kd-tree construction (points, build time,
# mean leaf depth, points per leaf) and rendering (culling, projection with the splats'
# resolve, as the paper's projection includes rasterising the points, their total, share of
# valid projections), beside the paper's figures. Writes c3rc-tables.md and the JSON into
# --out (default c3rc-tables-report). `--method c3rc:paper` times the published algorithm (the
# paper preset: every step beyond the paper off) instead of c3rc's defaults. Needs python3.
#   scripts/c3rc-tables.sh [--out DIR] [--frames N] [--method LABEL] [-- extra bench arguments]
set -euo pipefail
cd "$(dirname "$0")/.."
out=c3rc-tables-report
frames=10
method=c3rc
extra=()
while [ $# -gt 0 ]; do
    case "$1" in
        --out) out="$2"; shift 2 ;;
        --frames) frames="$2"; shift 2 ;;
        --method) method="$2"; shift 2 ;;
        --) shift; extra=("$@"); break ;;
        *) echo "usage: scripts/c3rc-tables.sh [--out DIR] [--frames N] [--method LABEL] [-- bench args]" >&2; exit 2 ;;
    esac
done
mkdir -p "$out"
specula="${SPECULA:-}"
if [ -z "$specula" ]; then
    cargo build --release --bin specula
    specula=target/release/specula
fi
export NODEVICE_SELECT=1
# row name, scene, points, paper: points x1000, construction ms, depth, per leaf, total ms,
# culling ms, projection ms, valid %
rows=(
    "Dragon0 teapot-dragon 437000 437 533 7.2 121 588 273 315 20"
    "Bunny0 teapot-bunny 147000 147 190 6.1 121 264 136 128 19"
    "Dragon1 teapot-dragon 100000 100 95 5.7 122 250 134 116 20"
    "Bunny1 teapot-bunny 37000 37 25 4.7 121 121 63 58 19"
)
for row in "${rows[@]}"; do
    read -r name scene points _ <<< "$row"
    "$specula" bench "scenes/c3rc/$scene.toml" --methods "$method" --frames "$frames" \
        -W 640 -H 480 -p "points=$points" ${extra[@]+"${extra[@]}"} \
        --json "$out/$name.json" > "$out/$name.txt"
done
python3 - "$out" "$method" "${rows[@]}" <<'PY'
import json, sys
out, label, rows = sys.argv[1], sys.argv[2], sys.argv[3:]
lines = [
    "| scene | points ×1000 | tree build ms | mean leaf depth | points per leaf | culling ms | projection and splatting ms | total ms | valid projections % | pixels without a camera ms | total with them ms | paper: points, build ms, depth, per leaf | paper: total, culling, projection ms, valid % | speed-up over the paper: total, with them |",
    "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
]
for row in rows:
    name, scene, points, pk, pbuild, pdepth, pleaf, ptotal, pcull, pproj, pvalid = row.split()
    run = next(r for r in json.load(open(f"{out}/{name}.json"))["runs"]
               if r["label"] == label and r["mode"] == "static")
    c = dict(run["counters"])
    stage = dict((n, s["median_ms"]) for n, s in run["stages"])
    cull, proj = stage["culling (backward phase)"], stage["projection (forward phase)"]
    # The paper's projection includes rasterising the points: here, resolving the splats.
    proj += stage["splatting (resolve, holes)"]
    # Small triangles' per-vertex colour and self-seeing triangles' traced pixels: work the
    # paper's cameras did for those triangles.
    without = stage.get("pixels without a camera (per-vertex, traced)", 0.0)
    leaves = c["kd-tree leaves"]
    # Of the points the leaves hold that were not left out by the level of detail.
    considered = c["points in leaves seen"] - c.get("points skipped by level of detail", 0)
    valid = 100.0 * c["valid projections"] / max(considered, 1)
    lines.append(
        f"| {name} ({scene}) | {c['points'] / 1000:.0f} | {c['kd-tree build us'] / 1000:.1f} "
        f"| {c['kd-tree mean leaf depth (hundredths)'] / 100:.2f} | {c['points'] / leaves:.0f} "
        f"| {cull:.1f} | {proj:.1f} | {cull + proj:.1f} | {valid:.0f} "
        f"| {without:.1f} | {cull + proj + without:.1f} "
        f"| {pk}k, {pbuild}, {pdepth}, {pleaf} | {ptotal}, {pcull}, {pproj}, {pvalid} "
        f"| {float(ptotal) / (cull + proj):.1f}×, {float(ptotal) / (cull + proj + without):.1f}× |")
open(f"{out}/c3rc-tables.md", "w").write("\n".join(lines) + "\n")
print("\n".join(lines))
PY
