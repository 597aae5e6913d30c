#!/usr/bin/env python3
"""Streams a G-code file with Printrun's printcore and prints its speed as JSON.

printcore (https://github.com/kliment/Printrun) sends one line and waits for its `ok`
("ping-pong"); it is the reference our windowed host is compared with. Usage:
    printcore_run.py PORT FILE [--timeout SECONDS]
Prints {"commands": N, "seconds": S, "lines_per_second": R, "completed": true|false}.
"""

import argparse
import json
import sys
import time

from printrun import gcoder
from printrun.printcore import printcore


class Printcore(printcore):
    """printcore opens a job with `N-1 M110 N-1`; OctoPrint's simulator cannot read a negative
    line number (its reader thread stops on it). Start the count from 0 instead: the same
    meaning ("the next line is the first"), in a form every firmware reads."""

    def _send(self, command, lineno=0, calcchecksum=False):
        if command == "M110 N-1" and lineno == -1:
            super()._send("M110 N0", 0, calcchecksum)
            self.lineno = 1
            return
        super()._send(command, lineno, calcchecksum)


def disconnect(core):
    """Disconnects once printcore has settled after the print. Its print thread ends by
    creating a new sender thread and then starting it; a disconnect in between joins a thread
    not yet started, and Python raises ("cannot join thread before it is started": it failed
    a CI run). So wait for the print thread to be gone and the new sender to run."""
    deadline = time.monotonic() + 5
    while time.monotonic() < deadline:
        sender = core.send_thread
        if core.print_thread is None and (sender is None or sender.ident is not None):
            break
        time.sleep(0.01)
    core.disconnect()


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("port")
    parser.add_argument("file")
    parser.add_argument("--baud", type=int, default=115200)
    parser.add_argument("--timeout", type=float, default=600.0)
    args = parser.parse_args()

    with open(args.file) as f:
        lines = [line.strip() for line in f]
    gcode = gcoder.LightGCode(lines)
    commands = sum(1 for line in lines if line.split(";", 1)[0].strip())

    core = Printcore(args.port, args.baud)
    deadline = time.monotonic() + 30
    while not core.online:
        if time.monotonic() > deadline:
            print(json.dumps({"completed": False, "error": "printer never came online"}))
            return 1
        time.sleep(0.05)
    started = time.monotonic()
    core.startprint(gcode)
    # printcore sets `printing` false once its last line is acknowledged.
    while core.printing and time.monotonic() - started < args.timeout:
        time.sleep(0.01)
    seconds = time.monotonic() - started
    completed = not core.printing
    disconnect(core)
    print(
        json.dumps(
            {
                "commands": commands,
                "seconds": seconds,
                "lines_per_second": commands / seconds if seconds > 0 else 0.0,
                "completed": completed,
            }
        )
    )
    return 0 if completed else 1


if __name__ == "__main__":
    sys.exit(main())
