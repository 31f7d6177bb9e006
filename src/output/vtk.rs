//! Material points as a VTK XML unstructured grid (`.vtu`), readable by ParaView.

use crate::columns::{col, points_with};
use crate::components::*;
use crate::dim::Dim;
use crate::simulation::Simulation;
use hecs::{Archetype, Component};
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

/// Writes every material point (load carriers excluded) in [`PointId`] order, whatever
/// order the spatial sort left them in, with its id, displacement (m, when kept), stress
/// (Pa, tension positive: xx yy zz xy yz zx), mean stress (Pa), volume (m³) and, when
/// present, accumulated plastic strain.
///
/// The file is streamed field by field straight from the columns: besides the buffered
/// writer, writing holds 8 bytes a point (where each id is), so output does not raise the
/// run's peak memory.
pub fn write_points<D: Dim>(sim: &Simulation<D>, path: &Path) -> std::io::Result<()> {
    let archs: Vec<&Archetype> = points_with::<Stress>(&sim.ctx.world).collect();
    // Where the point of each id is: archetype in the high half, row in the low half (the
    // load carriers' ids are gaps).
    let n = archs.iter().map(|a| a.len() as usize).sum::<usize>();
    let mut at = Vec::with_capacity(n);
    for (a, arch) in archs.iter().enumerate() {
        for (r, id) in col::<PointId>(arch).iter().enumerate() {
            id.place(&mut at, (a as u64) << 32 | r as u64, NONE);
        }
    }
    let order = Order(at);
    let mut out = BufWriter::with_capacity(1 << 20, File::create(path)?);
    out.write_all(b"<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" byte_order=\"LittleEndian\">\n")?;
    writeln!(
        out,
        "<UnstructuredGrid><Piece NumberOfPoints=\"{n}\" NumberOfCells=\"{n}\">"
    )?;
    out.write_all(b"<Points><DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n")?;
    each::<Position<D::Vec>>(&archs, &order, &mut out, |out, x| {
        let x = D::vec_to3(x.0);
        writeln!(out, "{:e} {:e} {:e}", x[0], x[1], x[2])
    })?;
    out.write_all(b"</DataArray></Points>\n<Cells>\n<DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n")?;
    for i in 0..n {
        write!(out, "{i} ")?;
    }
    out.write_all(b"\n</DataArray>\n<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n")?;
    for i in 0..n {
        write!(out, "{} ", i + 1)?;
    }
    out.write_all(b"\n</DataArray>\n<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n")?;
    for _ in 0..n {
        out.write_all(b"1 ")?;
    }
    out.write_all(b"\n</DataArray>\n</Cells>\n<PointData>\n")?;
    out.write_all(b"<DataArray type=\"UInt32\" Name=\"id\" format=\"ascii\">\n")?;
    for (id, _, _) in order.points() {
        write!(out, "{id} ")?;
    }
    out.write_all(b"\n</DataArray>\n")?;
    // Displacements only when the scene keeps them (`output.displacements`).
    if n > 0 && archs.iter().all(|a| a.has::<Displacement<D::Vec>>()) {
        out.write_all(
            b"<DataArray type=\"Float64\" Name=\"displacement\" NumberOfComponents=\"3\" format=\"ascii\">\n",
        )?;
        each::<Displacement<D::Vec>>(&archs, &order, &mut out, |out, u| {
            let u = D::vec_to3(u.0);
            writeln!(out, "{:e} {:e} {:e}", u[0], u[1], u[2])
        })?;
        out.write_all(b"</DataArray>\n")?;
    }
    out.write_all(
        b"<DataArray type=\"Float64\" Name=\"stress\" NumberOfComponents=\"6\" format=\"ascii\">\n",
    )?;
    each::<Stress>(&archs, &order, &mut out, |out, s| {
        let s = &s.0;
        writeln!(
            out,
            "{:e} {:e} {:e} {:e} {:e} {:e}",
            s.xx, s.yy, s.zz, s.xy, s.yz, s.zx
        )
    })?;
    out.write_all(b"</DataArray>\n<DataArray type=\"Float64\" Name=\"mean_stress\" format=\"ascii\">\n")?;
    each::<Stress>(&archs, &order, &mut out, |out, s| {
        writeln!(out, "{:e}", s.0.trace() / 3.0)
    })?;
    out.write_all(b"</DataArray>\n<DataArray type=\"Float64\" Name=\"volume\" format=\"ascii\">\n")?;
    each::<Volume>(&archs, &order, &mut out, |out, v| writeln!(out, "{:e}", v.0))?;
    out.write_all(b"</DataArray>\n<DataArray type=\"Float64\" Name=\"plastic_strain\" format=\"ascii\">\n")?;
    // Bodies without plastic state (elastic) write zero.
    let plastic: Vec<_> = archs.iter().map(|a| a.get::<&PlasticStrain>()).collect();
    for (_, a, r) in order.points() {
        let e = plastic[a].as_ref().map_or(0.0, |e| e[r].0);
        writeln!(out, "{e:e}")?;
    }
    out.write_all(b"</DataArray>\n</PointData>\n</Piece></UnstructuredGrid>\n</VTKFile>\n")?;
    out.flush()
}

/// No point has this id.
const NONE: u64 = u64::MAX;

/// Archetype and row of the point of each id (`NONE` where no point has it).
struct Order(Vec<u64>);

impl Order {
    /// (id, archetype, row) of every point, in id order.
    fn points(&self) -> impl Iterator<Item = (usize, usize, usize)> + '_ {
        self.0
            .iter()
            .enumerate()
            .filter(|(_, &at)| at != NONE)
            .map(|(id, &at)| (id, (at >> 32) as usize, (at & 0xFFFF_FFFF) as usize))
    }
}

/// Writes `field(value)` for the `T` of every point, in id order.
fn each<T: Component>(
    archs: &[&Archetype],
    order: &Order,
    out: &mut BufWriter<File>,
    mut field: impl FnMut(&mut BufWriter<File>, &T) -> std::io::Result<()>,
) -> std::io::Result<()> {
    let columns: Vec<_> = archs.iter().map(|a| col::<T>(a)).collect();
    for (_, a, r) in order.points() {
        field(out, &columns[a][r])?;
    }
    Ok(())
}
