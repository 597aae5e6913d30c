#!/usr/bin/env bash
# Installs admesh, the STL checker the sweep tests ask for a second opinion
# (crates/isoforge-cli/tests/cli/sweeps.rs). Does nothing when it is already there, so
# .ci/run calls it on every run.
set -euo pipefail
if command -v admesh >/dev/null 2>&1; then
  exit 0
fi
if [ "$(id -u)" -eq 0 ]; then
  apt-get update -qq && apt-get install -y -qq admesh
else
  sudo apt-get update -qq && sudo apt-get install -y -qq admesh
fi
command -v admesh >/dev/null
