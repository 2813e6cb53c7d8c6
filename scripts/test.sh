#!/usr/bin/env bash
# Runs the whole test suite (after installing system packages if needed).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
cargo test --workspace "$@"
