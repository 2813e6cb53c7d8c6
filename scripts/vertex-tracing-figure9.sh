#!/usr/bin/env bash
# Ullmann et al.'s Figure 9 for vertex-tracing: distributed frames of truck-cover at 1024 × 768
# measured with 1, 2 and 3 MPI ranks on this machine (the refinement phase's speed-up and
# imbalance), then the discrete-event simulation checked against them and extended to 1–32
# workers (cargo bench --bench vertex_tracing_figure9): tables on stdout, chart in
# DIR/figure9.svg, the MPI reports in DIR/ranks-N.json.
#   scripts/vertex-tracing-figure9.sh [--out DIR] [--frames N] [--size WxH]
# Each rank runs one rayon thread (RAYON_NUM_THREADS=1), so three ranks on two cores leave
# the master, which mostly waits, sleeping between polls.
set -euo pipefail
cd "$(dirname "$0")/.."
out=target/figure9
frames=4
size=(-W 1024 -H 768)
while [ $# -gt 0 ]; do
    case "$1" in
        --out) out="$2"; shift 2 ;;
        --frames) frames="$2"; shift 2 ;;
        --size) size=(-W "${2%x*}" -H "${2#*x}"); shift 2 ;;
        *) echo "usage: $0 [--out DIR] [--frames N] [--size WxH]" >&2; exit 2 ;;
    esac
done
mkdir -p "$out"
out="$(cd "$out" && pwd)"
cargo build --release --features mpi --bin specula
root=()
[ "$(id -u)" -eq 0 ] && root=(--allow-run-as-root)
for ranks in 1 2 3; do
    mpirun "${root[@]}" --oversubscribe --enable-recovery --mca mpi_yield_when_idle 1 \
        -np "$ranks" -x RAYON_NUM_THREADS=1 \
        target/release/specula render truck-cover --method vertex-tracing -p tracing=vertices "${size[@]}" \
        --distributed --frames "$frames" -o "$out/ranks-$ranks.png" --report "$out/ranks-$ranks.json"
done
cargo bench -p specula-compare --bench vertex_tracing_figure9 -- "$out"
