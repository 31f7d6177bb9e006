#!/usr/bin/env python3
"""Undrained cavity expansion in Modified Cam Clay, the reference for
`scenes/cavity_clay.ron` (docs/verification.md, "Undrained cavity expansion").

Collins & Yu (1996, "Undrained cavity expansions in critical state soils", IJNAMG 20)
reduce the undrained expansion of a cavity in an infinite critical-state soil to one
element's response: the soil is incompressible, so a particle now at r that started at
r0 has the hoop log strain e = ln(r/r0), every particle follows the same path of
deviatoric strain, and radial equilibrium integrates to the cavity pressure

    cylinder:  psi - p0 = int_0^e_a (sigma_r - sigma_t)(e) de / (exp(2 e) - 1)
    sphere:    psi - p0 = 2 int_0^e_a (sigma_r - sigma_t)(e) de / (exp(3 e) - 1)

with e_a = ln(a/a0) at the cavity wall (a0 its radius at the start), the limit pressure
as e_a grows without end. The element: plane-strain pure shear in the cylinder
(eps_q = 2 e / sqrt 3, sigma_z the mean of the other two, q = sqrt 3 (sigma_r - sigma_t)/2),
axisymmetric in the sphere (eps_q = 2 e, q = sigma_r - sigma_t). Its Cam Clay response
undrained from an isotropic p'0 with R = p'c/p'0, integrated here on its own (not with
the engine's code): elastic at constant p' up to the yield surface, then on it with
kappa ln p' + (lambda - kappa) ln p'c fixed (no volume change), q^2 = M^2 p'(p'c - p'),
and the shear strain dq/3G plus the associated flow's
d eps_q^p = 2q/(M^2 (2p' - p'c)) * (-kappa dp'/(v p')), G from K = v p'/kappa and nu.
At the wall the excess pore pressure is the total mean stress less p' (less u0 = 0):
psi - q/sqrt 3 - p' (cylinder), psi - 2q/3 - p' (sphere).

Run: `python3 studies/cavity_mcc.py [R]` (R = 1 by default) prints the pressure against
a/a0 and the limits, for the clay of `scenes/cavity_clay.ron`; `python3
studies/cavity_mcc.py R OUT` sets a finished run of that scene (or of
`cavity_clay_r2.ron`) in OUT against it, stage by stage: the cavity's radius from the
traced point `wall` (r0 = 1.025 m, its volume held: a² − a0² = r² − r0², both counted from
the clay at rest under the cavity's 100 kPa, the stage `in situ`) and the pressure the
reference gives at that a/a0.

`python3 studies/cavity_mcc.py R OUT --sphere` does the same for a run of
`scenes/cavity_sphere.ron` (or `cavity_sphere_r2.ron`; `--from 1.025` adds the shell of
clay from 1.025 m, for a run at h = 0.05 m, whose loaded points lie within 0.025 m of the
wall): a thick sphere of outer radius b = 6 m under the far field's 100 kPa, whose
reference is the same integral from the
outer face's strain e_b = -ln(1 - (a^3 - a0^3)/b^3)/3 instead of 0 (the kinematics of an
incompressible sphere hold in a finite one; only the far field's pressure now acts at b),
and whose cavity radius comes from the volume of the cavity: the traced points `wall9`,
`wall27`, ... `wall81` stand for the wall's 18-degree zones, a^3 = a0^3 + the zones'
mean of rho^3 - rho0^3 weighted by their share of the sphere, cos(phi) dphi. After the
shells it reads the wall's excess pore pressure from the clay 2 to 6, 8 and 10 cells off
the wall (`--cell H`, the run's cell, 0.1 m by default): the straight line of those points'
pressures against their starting radius, at the wall (`wall_trend`).
"""
import csv
import math
import sys

LAMBDA, KAPPA, M, NU, N = 0.25, 0.05, 0.9, 0.3, 3.0
P0 = 100e3  # Pa, isotropic effective, u0 = 0
REF = 1e3  # Pa, N's pressure


def element(r_ocr, steps=200000):
    """(eps_q, p', q) along the undrained path, from the start to near the critical state."""
    pc0 = r_ocr * P0
    v = N - LAMBDA * math.log(pc0 / REF) + KAPPA * math.log(pc0 / P0)
    k = lambda p: v * p / KAPPA
    g = lambda p: 3 * k(p) * (1 - 2 * NU) / (2 * (1 + NU))
    path = [(0.0, P0, 0.0)]
    # Elastic at p' = p'0 (no volume change, K acts on none): q to the yield surface.
    qy = M * math.sqrt(max(P0 * (pc0 - P0), 0.0))
    eq = qy / (3 * g(P0))
    path.append((eq, P0, qy))
    # On the surface: p' falls (R < 2) or rises (R > 2) towards the critical state
    # p'f = p'0 (R/2)^Lambda; march p' in small steps.
    lam_ = (LAMBDA - KAPPA) / LAMBDA
    pf = P0 * (r_ocr / 2) ** lam_
    c = KAPPA * math.log(P0) + (LAMBDA - KAPPA) * math.log(pc0)
    pc = lambda p: math.exp((c - KAPPA * math.log(p)) / (LAMBDA - KAPPA))
    p, q = P0, qy
    for i in range(1, steps + 1):
        # Geometric approach to p'f, stopping 1e-6 short (the flow rule's 2p' - p'c -> 0).
        p_next = pf + (P0 - pf) * (1 - i / steps) ** 3
        if abs(p_next - pf) < 1e-9 * P0:
            break
        pcn = pc(p_next)
        qn = M * math.sqrt(max(p_next * (pcn - p_next), 0.0))
        pm, qm = 0.5 * (p + p_next), 0.5 * (q + qn)
        pcm = pc(pm)
        dp = p_next - p
        deq_p = 2 * qm / (M * M * (2 * pm - pcm)) * (-KAPPA * dp / (v * pm))
        eq += (qn - q) / (3 * g(pm)) + deq_p
        p, q = p_next, qn
        path.append((eq, p, q))
    return path, pf


def q_at(path, eq):
    """q and p' at the deviatoric strain eq (linear between path points; the critical
    state beyond)."""
    lo, hi = 0, len(path) - 1
    if eq >= path[hi][0]:
        return path[hi][2], path[hi][1]
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if path[mid][0] <= eq:
            lo = mid
        else:
            hi = mid
    (e0, p0, q0), (e1, p1, q1) = path[lo], path[hi]
    t = 0.0 if e1 == e0 else (eq - e0) / (e1 - e0)
    return q0 + t * (q1 - q0), p0 + t * (p1 - p0)


def pressure(path, e_a, sphere, n=200000, e_b=0.0):
    """psi - p0 at the wall's hoop log strain e_a (midpoint rule in e), the far field's p0
    acting where the strain is e_b (0: an infinite body)."""
    total = 0.0
    de = (e_a - e_b) / n
    for i in range(n):
        e = e_b + (i + 0.5) * de
        if sphere:
            q, _ = q_at(path, 2 * e)
            total += 2 * q * de / math.expm1(3 * e)
        else:
            q, _ = q_at(path, 2 * e / math.sqrt(3))
            total += (2 / math.sqrt(3)) * q * de / math.expm1(2 * e)
    return total


def compare(path, out):
    """The run in `out` against the reference, stage by stage."""
    history = {int(r["step"]): r for r in csv.DictReader(open(out + "/history.csv"))}
    print("stage | a/a0 | kdmpm (kPa) | Collins & Yu (kPa) | difference")
    r0 = a0 = None
    for s in csv.DictReader(open(out + "/stages.csv")):
        row = history[max(k for k in history if k <= int(s["step"]))]
        r = 1.025 + float(row["wall_ux"])
        if r0 is None:
            r0, a0 = r, math.sqrt(1.0 + r * r - 1.025**2)
            continue
        ratio = math.sqrt(a0 * a0 + r * r - r0 * r0) / a0
        psi = float(s["stage"].split()[0])
        ref = (P0 + pressure(path, math.log(ratio), False, n=20000)) / 1e3
        print(f"{s['stage']} | {ratio:.4f} | {psi:.1f} | {ref:.2f} | {(psi / ref - 1) * 100:+.2f} %")


B_SPHERE = 6.0  # m, the outer radius of scenes/cavity_sphere.ron


def compare_sphere(path, out, near=1.075, cell=0.1):
    """The spherical run in `out` against the reference for its thick sphere; the clay's
    excess pore pressure in shells from `near` m out (past the loaded points), and at the
    wall as read from the clay 2 to 6, 8 and 10 cells of `cell` m off it (`wall_trend`)."""
    import json

    history = {int(r["step"]): r for r in csv.DictReader(open(out + "/history.csv"))}
    traced = json.load(open(out + "/summary.json"))["traced"]
    walls = []
    for t in traced:
        if t["name"].startswith("wall"):
            phi = math.radians(float(t["name"][4:]))
            weight = math.sin(phi + math.radians(9)) - math.sin(phi - math.radians(9))
            walls.append((t["name"], t["initial_position"], weight))
    print("stage | a/a0 | kdmpm (kPa) | Collins & Yu, b = 6 m (kPa) | difference | wall u (kPa)")
    base = None
    for s in csv.DictReader(open(out + "/stages.csv")):
        row = history[max(k for k in history if k <= int(s["step"]))]
        rho3 = []
        for name, x0, _ in walls:
            x, y = x0[0] + float(row[name + "_ux"]), x0[1] + float(row[name + "_uy"])
            rho3.append(math.hypot(x, y) ** 3)
        if base is None:
            base = rho3
            continue
        total = sum(w for _, _, w in walls)
        grown = sum(w * (r - r0) for (_, _, w), r, r0 in zip(walls, rho3, base)) / total
        ratio = (1.0 + grown) ** (1 / 3)
        e_b = -math.log(1 - grown / B_SPHERE**3) / 3
        psi = float(s["stage"].split()[0])
        ref = P0 + pressure(path, math.log(ratio), True, n=20000, e_b=e_b)
        q, p = q_at(path, 2 * math.log(ratio))
        u_wall = ref - 2 * q / 3 - p
        print(
            f"{s['stage']} | {ratio:.4f} | {psi:.1f} | {ref / 1e3:.2f} | "
            f"{(psi * 1e3 / ref - 1) * 100:+.2f} % | {u_wall / 1e3:.2f}"
        )
    # The last stage's points.vtu: the excess pore pressure of the clay in shells out from
    # the wall against the reference at each point's own strain.
    import os

    if not os.path.exists(out + "/points.vtu"):
        return
    points = vtu_arrays(out + "/points.vtu", {"points", "displacement", "excess_pore_pressure"})
    bands = ((1.075, 1.175), (1.175, 1.275), (1.275, 1.4), (1.4, 1.6))
    if near < bands[0][0]:
        bands = ((near, bands[0][0]),) + bands
    for band in bands:
        near_wall(path, points, grown, e_b, band)
    for cells in ((2, 6), (2, 8), (2, 10)):
        at_wall, line_ref, n = wall_trend(path, points, grown, e_b, cell, cells)
        print(
            f"the wall's excess pore pressure from the clay {cells[0]}-{cells[1]} cells off it "
            f"({n} points, their straight line in rho0 carried to the wall): {at_wall / 1e3:.1f} kPa "
            f"against {u_wall / 1e3:.1f} kPa, {(at_wall / u_wall - 1) * 100:+.1f} % (the reference's "
            f"own values at the same points, so read: {line_ref / 1e3:.1f} kPa, "
            f"{(line_ref / u_wall - 1) * 100:+.1f} %)"
        )


def wall_trend(path, a, grown, e_b, cell, cells, a0=1.0):
    """The excess pore pressure at the cavity's wall read from the clay that started
    `cells` (from, to) cells off it, as a finite element code recovers a stress at a
    boundary from its integration points: the least-squares straight line of each point's
    excess pore pressure against its starting distance from the centre, at rho0 = a0. The
    cells the arc cuts, whose points scatter, are left out. Returns the engine's line at the
    wall, the same line through the reference's values at the same points (the reading's
    own error, against the reference at the wall), and the number of points."""
    band = (a0 + cells[0] * cell, a0 + cells[1] * cell)
    rho0s, engine, ref = clay_in_band(path, a, grown, e_b, band)
    xs = [r - a0 for r in rho0s]

    def at_wall(values):
        n = len(xs)
        mx, mv = sum(xs) / n, sum(values) / n
        slope = sum((x - mx) * (v - mv) for x, v in zip(xs, values)) / sum((x - mx) ** 2 for x in xs)
        return mv - slope * mx

    return at_wall(engine), at_wall(ref), len(xs)


def vtu_arrays(name, wanted):
    """The arrays `wanted` of a points.vtu (raw appended, UInt64 headers), as lists of
    tuples (or numbers), by name; 'points' for the positions."""
    import re
    import struct

    data = open(name, "rb").read()
    head, _, rest = data.partition(b'<AppendedData encoding="raw">')
    blob = rest[rest.index(b"_") + 1 :]
    found = {}
    for m in re.finditer(rb"<DataArray ([^>]*)/>", head):
        attrs = dict(re.findall(rb'(\w+)="([^"]*)"', m.group(1)))
        key = attrs.get(b"Name", b"points").decode()
        if key not in wanted or attrs[b"type"] != b"Float64":
            continue
        off = int(attrs[b"offset"])
        size = struct.unpack("<Q", blob[off : off + 8])[0]
        values = struct.unpack(f"<{size // 8}d", blob[off + 8 : off + 8 + size])
        nc = int(attrs.get(b"NumberOfComponents", b"1"))
        found[key] = [values[i : i + nc] for i in range(0, len(values), nc)] if nc > 1 else list(values)
    return found


def clay_in_band(path, a, grown, e_b, band):
    """The points of the clay that started `band` (from, to) m from the centre: their
    starting radii, their excess pore pressures at the last stage and the reference's at
    each point's strain, e = ln(rho/rho0) with rho^3 = rho0^3 + (a^3 - a0^3),
    u = sigma_r - 2q/3 - p' (sigma_r from the integral between e_b and e); `a` holds the
    last stage's points.vtu arrays (`vtu_arrays`)."""
    rho0s, engine, ref = [], [], []
    for x, d, u in zip(a["points"], a["displacement"], a["excess_pore_pressure"]):
        rho0 = math.hypot(x[0] - d[0], x[1] - d[1])
        if not band[0] < rho0 < band[1]:
            continue
        rho = (rho0**3 + grown) ** (1 / 3)
        e = math.log(rho / rho0)
        q, p = q_at(path, 2 * e)
        sigma_r = P0 + pressure(path, e, True, n=2000, e_b=e_b)
        rho0s.append(rho0)
        engine.append(u)
        ref.append(sigma_r - 2 * q / 3 - p)
    return rho0s, engine, ref


def near_wall(path, a, grown, e_b, band):
    """The clay that started `band` m from the centre (the first, from 1.075 m, about a cell
    out from the cavity's wall at a0 = 1 m, past the loaded points): its excess pore
    pressure at the last stage (mean, median, range) against the reference's mean
    (`clay_in_band`)."""
    _, engine, ref = clay_in_band(path, a, grown, e_b, band)
    if engine:
        mean = lambda v: sum(v) / len(v) / 1e3
        median = sorted(engine)[len(engine) // 2] / 1e3
        print(
            f"clay {band[0]}-{band[1]} m from the centre at the start ({len(engine)} points): "
            f"excess pore pressure mean {mean(engine):.1f} kPa, median {median:.1f} "
            f"({min(engine) / 1e3:.1f} to {max(engine) / 1e3:.1f}); "
            f"reference {mean(ref):.1f} kPa ({min(ref) / 1e3:.1f} to {max(ref) / 1e3:.1f})"
        )


def main():
    r_ocr = float(sys.argv[1]) if len(sys.argv) > 1 else 1.0
    path, pf = element(r_ocr)
    if len(sys.argv) > 2:
        if "--sphere" in sys.argv[3:]:
            rest = sys.argv[3:]
            near = float(rest[rest.index("--from") + 1]) if "--from" in rest else 1.075
            cell = float(rest[rest.index("--cell") + 1]) if "--cell" in rest else 0.1
            compare_sphere(path, sys.argv[2], near, cell)
        else:
            compare(path, sys.argv[2])
        return
    print(f"R = {r_ocr}: p'f = {pf / 1e3:.3f} kPa, s_u = {M * pf / 2e3:.3f} kPa")
    for sphere in (False, True):
        name = "sphere" if sphere else "cylinder"
        for ratio in (1.1, 1.2, 1.5, 2.0, 3.0, 5.0, 10.0, 1e3):
            e_a = math.log(ratio)
            psi = P0 + pressure(path, e_a, sphere)
            eq = (2 if sphere else 2 / math.sqrt(3)) * e_a
            q, p = q_at(path, eq)
            u = psi - (2 * q / 3 if sphere else q / math.sqrt(3)) - p
            print(f"{name:8s} a/a0 {ratio:7.1f}: psi {psi / 1e3:8.2f} kPa, wall u {u / 1e3:8.2f} kPa")


if __name__ == "__main__":
    main()
