#!/usr/bin/env bash
# Installs the system packages specula needs, once (idempotent: installed packages are skipped).
#   g++                  C++ compiler for nv-flip (FLIP image metric, used by the tests)
#   mesa-vulkan-drivers  lavapipe, the CPU Vulkan driver wgpu uses on machines without a GPU
#   libvulkan1           the Vulkan loader
#   xvfb xauth           a virtual X display for `specula view` in tests (xvfb-run needs xauth,
#                        which is only a recommendation of xvfb, so name it)
#   libxkbcommon-x11-0 libxcursor1 libxrandr2 libxi6 libx11-xcb1
#                        the X11 libraries winit loads at run time for the viewer's window
#   assimp-testmodels    a public corpus of real and malformed model files the loader tests run
#   openmpi-bin libopenmpi-dev libclang-dev
#                        OpenMPI (mpirun, mpicc, headers) and libclang for the `mpi` crate's
#                        bindings: distributed vertex tracing (specula-cli's `mpi` feature)
#   chromium             headless Chromium, which opens the HTML reports in the browser tests
#
# A requirement that SPECULA_ALLOW_SKIP names (gpu, xvfb, mpi, corpus, browser) is not installed: the
# tests that need it are skipped, and counted, instead (scripts/test.sh). The list is read by
# the testkit's rule (scripts/allow-skip.sh).
set -euo pipefail
# shellcheck source=allow-skip.sh
source "$(dirname "$0")/allow-skip.sh"
allowed() { specula_allowed "$1"; }
packages=(g++)
allowed gpu || packages+=(mesa-vulkan-drivers libvulkan1)
allowed xvfb || packages+=(xvfb xauth libxkbcommon-x11-0 libxcursor1 libxrandr2 libxi6 libx11-xcb1)
allowed corpus || packages+=(assimp-testmodels)
allowed mpi || packages+=(openmpi-bin libopenmpi-dev libclang-dev)
allowed browser || packages+=(chromium)
missing=()
for p in "${packages[@]}"; do
  dpkg -s "$p" >/dev/null 2>&1 || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  exit 0
fi
echo "setup: installing ${missing[*]}"
sudo_cmd=()
[ "$(id -u)" -eq 0 ] || sudo_cmd=(sudo)
export DEBIAN_FRONTEND=noninteractive
"${sudo_cmd[@]}" apt-get update -qq
"${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
