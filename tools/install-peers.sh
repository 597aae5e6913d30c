#!/usr/bin/env bash
# Installs the programs that judge isoforge's output in tests (see docs/contributing.md):
# ADMesh, an independent STL checker (crates/isoforge-script/tests/modern_fixtures.rs).
# Idempotent and quick when they are already there. Debian/Ubuntu (apt-get); elsewhere,
# install ADMesh by hand.
set -euo pipefail
if command -v admesh >/dev/null 2>&1; then
  exit 0
fi
if ! command -v apt-get >/dev/null 2>&1; then
  echo "install-peers: no admesh and no apt-get: install ADMesh by hand" >&2
  exit 1
fi
SUDO=""
if [ "$(id -u)" != 0 ]; then
  SUDO="sudo"
fi
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq admesh
admesh --version
