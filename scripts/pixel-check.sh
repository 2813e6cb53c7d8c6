#!/usr/bin/env bash
# Holds a refactoring to "no pixel changes": renders every method (and each preset) on every
# built-in and suite scene at 160 × 120 as OpenEXR (linear f32), and compares two such folders
# byte for byte, printing the PSNR of any image that differs (ImageMagick's `compare`).
#
#   scripts/pixel-check.sh render DIR        # with target/release/specula (built first)
#   scripts/pixel-check.sh diff BEFORE AFTER # exits 1 if any image differs
#
# Run `render` at the commit a change starts from and again after it, then `diff` the two.
set -euo pipefail
cd "$(dirname "$0")/.."
export NODEVICE_SELECT=1

render() {
  local out="$1"
  mkdir -p "$out"
  cargo build --release --bin specula --quiet
  local specula=target/release/specula
  local scenes labels
  scenes="$($specula scenes | awk '/^[^ ]/ {print $1}') $(ls scenes/suite/*.toml)"
  # Each method, and each of its presets, as `specula methods` lists them.
  labels="$($specula methods | sed -n 's/^\([a-z0-9-]*\) (.*/\1/p')"
  labels="$labels $($specula methods | sed -n 's/^  preset \([a-z0-9-]*:[a-z0-9-]*\):.*/\1/p')"
  for scene in $scenes; do
    local name
    name="$(basename "$scene" .toml)"
    for label in $labels; do
      local file="$out/${name}__${label//:/_}"
      if ! $specula render "$scene" --method "$label" -W 160 -H 120 -o "$file.png" --exr "$file.exr" \
        2> "$file.log"; then
        echo "$name $label: failed (see $file.log)"
      fi
    done
  done
  ls "$out"/*.exr | wc -l
}

diff_dirs() {
  local before="$1" after="$2" differ=0 same=0
  for a in "$before"/*.exr; do
    local b="$after/$(basename "$a")"
    if [ ! -f "$b" ]; then
      echo "missing after: $(basename "$a")"
      differ=$((differ + 1))
    elif cmp -s "$a" "$b"; then
      same=$((same + 1))
    else
      differ=$((differ + 1))
      # PSNR by ImageMagick's compare where installed (apt-get install imagemagick).
      local psnr="install imagemagick for its PSNR"
      if command -v compare >/dev/null; then
        psnr="PSNR $(compare -metric PSNR "$a" "$b" null: 2>&1 || true) dB"
      fi
      echo "differs: $(basename "$a") ($psnr)"
    fi
  done
  echo "$same identical, $differ differ"
  [ "$differ" -eq 0 ]
}

case "${1:-}" in
  render) render "$2" ;;
  diff) diff_dirs "$2" "$3" ;;
  *) echo "usage: $0 render DIR | diff BEFORE AFTER" >&2; exit 2 ;;
esac
