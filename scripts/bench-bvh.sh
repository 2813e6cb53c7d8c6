#!/usr/bin/env bash
# Primary-ray throughput of specula's BVH against Intel Embree (PyPI `embreex`) on the same
# rays, in one run on one machine: ../shared/bench/embree_rays.py, then `cargo bench --bench bvh`.
# Prints both, their hit counts (a checksum) and the single-thread ratio; then a whole frame of
# the same rays through `specula render` against the kernel, and each whole process.
set -euo pipefail
cd "$(dirname "$0")/.."
mesh=../shared/meshes/dragon_res2.obj.gz
if [ ! -f "$mesh" ]; then
  echo "!!! $mesh is absent: cannot benchmark" >&2
  exit 1
fi
venv=.venv-embree
if [ ! -x "$venv/bin/python" ]; then
  python3 -m venv "$venv"
  "$venv/bin/pip" install -q embreex numpy
fi
embree=$("$venv/bin/python" ../shared/bench/embree_rays.py "$mesh" --size 1024 --repeat 5)
echo "$embree"
ours=$(cargo bench -p specula-trace --bench bvh 2>&1 | grep -vE '^\s*(Compiling|Finished|Running|Benchmarking|Warning|Found|Analyzing)|outlier|^\s*$|change:|Performance|No change|within noise|%\]')
echo "$ours"
embree_rate=$(echo "$embree" | sed -n 's/.*median \([0-9.]*\) Mrays\/s.*/\1/p')
ours_rate=$(echo "$ours" | grep -A2 'primary_rays/single_thread' | sed -n 's/.*thrpt: *\[[0-9.]* Melem\/s \([0-9.]*\) Melem\/s.*/\1/p' | head -1)
echo "single-thread ratio specula / Embree: $(python3 -c "print(f'{$ours_rate / $embree_rate:.2f}')") ($ours_rate / $embree_rate Mrays/s)"
warm_frame_rate=$(echo "$ours" | grep -A2 'reference_frame/single_thread' | sed -n 's/.*thrpt: *\[[0-9.]* Melem\/s \([0-9.]*\) Melem\/s.*/\1/p' | head -1)
echo "a warm reference frame of the same rays (criterion, 1 thread): $warm_frame_rate Mrays/s; frame / kernel time: $(python3 -c "print(f'{$ours_rate / $warm_frame_rate:.2f}')")"

# A whole frame of the same rays through `specula render` (unlit dragon, the benchmark's camera),
# one thread, against the kernel's time for them; and each whole process (load, build, trace,
# write) against Embree's script run once, all in this run.
cargo build --release -q -p specula-cli
frame_ms=() ; specula_s=() ; embree_s=()
for _ in 1 2 3; do
  start=$(date +%s.%N)
  line=$(RAYON_NUM_THREADS=1 target/release/specula render scenes/bench/dragon-unlit.toml -W 1024 -H 1024 -o /tmp/specula-bench-dragon.png 2>&1 | tail -1)
  end=$(date +%s.%N)
  frame_ms+=("$(echo "$line" | sed -n 's/.*reference 1024x1024 in \([0-9.]*\) ms.*/\1/p')")
  specula_s+=("$(python3 -c "print($end - $start)")")
  start=$(date +%s.%N)
  "$venv/bin/python" ../shared/bench/embree_rays.py "$mesh" --size 1024 --repeat 1 > /dev/null
  end=$(date +%s.%N)
  embree_s+=("$(python3 -c "print($end - $start)")")
done
median() { printf '%s\n' "$@" | sort -g | sed -n 2p; }
frame=$(median "${frame_ms[@]}")
kernel_ms=$(python3 -c "print(1048576 / ($ours_rate * 1e6) * 1e3)")
echo "a cold frame in specula render (1 thread, its first and only): median ${frame} ms of ${frame_ms[*]}; the kernel on the same rays: $(python3 -c "print(f'{$kernel_ms:.1f}')") ms; frame / kernel: $(python3 -c "print(f'{$frame / $kernel_ms:.2f}')")"
echo "whole process (load, build, trace, write; median of 3): specula $(median "${specula_s[@]}") s, Embree's script $(median "${embree_s[@]}") s; Embree / specula: $(python3 -c "print(f'{$(median "${embree_s[@]}") / $(median "${specula_s[@]}"):.2f}')")"
