#!/usr/bin/env bash
# The studio's preview latency per classic model: slider input to the coarse preview on
# screen, measured in headless Chromium with performance marks (release build).
# Usage: tools/studio-latency.sh [REPORT.md]
set -euo pipefail
cd "$(dirname "$0")/.."
unset RUSTFLAGS CARGO_ENCODED_RUSTFLAGS
bash tools/install-browser.sh
if [ $# -gt 0 ]; then export ISOFORGE_LATENCY_OUT="$(realpath -m "$1")"; fi
cargo test --release -p isoforge-cli --test cli studio_browser::preview_latency \
  -- --ignored --nocapture --test-threads=1
