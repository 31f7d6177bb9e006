#!/usr/bin/env python3
"""The README's headline verification figures, run again and read the way the README
reads them, each beside the figure the README prints and the published value it is set
against.

A change that moves bits (a contact solve, a stopping rule, a kernel's order of
additions) has to say which figures moved and by how much: this runs the headline cases
one after the other and prints, for each, the figure now, the README's, the change
between them and the error on the published value. It is a script, not a test: the whole
set takes about an hour on one thread here (`--list` gives each case's time as last
measured), and a figure that moved is a finding to explain, not a failure.

    python3 studies/headline.py OUT                     # every case, into OUT/<case>/
    python3 studies/headline.py OUT --only tbar,cpt     # some of them
    python3 studies/headline.py OUT --quick             # those under a minute
    python3 studies/headline.py OUT --kdmpm PATH        # another build (default:
                                                        # target/release/kdmpm)
    python3 studies/headline.py --list

A case whose OUT/<case>/summary.json already exists is read, not run again (delete the
directory to run it again), so an interrupted sweep carries on where it stopped. The
cavity expansions have their own reader (`studies/cavity_mcc.py`), the piezocone's
closed form its own (`studies/cptu_cssm.py`).
"""

import argparse
import csv
import json
import os
import subprocess
import sys
import time

import cptu_cssm

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)

C_U = 10.0e3  # Pa, the Tresca clay's strength in the penetrometer and footing scenes
SIGMA_V0 = 100.0e3  # Pa, the confining stress round the cone and the pile


def curve(out):
    """curve.csv's rows as (name, displacement, force_x, force_y, pressure)."""
    def number(text):
        return float(text) if text else None  # a row without an area has no pressure

    with open(os.path.join(out, "curve.csv")) as f:
        return [(r["name"], float(r["displacement"]), float(r["force_x"]),
                 float(r["force_y"]), number(r.get("pressure"))) for r in csv.DictReader(f)]


def summary(out):
    with open(os.path.join(out, "summary.json")) as f:
        return json.load(f)


def limit(scale=1.0, offset=0.0):
    """The largest static pressure (summary.json's `limit_pressure`), (p − offset)/scale."""
    return lambda out: (summary(out)["limit_pressure"] - offset) / scale


def mean(row, start, scale=1.0, offset=0.0, with_start=False):
    """The mean pressure of `row`'s static states from the displacement `start` (m) on,
    (p − offset)/scale: a penetrometer's steady resistance. As docs/verification.md's
    tables read it: the states after `start` ("over 1–2 D" of the T-bar, the twenty states
    after 1 D of a push in D/20 increments), or from it on (`with_start`: the 3D ball's,
    the cones' and the pile's tables)."""

    def read(out):
        v = [p for n, d, _, _, p in curve(out)
             if n == row and (d > start + 1e-9 or (with_start and d > start - 1e-9))]
        return (sum(v) / len(v) - offset) / scale

    return read


def last_force_x(row, scale=1.0e3):
    """The horizontal force of `row` at its last static state (N/m), / scale."""
    return lambda out: [fx for n, _, fx, _, _ in curve(out) if n == row][-1] / scale


def traced(point, component):
    def read(out):
        for t in summary(out)["traced"]:
            if t["name"] == point:
                return t["displacement"][component]
        raise KeyError(point)

    return read


def angle(out):
    return summary(out)["surface_angle"]["degrees"]


def factor(out):
    return summary(out)["factor_of_safety"]


def piezocone_n_kt(out):
    """The mean N_kt of the log's last four rows with all three readings, as
    `studies/cptu_cssm.py` and docs/verification.md read the piezocone."""
    v = [n_kt for _, n_kt, _, _ in cptu_cssm.logged(out)[-4:]]
    return sum(v) / len(v)


RIGID = "rigid_bodies[0]"

# name, command, scene, overrides, reading, unit, the README's figure, the published
# value and its source, minutes on one thread here (as last measured, beside other runs)
CASES = [
    ("bar", "run", "bar.ron", [], traced("A", 0), "m", 4.918e-3,
     (4.75e-3, "Fx/(EA)"), 0.02),
    ("slope", "run", "slope.ron", [], angle, "°", 18.994, (18.9, "Davis's φ*"), 1.6),
    ("footing", "run", "footing.ron", [], limit(1e3), "kPa", 50.33, (51.42, "Prandtl"), 0.1),
    ("footing_cphi", "run", "footing_cphi.ron", [], limit(1e3), "kPa", 297.98,
     (301.4, "Prandtl–Reissner"), 0.5),
    ("footing_rigid", "run", "footing_rigid.ron", [], limit(1e3), "kPa", 57.40,
     (51.42, "Prandtl"), 0.1),
    ("footing_rigid_released", "run", "footing_rigid.ron", [f"{RIGID}.corners=Released"],
     limit(1e3), "kPa", 53.25, (51.42, "Prandtl"), 0.1),
    ("footing_circular", "run", "footing_circular.ron", [], limit(C_U), "N_c", 5.81,
     (5.69, "Eason & Shield"), 0.3),
    ("tbar", "run", "tbar.ron", [], mean("tbar", 1.0, scale=C_U), "N", 9.08,
     (9.14, "Randolph & Houlsby"), 5.5),
    ("tbar_rough", "run", "tbar.ron", [f"{RIGID}.interface=Rough"],
     mean("tbar", 1.0, scale=C_U), "N", 11.43, (11.94, "Randolph & Houlsby"), 6.5),
    ("ball", "run", "ball.ron", [], mean("ball", 1.0, scale=C_U), "N", 10.90,
     (11.0, "Randolph, Martin & Hu"), 1.5),
    ("ball_rough", "run", "ball.ron", [f"{RIGID}.interface=Rough"],
     mean("ball", 1.0, scale=C_U), "N", 14.40, (15.1, "Randolph, Martin & Hu"), 1.7),
    ("ball_3d", "run", "ball_3d.ron", [], mean("ball", 1.0, scale=C_U, with_start=True), "N",
     11.28, (11.0, "Randolph, Martin & Hu"), 4.5),
    ("passive_wall", "run", "passive_wall.ron", [], limit(0.5e3), "kN/m", 108.0,
     (105.9, "Rankine"), 1),
    ("passive_wall_rough", "run", "passive_wall_rough.ron", [], limit(0.5e3), "kN/m", 177.3,
     (177.5, "Lancellotta"), 4),
    ("passive_wall_cphi", "run", "passive_wall_cphi.ron", [],
     mean("wall", 0.03, scale=0.5e3), "kN/m", 147.5, (139.5, "Lancellotta, exact here"), 8.5),
    ("cpt", "run", "cpt.ron", [],
     mean("cone.tip", 5.0, scale=C_U, offset=SIGMA_V0, with_start=True), "N_kt", 11.78,
     (9.7, "Teh & Houlsby"), 8),
    ("cpt_sand", "run", "cpt_sand.ron",
     ["grid.cell_size=0.125", "grid.cells=[40, 208]", "tractions[0].min=[0.5, 13.875]"],
     mean("cone.tip", 3.75, scale=SIGMA_V0, with_start=True), "q_c/p0", 24.75,
     (None, "between 13.9 and 51, Vesić 1972 and 1977"), 9.5),
    ("cptu_clay", "run", "cptu_clay.ron", [], piezocone_n_kt, "N_kt", 12.20,
     (cptu_cssm.readings(1.0)[2], "SCE-CSSM (Mayne 1991), at R = 1"), 4.5),
    ("pile_jacking", "run", "pile_jacking.ron", [],
     mean("pile.base", 5.0, scale=C_U, offset=SIGMA_V0, with_start=True), "N_c", 13.62,
     (9.0, "Skempton"), 11),
    ("slope_fos", "fos", "slope_fos.ron", [], factor, "F", 1.383, (1.378, "Bishop"), 0.2),
    ("slope_water_fos", "fos", "slope_water.ron", [], factor, "F", 1.180,
     (1.182, "Bishop, XSLOPE"), 0.2),
    ("slope_reservoir_fos", "fos", "slope_reservoir.ron", [], factor, "F", 1.352,
     (1.351, "Bishop, XSLOPE"), 0.2),
    ("slope_drawdown_fos", "fos", "slope_drawdown.ron", [], factor, "F", 1.305,
     (1.302, "Bishop, XSLOPE"), 0.3),
    ("sliding_block", "run", "sliding_block.ron", [], last_force_x("push"), "kN/m", 14.07,
     (14.28, "tan δ · W"), 0.05),
    ("block_on_rigid_base", "run", "block_on_rigid_base.ron", [], last_force_x("wall"),
     "kN/m", 14.14, (14.28, "tan δ · W"), 0.3),
]


def main(argv):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("out", nargs="?", help="directory for the runs, one a case")
    parser.add_argument("--kdmpm", default=os.path.join(ROOT, "target", "release", "kdmpm"))
    parser.add_argument("--only", help="cases, comma-separated")
    parser.add_argument("--quick", action="store_true", help="the cases under a minute")
    parser.add_argument("--threads", default="1")
    parser.add_argument("--list", action="store_true")
    args = parser.parse_args(argv)
    if args.list:
        for c in CASES:
            print(f"{c[0]:24} {c[1]:4} scenes/{c[2]} {' '.join('--set ' + s for s in c[3])}"
                  f"  (about {c[8]:g} min)")
        return 0
    if args.out is None:
        parser.error("the output directory is needed")
    names = {c[0] for c in CASES}
    only = set(args.only.split(",")) if args.only else None
    if only is not None and not only <= names:
        parser.error(f"unknown cases: {sorted(only - names)}")
    cases = [c for c in CASES if (only is None or c[0] in only) and (not args.quick or c[8] < 1)]
    print("case | figure | README | change | published | error on it | wall (s)")
    for name, command, scene, sets, read, unit, readme, (published, source), _ in cases:
        out = os.path.join(args.out, name)
        wall = ""
        if not os.path.exists(os.path.join(out, "summary.json")):
            cmd = [args.kdmpm, command, os.path.join(ROOT, "scenes", scene), "--out", out, "-q"]
            cmd += [x for s in sets for x in ("--set", s)] + ["--threads", args.threads]
            t0 = time.time()
            done = subprocess.run(cmd)
            wall = f"{time.time() - t0:.0f}"
            if done.returncode != 0:
                print(f"{name} | exit {done.returncode} | {readme:g} | | {source} | | {wall}")
                continue
        value = read(out)
        change = (value / readme - 1) * 100
        if published is None:
            against = f"{source} | "
        else:
            against = f"{published:g} ({source}) | {(value / published - 1) * 100:+.1f} %"
        print(f"{name} | {value:.6g} {unit} | {readme:g} | {change:+.2f} % | {against} | {wall}",
              flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
