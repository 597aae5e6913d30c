#!/usr/bin/env python3
"""Check the evaluators' sin and cos (crates/isoforge-field/src/eval/trig.rs) against
70-digit decimal arithmetic, by hand:

    python3 tools/trig-accuracy.py [--seed N] [--points N]

Random x at scales from 1 to 10^6 (the range reduced in plain arithmetic), plus each
double nearest to k*pi/2 for k < 2000 and its two neighbours (where the reduction cancels
most). Prints the largest error of each in units in the last place of the true value.
The interval evaluator's enclosures assume under one ulp (enclose.rs widens libm's
results by two: one for libm, one for the point evaluators).
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
    run = subprocess.run(
        ["cargo", "run", "--release", "-q", "-p", "isoforge-field", "--example", "trig_values"],
        cwd=ROOT,
        input="\n".join(repr(x) for x in xs),
        capture_output=True,
        text=True,
    )
    if run.returncode != 0:
        raise SystemExit(run.stderr)
    worst = {"sin": (0.0, None), "cos": (0.0, None)}
    for line in run.stdout.splitlines():
        x, s, c = map(float, line.split())
        for name, ours, true in zip(("sin", "cos"), (s, c), true_sin_cos(x)):
            ulps = abs(float((Decimal(ours) - true) / Decimal(math.ulp(float(true)))))
            if ulps > worst[name][0]:
                worst[name] = (ulps, x)
    print("points: %d" % len(xs))
    for name, (ulps, x) in worst.items():
        print("%s: largest error %.3f ulp, at x = %r" % (name, ulps, x))


if __name__ == "__main__":
    main()
