#!/usr/bin/env bash
# Primary-ray throughput of specula's BVH against Intel Embree (PyPI `embreex`) on the same
# rays, in one run on one machine: ../shared/bench/embree_rays.py, then `cargo bench --bench bvh`.
# Prints both, their hit counts (a checksum) and the single-thread ratio.
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
