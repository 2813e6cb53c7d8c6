#!/usr/bin/env bash
# Measures every method on the scene suite and on the built-in scenes (accuracy against the
# exact reference, warm frame times) and the ray kernel against Intel Embree, keeps the runs as
# JSON in docs/figures/runs, and writes docs/benchmarks.md's generated tables and the README's
# measured columns from them (scripts/figures.py). Run on a quiet machine: it times things.
#
#   scripts/figures.sh              measure, then write the tables
#   scripts/figures.sh --tables     write the tables from the runs already kept
#   scripts/figures.sh --no-embree  measure without the Embree run (it installs embreex from PyPI)
#
# A second run changes nothing in the tables but the times: every figure but a time comes from
# deterministic renders.
set -euo pipefail
cd "$(dirname "$0")/.."
runs=docs/figures/runs
measure=1
embree=1
for arg in "$@"; do
  case "$arg" in
    --tables) measure=0 ;;
    --no-embree) embree=0 ;;
    *) echo "usage: $0 [--tables] [--no-embree]" >&2; exit 2 ;;
  esac
done
if [ "$measure" = 1 ]; then
  cargo build --release -q -p specula-cli
  export NODEVICE_SELECT=1
  mkdir -p "$runs"
  work=$(mktemp -d -t specula-figures.XXXXXX)
  trap 'rm -rf "$work"' EXIT
  methods=gpu-trace,envmap,pvrr,distance-maps,image-space,c3rc,vertex-tracing
  builtins=$(target/release/specula scenes | awk '/^[^ ]/ {print $1}' | paste -sd' ')
  suite="specula compare scenes/suite --methods $methods -W 320 -H 240 --json $runs/suite.json"
  scenes="specula compare $builtins --methods $methods -W 320 -H 240 --json $runs/builtins.json"
  echo "figures: $suite"
  # shellcheck disable=SC2086 # the command lines split into their words on purpose
  target/release/$suite --report "$work/suite" > /dev/null
  echo "figures: $scenes"
  # shellcheck disable=SC2086
  target/release/$scenes --report "$work/builtins" > /dev/null
  embree_command="scripts/bench-bvh.sh"
  if [ "$embree" = 1 ]; then
    echo "figures: $embree_command"
    scripts/bench-bvh.sh > "$runs/embree.txt"
  fi
  # The commit of what was measured: the last to change the code, the scenes or the scripts
  # (committing the runs and the tables does not change it).
  measured=(crates scenes scripts Cargo.toml Cargo.lock)
  commit=$(git log -1 --format=%h --abbrev=10 -- "${measured[@]}")
  git diff --quiet HEAD -- "${measured[@]}" || commit="$commit with uncommitted changes"
  cpu=$(lscpu | sed -n 's/^Model name: *//p' | head -1)
  memory=$(awk '/MemTotal/ {printf "%.0f GiB", $2 / 1048576}' /proc/meminfo)
  python3 - "$runs/meta.json" "$commit" "$cpu, $(nproc) cores, $memory" "$suite" "$scenes" \
    "$embree_command" <<'PY'
import json, sys
path, commit, machine, suite, builtins, embree = sys.argv[1:]
json.dump({"commit": commit, "machine": machine,
           "commands": {"suite": suite, "builtins": builtins, "embree": embree}},
          open(path, "w"), indent=1)
PY
fi
python3 scripts/figures.py
