#!/usr/bin/env python3
"""The piezocone's readings in Modified Cam Clay by spherical cavity expansion and critical
state (SCE-CSSM), the published closed form for `scenes/cptu_clay.ron`
(docs/verification.md, "The piezocone in Cam Clay").

Mayne (1991, "Determination of OCR in clays by piezocone tests using cavity expansion and
critical state concepts", Soils and Foundations 31(2)), Chen & Mayne (1993, "Piezocone
evaluation of undrained shear strength in clays", 11th SEAGC) and Burns & Mayne (2002,
"Analytical cavity expansion-critical state model for piezocone dissipation in
fine-grained soils", Soils and Foundations 42(2)) read a piezocone in a clay of Modified
Cam Clay parameters M, Lambda = (lambda - kappa)/lambda and OCR R from the isotropic
p'0 = sigma'v0:

    s_u         = (M/2) (R/2)^Lambda p'0                   (Wood 1990, triaxial, undrained)
    q_t - s_v0  = s_u [ (4/3)(ln I_r + 1) + pi/2 + 1 ]     (the tip: Vesic's spherical
                                                            cavity limit and the shoulder)
    du2         = (2/3) M (R/2)^Lambda p'0 ln I_r          (octahedral: the cavity's
                  + p'0 [1 - (R/2)^Lambda]                  mean stress, (4/3) s_u ln I_r;
                                                            shear: p'0 - p'f on the
                                                            undrained path)

so that q_t - u2 = p'0 (R/2)^Lambda (1.95 M + 1), the form these papers invert for the
OCR. I_r = G/s_u with G of the clay at rest: K = v p'0/kappa, G = 3K(1 - 2nu)/(2(1 + nu)),
v on the swelling line through p'c = R p'0 below the normal compression line
v = N - lambda ln(p'/1 kPa), as the engine starts a point (src/materials/modified_cam_clay.rs).
The engine's G falls with p' along the undrained path (to (R/2)^Lambda of the start at the
critical state), so the cone shears clay of a smaller I_r than the one at rest; the table
prints both ends.

Run: `python3 studies/cptu_cssm.py` prints the readings at R = 1 and 2 for the clay of
`scenes/cptu_clay.ron`; `python3 studies/cptu_cssm.py R OUT [OUT ...]` sets the rows of
each run's OUT/cpt.csv (a run of that scene with `preconsolidation=Ratio(R)`) against them,
and with two runs whose cells halve (h, h/2, in that order) the first-order extrapolation
2 X(h/2) - X(h) of the mean over the last four rows; with three (h, h/2, h/4) the order
p = log2((X(h) - X(h/2))/(X(h/2) - X(h/4))) the three observe and the extrapolation
X(h/4) + (X(h/4) - X(h/2))/(2^p - 1), where the two differences have one sign.
`python3 studies/cptu_cssm.py --shoulder OUT H` reads the run's last points (points.vtu, or
points_*.vtu over MPI ranks) about the cone's shoulder at the end of the push, h = H m: the
pore pressure the scene's filter reads (the clay beside the sleeve within a cell of its
place 0.07 D above the shoulder, where the middle of a field u2 element sits), that within a
cell of the shoulder's corner on either side, that of the clay a cell thick beside the
shaft at heights above the shoulder and on the face, and N_du and B_q of the filter's and
of the shaft's reading at 0.07 D with the log's last q_t.
"""
import csv
import math
import sys

LAMBDA, KAPPA, M, NU, N = 0.25, 0.05, 0.9, 0.3, 3.0
P0 = 100e3  # Pa, isotropic effective, u0 = 0
REF = 1e3  # Pa, N's pressure


def readings(r_ocr, g_at="rest"):
    """(s_u, I_r, N_kt, N_du, B_q) of SCE-CSSM; G at rest or at the critical state."""
    lam = (LAMBDA - KAPPA) / LAMBDA
    ratio = (r_ocr / 2.0) ** lam  # p'f / p'0 on the undrained path
    s_u = M / 2.0 * ratio * P0
    pc = r_ocr * P0
    v = N - LAMBDA * math.log(pc / REF) + KAPPA * math.log(pc / P0)
    p = P0 if g_at == "rest" else P0 * ratio
    k = v * p / KAPPA
    g = 3.0 * k * (1.0 - 2.0 * NU) / (2.0 * (1.0 + NU))
    i_r = g / s_u
    n_kt = 4.0 / 3.0 * (math.log(i_r) + 1.0) + math.pi / 2.0 + 1.0
    du2 = 2.0 / 3.0 * M * ratio * P0 * math.log(i_r) + P0 * (1.0 - ratio)
    return s_u, i_r, n_kt, du2 / s_u, du2 / (n_kt * s_u)


def logged(out):
    """(depth, N_kt, N_du, B_q) of each row of OUT/cpt.csv that has all three."""
    rows = []
    with open(f"{out}/cpt.csv") as f:
        for r in csv.DictReader(f):
            if r["N_kt"] and r["N_du"] and r["B_q"]:
                rows.append((float(r["depth"]), float(r["N_kt"]), float(r["N_du"]), float(r["B_q"])))
    return rows


def shoulder(out, h):
    """The pore pressures about the cone's shoulder in the run's last points (see the
    module's text), for scenes/cptu_clay.ron's cone: D = 1 m, the shoulder at (0.5, 14.0) m
    at the start, moved down by the log's last travel."""
    import glob

    from cavity_mcc import vtu_arrays

    names = sorted(glob.glob(f"{out}/points_*.vtu")) or [f"{out}/points.vtu"]
    pts = []
    for name in names:
        a = vtu_arrays(name, {"points", "volume", "excess_pore_pressure"})
        pts += [(x[0], x[1], v, u) for x, v, u in zip(a["points"], a["volume"], a["excess_pore_pressure"])]
    with open(f"{out}/cpt.csv") as f:
        last = list(csv.DictReader(f))[-1]
    radius, z0 = 0.5, 14.0 - float(last["travel"])
    apex = z0 - radius / math.tan(math.radians(30.0))

    def mean(keep):
        sel = [(v, u) for r, z, v, u in pts if keep(r, z)]
        return sum(v * u for v, u in sel) / sum(v for v, _ in sel), len(sel)

    def segment(p, a, b):
        t = ((p[0] - a[0]) * (b[0] - a[0]) + (p[1] - a[1]) * (b[1] - a[1])) / math.dist(a, b) ** 2
        t = min(1.0, max(0.0, t))
        return math.dist(p, (a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])))

    def outside(p, poly):
        return min(segment(p, a, b) for a, b in zip(poly, poly[1:] + poly[:1]))

    tip = [(0.0, apex), (radius, z0), (0.0, z0)]
    sleeve = [(0.0, z0), (radius, z0), (radius, z0 + 3.75), (0.0, z0 + 3.75)]
    filt = z0 + 0.07
    u2, n = mean(
        lambda r, z: math.hypot(r - radius, z - filt) <= h and outside((r, z), sleeve) < outside((r, z), tip)
    )
    print(f"the scene's filter, 0.07 m up the sleeve (within {h} m, beside the sleeve): {u2 / 1e3:.1f} kPa, {n} points")
    u, n = mean(lambda r, z: math.hypot(r - radius, z - z0) <= h)
    print(f"within {h} m of the shoulder's corner, either side: {u / 1e3:.1f} kPa, {n} points")
    shaft = {}
    for dz in (0.0, 0.035, 0.07, 0.14, 0.25, 0.5, 1.0):
        shaft[dz], n = mean(lambda r, z: radius < r < radius + h and abs(z - z0 - dz) < h / 2)
        print(f"beside the shaft, {dz:5.3f} m above the shoulder: {shaft[dz] / 1e3:6.1f} kPa, {n} points")
    for f in (0.25, 0.5, 0.75):
        c = (radius * f, apex + (z0 - apex) * f)
        u, n = mean(lambda r, z: math.hypot(r - c[0], z - c[1]) <= h)
        print(f"the face, {f:.2f} of the way up: {u / 1e3:6.1f} kPa, {n} points")
    net, s_u = float(last["q_t"]) - float(last["sigma_v0"]), float(last["s_u"])
    for name, u in (("the scene's filter", u2), ("beside the shaft at 0.07 D", shaft[0.07])):
        print(f"{name}, depth {float(last['depth']):.2f} m: N_du {u / s_u:.2f}, B_q {u / net:.2f}")


def main():
    if len(sys.argv) == 4 and sys.argv[1] == "--shoulder":
        shoulder(sys.argv[2], float(sys.argv[3]))
        return
    if len(sys.argv) < 3:
        print("R  G at     s_u (kPa)  I_r    N_kt   N_du   B_q")
        for r_ocr in (1.0, 2.0):
            for g_at in ("rest", "critical"):
                s_u, i_r, n_kt, n_du, b_q = readings(r_ocr, g_at)
                print(f"{r_ocr:<2g} {g_at:<8} {s_u / 1e3:9.2f}  {i_r:5.1f}  {n_kt:5.2f}  {n_du:5.2f}  {b_q:5.3f}")
        return
    r_ocr = float(sys.argv[1])
    s_u, i_r, n_kt, n_du, b_q = readings(r_ocr)
    print(f"SCE-CSSM, R = {r_ocr:g}, I_r = {i_r:.1f} at rest: N_kt {n_kt:.2f}, N_du {n_du:.2f}, B_q {b_q:.3f}")
    means = []
    for out in sys.argv[2:]:
        rows = logged(out)
        print(f"{out}: depth, N_kt, N_du, B_q (difference on SCE-CSSM)")
        for d, kt, du, bq in rows:
            print(f"  {d:5.2f}  {kt:6.2f} ({kt / n_kt - 1:+6.1%})  {du:6.2f} ({du / n_du - 1:+6.1%})  {bq:5.2f}")
        last = rows[-4:]
        means.append([sum(x[i] for x in last) / len(last) for i in (1, 2, 3)])
        print("  mean of the last four rows: N_kt {:.2f}, N_du {:.2f}, B_q {:.2f}".format(*means[-1]))
    if len(means) == 2:
        ext = [2.0 * f - c for c, f in zip(*means)]
        print(
            f"extrapolated (2 X(h/2) - X(h)): N_kt {ext[0]:.2f} ({ext[0] / n_kt - 1:+.1%}), "
            f"N_du {ext[1]:.2f} ({ext[1] / n_du - 1:+.1%}), B_q {ext[2]:.2f}"
        )
    if len(means) == 3:
        for i, name, ref in ((0, "N_kt", n_kt), (1, "N_du", n_du), (2, "B_q", b_q)):
            print(f"{name}: {three_cells(*(m[i] for m in means), ref)}")


def three_cells(coarse, middle, fine, ref):
    """The order three cells that halve observe and the limit they extrapolate to."""
    d1, d2 = coarse - middle, middle - fine
    if d1 == 0.0 or d2 == 0.0 or (d1 > 0.0) != (d2 > 0.0):
        return f"{coarse:.2f}, {middle:.2f}, {fine:.2f}: not monotone, no order"
    order = math.log2(d1 / d2)
    if order <= 0.0:
        return f"{coarse:.2f}, {middle:.2f}, {fine:.2f}: differences not shrinking (order {order:.2f})"
    limit = fine + (fine - middle) / (2.0**order - 1.0)
    return (
        f"{coarse:.2f}, {middle:.2f}, {fine:.2f}: order {order:.2f}, "
        f"extrapolated {limit:.2f} ({limit / ref - 1:+.1%} on SCE-CSSM)"
    )


if __name__ == "__main__":
    main()
