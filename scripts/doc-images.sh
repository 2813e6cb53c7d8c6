#!/usr/bin/env bash
# Regenerates the analysis plots in docs/images from the commands docs/analyses/*.md names
# (release build). The two Tscherning maps come from a test's lenses, not a command: they are
# left as they are.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release -q -p specula-cli
specula=target/release/specula
export NODEVICE_SELECT=1
out=$(mktemp -d -t specula-doc-images.XXXXXX)
trap 'rm -rf "$out"' EXIT
images=docs/images
run() { # NAME then the command's arguments: writes the report to $out/NAME
  local name=$1
  shift
  echo "doc-images: $name"
  "$specula" analyze "$@" --report "$out/$name" > /dev/null
}
take() { # REPORT PLOT IMAGE
  cp "$out/$1/$2.png" "$images/$3.png"
}

run door-mirror mirror-view door-mirror --mirror "door mirror" --ocular --region=-4,2,4,30
take door-mirror ground analyze-door-mirror-ground
take door-mirror mirror analyze-door-mirror-mirror

run truck-cover glare truck-cover --surface "cover glass" --source "side window" \
  --source-luminance 8000 --eyebox 0.2,0.1,5,3 --display dial --symbol-luminance 300 \
  --background-luminance 10 --min-contrast 3
take truck-cover eyebox analyze-truck-cover-eyebox
take truck-cover worst analyze-truck-cover-worst
for heading in 0 270; do
  run "sun-$heading" glare truck-cover --surface "cover glass" --sun-sweep -180,180,5,85,5 \
    --eyebox 0.2,0.1,5,3 --display dial --symbol-luminance 300 --background-luminance 10 \
    --min-contrast 3 --latitude 48 --heading "$heading" --date 2026-06-21
done
take sun-0 sweep analyze-truck-cover-sun-sweep
take sun-0 polar analyze-truck-cover-sun-polar-north
take sun-270 polar analyze-truck-cover-sun-polar-west

run builtin lens spectacle-lens --lens "spectacle lens"
for map in mean-power cylinder prism distortion; do take builtin "$map" "analyze-lens-builtin-$map"; done
run toric lens scenes/spectacles.toml --lens "right lens"
for map in cylinder unwanted-cylinder distortion; do take toric "$map" "analyze-lens-toric-$map"; done
run wrap lens scenes/spectacles-wrap.toml --lens "right lens" --pantoscopic 10 --wrap 5 \
  --compensate --standard iso-8980-1 --focimeter
for map in cylinder unwanted-cylinder; do take wrap "$map" "analyze-lens-wrap-$map"; done
run wrap-plain lens scenes/spectacles-wrap.toml --lens "right lens" --pantoscopic 10 --wrap 5
take wrap-plain lens-cylinder analyze-lens-wrap-clear-zones
run progressive lens scenes/progressive.toml --lens "right lens" --standard ansi-z80.1 \
  --near 0.4 --focimeter
take progressive lens-mean-power analyze-lens-progressive-mean-power
take progressive lens-cylinder analyze-lens-progressive-unwanted-cylinder
echo "doc-images: done ($images)"
