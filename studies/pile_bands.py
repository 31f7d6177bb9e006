#!/usr/bin/env python3
"""The jacked pile's base and shaft by bands of penetration, from a run of
`scenes/pile_jacking.ron` (docs/verification.md, "A jacked pile").

Rows `pile.base` and `pile.shaft` of `curve.csv`, forces per radian:

    N_c           = (q_b - sigma_v0) / c_u,   sigma_v0 = 100 kPa (the surcharge), c_u = 10 kPa
    shaft stress  = |F_y| / (R L),            R = 0.5 m, L = 0.9375 m + d the shaft's
                                              length in the clay (the pile starts 1 m in,
                                              its base slab 0.0625 m)

Run: `python3 studies/pile_bands.py OUT` for the run's output directory OUT; prints the
mean and range of each over 0.25-2, 2.25-4, 4.25-6, 6.25-8, 8.25-10 and 5-10 D.
"""

import csv
import sys

SIGMA_V0, C_U, R, SHAFT_AT_START = 100e3, 10e3, 0.5, 0.9375
BANDS = [(0.25, 2), (2.25, 4), (4.25, 6), (6.25, 8), (8.25, 10), (5, 10)]


def main(out):
    with open(f"{out}/curve.csv") as f:
        rows = list(csv.DictReader(f))
    base = {float(r["displacement"]): float(r["pressure"]) for r in rows if r["name"] == "pile.base"}
    shaft = {float(r["displacement"]): float(r["force_y"]) for r in rows if r["name"] == "pile.shaft"}
    print("penetration  N_c mean (range)        shaft stress kPa mean (range)  states")
    for lo, hi in BANDS:
        at = [d for d in sorted(base) if lo - 1e-9 <= d <= hi + 1e-9]
        if not at:
            continue
        nc = [(base[d] - SIGMA_V0) / C_U for d in at]
        ss = [abs(shaft[d]) / (R * (SHAFT_AT_START + d)) / 1e3 for d in at]
        print(
            f"{lo:5.2f}-{hi:<5g} D  {sum(nc) / len(nc):6.2f} ({min(nc):.2f}-{max(nc):.2f})"
            f"   {sum(ss) / len(ss):6.2f} ({min(ss):.2f}-{max(ss):.2f})   {len(at)}"
        )


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    main(sys.argv[1])
