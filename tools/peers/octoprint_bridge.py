#!/usr/bin/env python3
"""OctoPrint's virtual printer behind a pseudo-terminal, so a real serial host can print to it.

OctoPrint (https://octoprint.org) ships a simulated Marlin-like printer for its own tests. It is
a Python object with write() and readline(); this script puts it on the master end of a pty,
prints the slave's path (the "serial port") on the first line of stdout, and records every
command the simulator executed, in order, so a test can compare that record with the file.

It runs until the host closes the port (or a SIGTERM), then writes --log and --summary.

Options set the simulator's own settings (see octoprint/plugins/virtual_printer/__init__.py in
the installed package): --simulated-errors (e.g. 100:resend,110:missing_lineno), --send-busy,
--rx-buffer, --command-buffer, --ok-format. --flip-every N damages one bit in every Nth line on
its way to the simulator (the line noise of a bad USB cable); --busy-every N adds busy reports.
"""

import argparse
import json
import os
import pty
import signal
import sys
import tempfile
import threading
import time
import tty

import octoprint.plugins.virtual_printer.virtual as virtual
from octoprint.plugins.virtual_printer import VirtualPrinterPlugin


class NoPlugins:
    """The simulator asks OctoPrint's plugin manager for action hooks; there are none here."""

    def get_hooks(self, _name):
        return {}


# The plugin manager only exists inside a running OctoPrint server.
virtual.plugin_manager = lambda: NoPlugins()


class Settings:
    """The small part of OctoPrint's settings object the simulator reads."""

    def __init__(self, values, base):
        self.values = values
        self.base = base

    def get(self, path, merged=False):
        value = self.values
        for key in path:
            value = value[key]
        return value

    def get_int(self, path):
        return int(self.get(path))

    def get_float(self, path):
        return float(self.get(path))

    def get_boolean(self, path):
        return bool(self.get(path))

    def global_get_basefolder(self, _name):
        return self.base


class RecordingPrinter(virtual.VirtualPrinter):
    """Records each G, M and T command as the simulator takes it for execution.

    The simulator looks for a handler named after the command's letter before the handler of
    the command itself; answering None from the letter handler lets the command run as usual.
    """

    def __init__(self, *args, **kwargs):
        self.executed = []
        super().__init__(*args, **kwargs)

    def _gcode_G(self, _code, data):
        self.executed.append(data.strip())

    def _gcode_M(self, _code, data):
        self.executed.append(data.strip())

    def _gcode_T(self, code, data):
        self.executed.append(data.strip())
        return super()._gcode_T(code, data)


def flip_one_bit(line):
    """Flips bit 0 of one byte of the command (between the line number and the `*`), choosing
    a byte whose flipped form is still printable and not a framing character, so the line
    stays a line and only its checksum can tell. Returns the line unchanged if no byte fits."""
    star = line.rfind(b"*")
    space = line.find(b" ")
    if star < 0 or space < 0 or space + 1 >= star:
        return line, False
    middle = (space + 1 + star) // 2
    order = sorted(range(space + 1, star), key=lambda i: abs(i - middle))
    for i in order:
        flipped = line[i] ^ 1
        if 0x21 <= flipped <= 0x7E and flipped not in b"*;()":
            return line[:i] + bytes([flipped]) + line[i + 1 :], True
    return line, False


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--log", required=True, help="executed commands, one per line")
    parser.add_argument("--summary", help="counters as JSON")
    parser.add_argument("--simulated-errors", default="", help="LINE:KIND,...")
    parser.add_argument("--send-busy", action="store_true")
    parser.add_argument("--busy-interval", type=float, default=2.0)
    parser.add_argument("--rx-buffer", type=int, default=128)
    parser.add_argument("--command-buffer", type=int, default=4)
    parser.add_argument("--ok-format", default="ok")
    parser.add_argument("--flip-every", type=int, default=0)
    parser.add_argument(
        "--busy-every",
        type=int,
        default=0,
        help="also report `echo:busy: processing` to the host after every Nth line (the "
        "simulator itself only says busy during waits, which a fast test pins away)",
    )
    parser.add_argument(
        "--instant-moves",
        action="store_true",
        help="moves take no time (the simulator otherwise sleeps a tenth of each move's "
        "duration, which would make any two hosts equally fast)",
    )
    parser.add_argument(
        "--pinned-hotend",
        type=float,
        help="hold the hotend at this temperature, so heating waits take no time",
    )
    args = parser.parse_args()

    values = VirtualPrinterPlugin().get_settings_defaults()
    values["simulated_errors"] = [e for e in args.simulated_errors.split(",") if e]
    values["sendBusy"] = args.send_busy
    values["busyInterval"] = args.busy_interval
    values["rxBuffer"] = args.rx_buffer
    values["commandBuffer"] = args.command_buffer
    values["okFormatString"] = args.ok_format
    if args.pinned_hotend is not None:
        values["pinnedExtruders"] = {0: args.pinned_hotend}

    master, slave = pty.openpty()
    tty.setraw(slave)
    tty.setraw(master)
    data_dir = tempfile.mkdtemp(prefix="octoprint-vp-")
    printer = RecordingPrinter(Settings(values, data_dir), None, data_folder=data_dir)
    if args.instant_moves:
        # The simulated move time is distance / (feed * multiplier); the multipliers are what
        # M220/M221 set, so a huge one makes every move instant without changing what runs.
        printer._feedrate_multiplier = 1e9
        printer._flowrate_multiplier = 1e9

    stop = threading.Event()
    counters = {"lines_in": 0, "flipped": 0}

    def host_to_printer():
        """Bytes from the host, line by line (flipping bits), into the simulator."""
        nonlocal slave
        pending = b""
        while not stop.is_set():
            try:
                data = os.read(master, 4096)
            except OSError:
                break  # every slave descriptor is closed: the host went away
            if not data:
                break
            if slave is not None:
                # A host is here; from now on its closing the port ends the session.
                os.close(slave)
                slave = None
            pending += data
            while b"\n" in pending:
                line, pending = pending.split(b"\n", 1)
                counters["lines_in"] += 1
                if args.flip_every and counters["lines_in"] % args.flip_every == 0:
                    line, flipped = flip_one_bit(line)
                    counters["flipped"] += int(flipped)
                if args.busy_every and counters["lines_in"] % args.busy_every == 0:
                    counters["busy"] = counters.get("busy", 0) + 1
                    try:
                        os.write(master, b"echo:busy: processing\n")
                    except OSError:
                        break
                rest = line + b"\n"
                while rest and not stop.is_set():
                    # The simulator takes what fits its receive buffer and says how much.
                    written = printer.write(rest)
                    rest = rest[written:]
                    if rest:
                        time.sleep(0.001)
        stop.set()

    def printer_to_host():
        while not stop.is_set():
            line = printer.readline()
            if not line:
                continue
            if not line.endswith(b"\n"):
                line += b"\n"
            try:
                os.write(master, line)
            except OSError:
                break

    signal.signal(signal.SIGTERM, lambda *_: stop.set())
    threads = [
        threading.Thread(target=host_to_printer, daemon=True),
        threading.Thread(target=printer_to_host, daemon=True),
    ]
    print(os.ttyname(slave), flush=True)
    for t in threads:
        t.start()
    while not stop.is_set():
        stop.wait(0.1)
    # Let the simulator finish the commands it already took.
    time.sleep(0.3)
    printer.close()
    with open(args.log, "w") as f:
        for command in printer.executed:
            f.write(command + "\n")
    if args.summary:
        counters["executed"] = len(printer.executed)
        with open(args.summary, "w") as f:
            json.dump(counters, f)
    return 0


if __name__ == "__main__":
    sys.exit(main())
