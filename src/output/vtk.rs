//! Material points as a VTK XML unstructured grid (`.vtu`) with raw binary arrays, readable
//! by ParaView, VisIt, meshio and pyvista.

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
/// (Pa, tension positive: xx yy zz xy yz zx), mean stress (Pa), volume (m³) and
/// accumulated plastic strain (0 for bodies without plastic state).
///
/// The arrays are raw little-endian binary in the file's appended section (VTK XML's
/// `format="appended"`, `encoding="raw"`, 64-bit block headers), the form ParaView itself
/// writes: every value to the last bit, at about half the size of decimal text and without
/// the cost of formatting it (a million points: 120 MB).
///
/// The file is streamed array by array straight from the columns: besides the buffered
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
    // Displacements only when the scene keeps them (`output.displacements`).
    let displacements = n > 0 && archs.iter().all(|a| a.has::<Displacement<D::Vec>>());

    let mut arrays = vec![
        Array::new("Points", "Float64", 3, n),
        Array::new("connectivity", "Int64", 1, n),
        Array::new("offsets", "Int64", 1, n),
        Array::new("types", "UInt8", 1, n),
        Array::new("id", "UInt32", 1, n),
    ];
    if displacements {
        arrays.push(Array::new("displacement", "Float64", 3, n));
    }
    arrays.extend([
        Array::new("stress", "Float64", 6, n),
        Array::new("mean_stress", "Float64", 1, n),
        Array::new("volume", "Float64", 1, n),
        Array::new("plastic_strain", "Float64", 1, n),
    ]);
    let mut offset = 0;
    for array in &mut arrays {
        array.offset = offset;
        offset += 8 + array.bytes;
    }
    let tag = |name: &str| {
        let a = arrays.iter().find(|a| a.name == name).expect("listed above");
        let named = if name == "Points" {
            String::new()
        } else {
            format!(" Name=\"{name}\"")
        };
        // Scalars leave the component count at VTK's default of one, so that readers give
        // them one dimension.
        let components = if a.components == 1 {
            String::new()
        } else {
            format!(" NumberOfComponents=\"{}\"", a.components)
        };
        format!(
            "<DataArray type=\"{}\"{named}{components} format=\"appended\" offset=\"{}\"/>\n",
            a.kind, a.offset
        )
    };

    let mut out = BufWriter::with_capacity(1 << 20, File::create(path)?);
    out.write_all(b"<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n")?;
    writeln!(
        out,
        "<UnstructuredGrid><Piece NumberOfPoints=\"{n}\" NumberOfCells=\"{n}\">"
    )?;
    write!(out, "<Points>\n{}</Points>\n<Cells>\n", tag("Points"))?;
    for name in ["connectivity", "offsets", "types"] {
        out.write_all(tag(name).as_bytes())?;
    }
    out.write_all(b"</Cells>\n<PointData>\n")?;
    for array in arrays.iter().filter(|a| a.point_data()) {
        out.write_all(tag(array.name).as_bytes())?;
    }
    out.write_all(b"</PointData>\n</Piece></UnstructuredGrid>\n<AppendedData encoding=\"raw\">\n_")?;

    // Each block: its length in bytes (UInt64), then the values, in the order listed.
    let block = |out: &mut BufWriter<File>, name: &str| {
        let a = arrays.iter().find(|a| a.name == name).expect("listed above");
        out.write_all(&(a.bytes as u64).to_le_bytes())
    };
    block(&mut out, "Points")?;
    each::<Position<D::Vec>>(&archs, &order, &mut out, |out, x| f64s(out, &D::vec_to3(x.0)))?;
    // One vertex cell per point.
    block(&mut out, "connectivity")?;
    for i in 0..n as i64 {
        out.write_all(&i.to_le_bytes())?;
    }
    block(&mut out, "offsets")?;
    for i in 1..=n as i64 {
        out.write_all(&i.to_le_bytes())?;
    }
    block(&mut out, "types")?;
    for _ in 0..n {
        out.write_all(&[VTK_VERTEX])?;
    }
    block(&mut out, "id")?;
    for (id, _, _) in order.points() {
        out.write_all(&(id as u32).to_le_bytes())?;
    }
    if displacements {
        block(&mut out, "displacement")?;
        each::<Displacement<D::Vec>>(&archs, &order, &mut out, |out, u| f64s(out, &D::vec_to3(u.0)))?;
    }
    block(&mut out, "stress")?;
    each::<Stress>(&archs, &order, &mut out, |out, s| {
        let s = &s.0;
        f64s(out, &[s.xx, s.yy, s.zz, s.xy, s.yz, s.zx])
    })?;
    block(&mut out, "mean_stress")?;
    each::<Stress>(&archs, &order, &mut out, |out, s| f64s(out, &[s.0.trace() / 3.0]))?;
    block(&mut out, "volume")?;
    each::<Volume>(&archs, &order, &mut out, |out, v| f64s(out, &[v.0]))?;
    block(&mut out, "plastic_strain")?;
    let plastic: Vec<_> = archs.iter().map(|a| a.get::<&PlasticStrain>()).collect();
    for (_, a, r) in order.points() {
        let e = plastic[a].as_ref().map_or(0.0, |e| e[r].0);
        f64s(&mut out, &[e])?;
    }
    out.write_all(b"\n</AppendedData>\n</VTKFile>\n")?;
    out.flush()
}

/// VTK's cell type of a single point.
const VTK_VERTEX: u8 = 1;

/// One array of the appended section: what the XML head says of it.
struct Array {
    name: &'static str,
    /// VTK's name of the value type.
    kind: &'static str,
    components: usize,
    /// Length of the values in bytes (without the block's 8-byte header).
    bytes: usize,
    /// Where the block starts, in bytes after the `_` that opens the appended section.
    offset: usize,
}

impl Array {
    /// True for the fields of `<PointData>`, false for the points and cells.
    fn point_data(&self) -> bool {
        !matches!(self.name, "Points" | "connectivity" | "offsets" | "types")
    }

    fn new(name: &'static str, kind: &'static str, components: usize, points: usize) -> Self {
        let size = match kind {
            "Float64" | "Int64" => 8,
            "UInt32" => 4,
            _ => 1,
        };
        Array {
            name,
            kind,
            components,
            bytes: points * components * size,
            offset: 0,
        }
    }
}

/// Writes `values` as little-endian f64.
fn f64s(out: &mut BufWriter<File>, values: &[f64]) -> std::io::Result<()> {
    for v in values {
        out.write_all(&v.to_le_bytes())?;
    }
    Ok(())
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
