"""Factors of safety of the Griffiths & Lane slope (scenes/slope_fos.ron) by Bishop's
simplified method and Spencer's method, computed by an independent, published
limit-equilibrium package: XSLOPE (Norman L. Jones, Brigham Young University; PyPI
`xslope`), with its own automatic search for the critical circle.

Run it with `studies/slope_lem.sh`, which installs the package in a virtual environment
under target/ and prints one table row a water condition, the same conditions the scenes
`slope_fos.ron`, `slope_water.ron`, `slope_reservoir.ron` and `slope_drawdown.ron` model.

The geometry is the scene's: toe at x = 15 m, crest at x = 35 m and 10 m up (a 2:1 face),
the crest running on to x = 55 m, a firm base at the toe's level (no circle goes below
y = 0). γ = 20 kN/m³ above the water and below it (the scenes give the soil one density
whether or not it is saturated), c′ = 10 kPa, φ′ = 20°, γ_w = 9.81 kN/m³. Pore pressure is
γ_w times the vertical depth below the piezometric line; where the line stands above the
ground the package applies the open water's pressure to the surface ("Water loads: auto").
"""

import os
import sys
import tempfile

import openpyxl
from xslope.fileio import load_slope_data
from xslope.search import run_lem_analysis

TEMPLATE = os.path.join(
    os.path.dirname(__import__("xslope").__file__), "resources", "input_template.xlsx"
)
GROUND = [(15.0, 0.0), (35.0, 10.0), (55.0, 10.0)]

# The water conditions: name → piezometric line (x, y), or None for a dry slope. Each
# matches the `water` of its scene.
CONDITIONS = {
    "dry (slope_fos.ron)": None,
    "water table (slope_water.ron)": [(0.0, 0.0), (15.0, 0.0), (35.0, 6.0), (55.0, 9.0)],
    "reservoir 5 m (slope_reservoir.ron)": [(0.0, 5.0), (55.0, 5.0)],
    "reservoir 10 m (slope_drawdown.ron, full)": [(0.0, 10.0), (55.0, 10.0)],
    "drawn down to 3 m (slope_drawdown.ron, drained)": [(0.0, 3.0), (55.0, 3.0)],
    "reservoir 6 m, table falling to 2 m (one polyline)": [(0.0, 6.0), (27.0, 6.0), (55.0, 2.0)],
}


def model(piezo, path):
    """Writes the XSLOPE workbook of one water condition to `path`."""
    wb = openpyxl.load_workbook(TEMPLATE)
    main = wb["main"]
    main["D8"] = "SI"
    main["D9"] = "sec"
    main["D10"] = 9.81
    mat = wb["mat"]
    for col, value in zip(
        "BCDEFGMN", ["soil", 20.0, 20.0, "mc", 10.0, 20.0, 100.0e3, 0.3]
    ):
        mat[f"{col}11"] = value
    mat["O11"] = "piezo" if piezo else "none"
    prof = wb["profile"]
    prof["B2"] = 0.0
    prof["B5"] = 1
    for k, (x, y) in enumerate(GROUND):
        prof[f"A{9 + k}"], prof[f"B{9 + k}"] = x, y
    if piezo:
        pz = wb["piezo"]
        pz["B3"] = "piezo"
        for k, (x, y) in enumerate(piezo):
            pz[f"A{5 + k}"], pz[f"B{5 + k}"] = x, y
    circ = wb["circles"]
    # A starting circle through the toe; the search moves and sizes it.
    circ["B3"], circ["C3"], circ["D3"], circ["E3"] = 25.0, 25.0, "Depth", 0.0
    wb.save(path)


def main():
    print("| condition | Bishop | Spencer |")
    print("|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        for name, piezo in CONDITIONS.items():
            path = os.path.join(tmp, "slope.xlsx")
            model(piezo, path)
            data = load_slope_data(path)
            fs = []
            for method in ("bishop", "spencer"):
                out = run_lem_analysis(data, method, announce=False)
                fs.append(out["results"]["FS"])
            print(f"| {name} | {fs[0]:.3f} | {fs[1]:.3f} |", flush=True)


if __name__ == "__main__":
    sys.exit(main())
