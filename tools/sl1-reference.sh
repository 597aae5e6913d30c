#!/usr/bin/env bash
# Makes the SL1 reference layer the resin tests compare against: PrusaSlicer's own image of
# the letter F (fixtures/slice/letter_f.rhai, meshed by isoforge) on the Original Prusa SL1
# display (2560 x 1440 pixels of 0.04725 mm, portrait, mirrored in x), centred on the
# display, supports and pad off. Writes fixtures/slice/letter_f_prusa_sl1_layer10.png.
#
# Usage: tools/sl1-reference.sh [ISOFORGE_BINARY]   (needs prusa-slicer and unzip)
set -euo pipefail
cd "$(dirname "$0")/.."
isoforge=${1:-target/debug/isoforge}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
"$isoforge" mesh fixtures/slice/letter_f.rhai -o "$work/letter_f.stl" --resolution 0.1 -q
prusa-slicer --export-sla --printer-technology SLA \
  --display-width 120.96 --display-height 68.04 \
  --display-pixels-x 2560 --display-pixels-y 1440 \
  --display-orientation portrait --display-mirror-x --no-display-mirror-y \
  --layer-height 0.05 --initial-layer-height 0.05 \
  --supports-enable=0 --pad-enable=0 \
  --bed-shape 0x0,120.96x0,120.96x68.04,0x68.04 --center 60.48,34.02 \
  "$work/letter_f.stl" -o "$work/f.sl1" >/dev/null 2>&1
unzip -q -o "$work/f.sl1" -d "$work/f"
cp "$work/f/f00010.png" fixtures/slice/letter_f_prusa_sl1_layer10.png
echo "fixtures/slice/letter_f_prusa_sl1_layer10.png written"
