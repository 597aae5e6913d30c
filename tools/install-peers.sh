#!/usr/bin/env bash
# Installs the programs the peer tests judge our output with, when they are missing:
# PrusaSlicer (its G-code of the same models, tests/cli/peers.rs). Idempotent and quick
# when everything is there (one `command -v`); needs apt-get (Debian, Ubuntu) otherwise.
set -euo pipefail
missing=()
command -v prusa-slicer >/dev/null 2>&1 || missing+=(prusa-slicer)
if [ ${#missing[@]} -eq 0 ]; then
  exit 0
fi
sudo=""
if [ "$(id -u)" -ne 0 ]; then
  sudo=sudo
fi
echo "installing ${missing[*]}" >&2
$sudo apt-get update -qq
DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
