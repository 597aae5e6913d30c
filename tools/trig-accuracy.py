#!/usr/bin/env python3
"""Check the evaluators' sin, cos and atan2 (crates/isoforge-field/src/eval/trig.rs)
against 70-digit decimal arithmetic, by hand:

    python3 tools/trig-accuracy.py [--seed N] [--points N]

Random x at scales from 1 to 10^6 (the range reduced in plain arithmetic), plus each
double nearest to k*pi/2 for k < 2000 and its two neighbours (where the reduction cancels
most); for atan2, random (y, x) at scales from 10^-3 to 10^3, each sign. Prints the
largest error of each in units in the last place of the true value. The interval
evaluator's enclosures assume sin and cos within one ulp (enclose.rs widens libm's results
by two: one for libm, one for the point evaluators) and atan2 within three (widened by
four).
"""

import argparse
import math
import os
import random
import subprocess
from decimal import Decimal, getcontext

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
getcontext().prec = 70
PI = Decimal(
    "3.14159265358979323846264338327950288419716939937510582097494459230781640628620899862803482534211706798"
)


def true_sin_cos(x):
    """sin x and cos x to about 60 digits: reduced by pi/2, then Taylor series."""
    x = Decimal(x)
    k = (x / (PI / 2)).to_integral_value()
    r = x - k * PI / 2

    def series(term, n):
        total = Decimal(0)
        while abs(term) > Decimal(10) ** -80:
            total += term
            term = -term * r * r / ((n + 1) * (n + 2))
            n += 2
        return total

    s, c = series(r, 1), series(Decimal(1), 0)
    return [(s, c), (c, -s), (-s, -c), (-c, s)][int(k) % 4]


def true_atan2(y, x):
    """atan2(y, x) to about 60 digits: atan of the smaller over the larger by halving the
    angle until the series is quick, then placed in its octant."""
    y, x = Decimal(y), Decimal(x)
    ay, ax = abs(y), abs(x)
    steep = ay > ax
    t = ax / ay if steep else ay / ax
    halvings = 0
    while t > Decimal("0.1"):
        t = t / (1 + (1 + t * t).sqrt())
        halvings += 1
    total, term, n = Decimal(0), t, 1
    while abs(term) > Decimal(10) ** -80:
        total += term / n
        term = -term * t * t
        n += 2
    a = total * (2**halvings)
    if steep:
        a = PI / 2 - a
    if x < 0:
        a = PI - a
    return -a if y < 0 else a


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--points", type=int, default=100000)
    args = ap.parse_args()
    rng = random.Random(args.seed)
    scales = [1, 10, 100, 1e3, 1e4, 1e5, 1e6]
    xs = [rng.uniform(-1, 1) * scales[i % len(scales)] for i in range(args.points)]
    for k in range(1, 2000):
        v = float(Decimal(k) * PI / 2)
        xs += [v, math.nextafter(v, 0), math.nextafter(v, math.inf)]
    pairs = []
    for i in range(args.points // 4):
        scale = [1e-3, 1, 1e3][i % 3]
        pairs.append((rng.uniform(-1, 1) * scale, rng.uniform(-1, 1) * scale))
    lines = [repr(x) for x in xs] + ["%r %r" % p for p in pairs]
    run = subprocess.run(
        ["cargo", "run", "--release", "-q", "-p", "isoforge-field", "--example", "trig_values"],
        cwd=ROOT,
        input="\n".join(lines),
        capture_output=True,
        text=True,
    )
    if run.returncode != 0:
        raise SystemExit(run.stderr)
    worst = {"sin": (0.0, None), "cos": (0.0, None), "atan2": (0.0, None)}

    def note(name, ours, true, at):
        ulps = abs(float((Decimal(ours) - true) / Decimal(math.ulp(float(true)))))
        if ulps > worst[name][0]:
            worst[name] = (ulps, at)

    out = run.stdout.splitlines()
    # One output line per input line, in order: the x lines, then the (y, x) lines.
    for line in out[: len(xs)]:
        x, s, c = map(float, line.split())
        for name, ours, true in zip(("sin", "cos"), (s, c), true_sin_cos(x)):
            note(name, ours, true, x)
    for line in out[len(xs) :]:
        y, x, a = map(float, line.split())
        note("atan2", a, true_atan2(y, x), (y, x))
    print("points: %d for sin and cos, %d for atan2" % (len(xs), len(pairs)))
    for name, (ulps, x) in worst.items():
        print("%s: largest error %.3f ulp, at %r" % (name, ulps, x))


if __name__ == "__main__":
    main()
