//! Material points as a VTK XML unstructured grid (`.vtu`), readable by ParaView.

use crate::columns::{col, points_with};
use crate::components::*;
use crate::dim::Dim;
use crate::simulation::Simulation;
use std::fmt::Write as _;
use std::path::Path;

/// Writes every material point (load carriers excluded) in [`PointId`] order, whatever
/// order the spatial sort left them in, with its id, displacement (m, when kept), stress
/// (Pa, tension positive: xx yy zz xy yz zx), mean stress (Pa), volume (m³) and, when
/// present, accumulated plastic strain.
pub fn write_points<D: Dim>(sim: &Simulation<D>, path: &Path) -> std::io::Result<()> {
    let (mut ids, mut xs, mut us, mut ss, mut vols, mut eps) = (
        Vec::new(),
        Vec::new(),
        Vec::new(),
        Vec::new(),
        Vec::new(),
        Vec::new(),
    );
    for arch in points_with::<Stress>(&sim.ctx.world) {
        let plastic = arch.get::<&PlasticStrain>();
        let displacement = arch.get::<&Displacement<D::Vec>>();
        ids.extend(col::<PointId>(arch).iter().map(|id| id.0));
        for (p, (x, (s, v))) in col::<Position<D::Vec>>(arch)
            .iter()
            .zip(col::<Stress>(arch).iter().zip(col::<Volume>(arch).iter()))
            .enumerate()
        {
            xs.push(D::vec_to3(x.0));
            if let Some(u) = &displacement {
                us.push(D::vec_to3(u[p].0));
            }
            ss.push(s.0);
            vols.push(v.0);
            eps.push(plastic.as_ref().map_or(0.0, |e| e[p].0));
        }
    }
    let n = xs.len();
    let mut rows: Vec<usize> = (0..n).collect();
    rows.sort_unstable_by_key(|&r| ids[r]);
    let mut out = String::with_capacity(n * 200);
    out.push_str("<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" byte_order=\"LittleEndian\">\n");
    let _ = writeln!(
        out,
        "<UnstructuredGrid><Piece NumberOfPoints=\"{n}\" NumberOfCells=\"{n}\">"
    );
    out.push_str("<Points><DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n");
    for x in rows.iter().map(|&r| &xs[r]) {
        let _ = writeln!(out, "{:e} {:e} {:e}", x[0], x[1], x[2]);
    }
    out.push_str(
        "</DataArray></Points>\n<Cells>\n<DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n",
    );
    for i in 0..n {
        let _ = write!(out, "{i} ");
    }
    out.push_str("\n</DataArray>\n<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n");
    for i in 0..n {
        let _ = write!(out, "{} ", i + 1);
    }
    out.push_str("\n</DataArray>\n<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n");
    out.push_str(&"1 ".repeat(n));
    out.push_str("\n</DataArray>\n</Cells>\n<PointData>\n");
    out.push_str("<DataArray type=\"UInt32\" Name=\"id\" format=\"ascii\">\n");
    for r in &rows {
        let _ = write!(out, "{} ", ids[*r]);
    }
    out.push_str("\n</DataArray>\n");
    // Displacements only when the scene keeps them (`output.displacements`).
    if us.len() == n && n > 0 {
        out.push_str(
            "<DataArray type=\"Float64\" Name=\"displacement\" NumberOfComponents=\"3\" format=\"ascii\">\n",
        );
        for u in rows.iter().map(|&r| &us[r]) {
            let _ = writeln!(out, "{:e} {:e} {:e}", u[0], u[1], u[2]);
        }
        out.push_str("</DataArray>\n");
    }
    out.push_str("<DataArray type=\"Float64\" Name=\"stress\" NumberOfComponents=\"6\" format=\"ascii\">\n");
    for s in rows.iter().map(|&r| &ss[r]) {
        let _ = writeln!(
            out,
            "{:e} {:e} {:e} {:e} {:e} {:e}",
            s.xx, s.yy, s.zz, s.xy, s.yz, s.zx
        );
    }
    out.push_str("</DataArray>\n<DataArray type=\"Float64\" Name=\"mean_stress\" format=\"ascii\">\n");
    for s in rows.iter().map(|&r| &ss[r]) {
        let _ = writeln!(out, "{:e}", s.trace() / 3.0);
    }
    out.push_str("</DataArray>\n<DataArray type=\"Float64\" Name=\"volume\" format=\"ascii\">\n");
    for v in rows.iter().map(|&r| &vols[r]) {
        let _ = writeln!(out, "{v:e}");
    }
    out.push_str("</DataArray>\n<DataArray type=\"Float64\" Name=\"plastic_strain\" format=\"ascii\">\n");
    for e in rows.iter().map(|&r| &eps[r]) {
        let _ = writeln!(out, "{e:e}");
    }
    out.push_str("</DataArray>\n</PointData>\n</Piece></UnstructuredGrid>\n</VTKFile>\n");
    std::fs::write(path, out)
}
