#!/usr/bin/env bash
# Regenerates the analysis plots in docs/images from the commands docs/analyses/*.md names
# (release build), and the two Tscherning maps from two scenes written here with the lenses of
# crates/specula-analyze/tests/lens.rs's Tscherning test (base 0 and +5 D).
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
# Tscherning: a −4 D lens (n 1.523, t 2 mm, 60 mm), its back vertex 12 mm before the eye, the
# centre of rotation 27 mm behind the back vertex; front base curve 0 and +5 D.
for base in 0 5; do
  cat > "$out/tscherning-$base.toml" <<TOML
name = "Tscherning: -4.00 D, front base $base D"
[camera]
eye = [0.0, 0.0, 0.0]
target = [0.0, 0.0, -1.0]
fov_y_deg = 60
[[objects]]
name = "lens"
translate = [0.0, 0.0, -0.014]
shape = { type = "spectacle-lens", sphere = -4.0, cylinder = 0.0, axis = 0, index = 1.523, abbe = 58, center_thickness = 0.002, base_curve = $base.0, diameter = 0.06 }
TOML
  run "tscherning-$base" lens "$out/tscherning-$base.toml" --lens lens --rotation-centre 0,0,0.015
  take "tscherning-$base" cylinder "analyze-lens-tscherning-base$base-cylinder"
done
echo "doc-images: done ($images)"
