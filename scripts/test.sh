#!/usr/bin/env bash
# Runs the whole test suite (after installing system packages if needed).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
# Mesa prints a harmless "XDG_RUNTIME_DIR is invalid" line per device without this.
export NODEVICE_SELECT=1
# With MPI: the distributed vertex-tracing tests run mpirun on loopback.
cargo test --workspace --features specula-cli/mpi "$@"
