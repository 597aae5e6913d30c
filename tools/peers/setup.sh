#!/usr/bin/env bash
# Creates (once) the Python virtual environment with the programs our host is judged against:
# OctoPrint's virtual printer (octoprint), pyserial, and Printrun's printcore (the ping-pong
# reference host). Usage: tools/peers/setup.sh [VENV_DIR]   (default: target/peers-venv)
# Idempotent: when the venv already holds these versions it only prints its path. The last
# line of stdout is the venv's path, for ISOFORGE_PEERS_VENV.
set -euo pipefail
cd "$(dirname "$0")/../.."
VENV="${1:-target/peers-venv}"
OCTOPRINT=1.11.8
PYSERIAL=3.5
PRINTRUN=2.2.0

check() {
  "$VENV/bin/python" - "$OCTOPRINT" "$PYSERIAL" "$PRINTRUN" <<'PY' 2>/dev/null
import sys
from importlib.metadata import version
want = dict(zip(["octoprint", "pyserial", "printrun"], sys.argv[1:]))
for name, v in want.items():
    if version(name) != v:
        sys.exit(1)
import octoprint.plugins.virtual_printer.virtual  # noqa: F401
import printrun.printcore  # noqa: F401
import serial  # noqa: F401
PY
}

if ! check; then
  echo "peers: creating $VENV (octoprint $OCTOPRINT, pyserial $PYSERIAL, printrun $PRINTRUN)" >&2
  python3 -m venv "$VENV"
  "$VENV/bin/pip" install --quiet --upgrade pip
  "$VENV/bin/pip" install --quiet "octoprint==$OCTOPRINT" "pyserial==$PYSERIAL"
  # printcore needs neither wxPython nor dbus (Printrun's GUI needs them, and their system
  # headers); its own imports need these two.
  "$VENV/bin/pip" install --quiet --no-deps "printrun==$PRINTRUN"
  "$VENV/bin/pip" install --quiet platformdirs puremagic
  check || { echo "peers: $VENV does not import octoprint/printcore after install" >&2; exit 1; }
fi
cd "$VENV" && pwd
