#!/usr/bin/env bash
# Installs the programs that judge isoforge's output in tests (see docs/contributing.md):
# ADMesh, an independent STL checker (crates/isoforge-script/tests/modern_fixtures.rs), and
# PrusaSlicer, whose G-code of the same models the slicer is compared with
# (crates/isoforge-cli/tests/cli/peers.rs), and OpenSCAD, whose extrusions of the same
# profiles judge the sweeps (crates/isoforge-cli/tests/cli/openscad.rs). Idempotent and quick when they are already
# there. Debian/Ubuntu (apt-get); elsewhere, install them by hand.
set -euo pipefail
missing=()
command -v admesh >/dev/null 2>&1 || missing+=(admesh)
command -v prusa-slicer >/dev/null 2>&1 || missing+=(prusa-slicer)
command -v openscad >/dev/null 2>&1 || missing+=(openscad)
if [ ${#missing[@]} -eq 0 ]; then
  exit 0
fi
if ! command -v apt-get >/dev/null 2>&1; then
  echo "install-peers: ${missing[*]} missing and no apt-get: install them by hand" >&2
  exit 1
fi
SUDO=""
if [ "$(id -u)" != 0 ]; then
  SUDO="sudo"
fi
$SUDO apt-get update -qq
DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
