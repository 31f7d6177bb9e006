//! Material points as a VTK XML unstructured grid (`.vtu`) with raw binary arrays, readable
//! by ParaView, VisIt, meshio and pyvista.

use crate::columns::{col, points_with};
use crate::components::*;
use crate::dim::Dim;
use crate::simulation::Simulation;
use crate::tensor::StoredSym;
use hecs::{Archetype, Component};
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

/// Writes (whole or not at all, see [`crate::output::dir::write_atomic`]) every material
/// point (load carriers excluded) in [`PointId`] order, whatever
/// order the spatial sort left them in, with its id, displacement (m, when kept), stress
/// (Pa, tension positive: xx yy zz xy yz zx), mean stress (Pa), volume (m³) and
/// accumulated plastic strain (0 for bodies without plastic state).
///
/// The arrays are raw little-endian binary in the file's appended section (VTK XML's
/// `format="appended"`, `encoding="raw"`, 64-bit block headers), the form ParaView itself
/// writes: every value to the last bit, at about half the size of decimal text and without
/// the cost of formatting it (a million points: 117 MB).
///
/// The file is streamed array by array straight from the columns: besides the buffered
/// writer, writing holds 8 bytes a point (where each id is), so output does not raise the
/// run's peak memory.
pub fn write_points<D: Dim>(sim: &Simulation<D>, path: &Path) -> std::io::Result<()> {
    let archs: Vec<&Archetype> = points_with::<Stress<D::Stress>>(&sim.ctx.world).collect();
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

    let plastic: Vec<_> = archs.iter().map(|a| a.get::<&PlasticStrain>()).collect();
    // Every array with the writer of its values. The XML head and the appended section are
    // both made from this one list, so the offsets cannot disagree with the blocks.
    let mut arrays: Vec<Array> = vec![
        Array::new(Part::Points, "Points", Kind::Float64, 3, n, |out| {
            each::<Position<D::Vec>>(&archs, &order, out, |out, x| f64s(out, &D::vec_to3(x.0)))
        }),
        // One vertex cell per point.
        Array::new(Part::Cells, "connectivity", Kind::Int64, 1, n, |out| {
            (0..n as i64).try_for_each(|i| out.write_all(&i.to_le_bytes()))
        }),
        Array::new(Part::Cells, "offsets", Kind::Int64, 1, n, |out| {
            (1..=n as i64).try_for_each(|i| out.write_all(&i.to_le_bytes()))
        }),
        Array::new(Part::Cells, "types", Kind::UInt8, 1, n, |out| {
            (0..n).try_for_each(|_| out.write_all(&[VTK_VERTEX]))
        }),
        Array::new(Part::PointData, "id", Kind::UInt32, 1, n, |out| {
            order
                .points()
                .try_for_each(|(id, _, _)| out.write_all(&(id as u32).to_le_bytes()))
        }),
    ];
    if displacements {
        arrays.push(Array::new(
            Part::PointData,
            "displacement",
            Kind::Float64,
            3,
            n,
            |out| each::<Displacement<D::Vec>>(&archs, &order, out, |out, u| f64s(out, &D::vec_to3(u.0))),
        ));
    }
    arrays.extend([
        Array::new(Part::PointData, "stress", Kind::Float64, 6, n, |out| {
            each::<Stress<D::Stress>>(&archs, &order, out, |out, s| {
                let s = s.0.to_sym3();
                f64s(out, &[s.xx, s.yy, s.zz, s.xy, s.yz, s.zx])
            })
        }),
        Array::new(Part::PointData, "mean_stress", Kind::Float64, 1, n, |out| {
            each::<Stress<D::Stress>>(&archs, &order, out, |out, s| {
                f64s(out, &[s.0.to_sym3().trace() / 3.0])
            })
        }),
        Array::new(Part::PointData, "volume", Kind::Float64, 1, n, |out| {
            each::<Volume>(&archs, &order, out, |out, v| f64s(out, &[v.0]))
        }),
        // Bodies without plastic state (elastic) write zero.
        Array::new(Part::PointData, "plastic_strain", Kind::Float64, 1, n, |out| {
            order
                .points()
                .try_for_each(|(_, a, r)| f64s(out, &[plastic[a].as_ref().map_or(0.0, |e| e[r].0)]))
        }),
    ]);
    let mut offset = 0;
    for array in &mut arrays {
        array.offset = offset;
        offset += 8 + array.bytes;
    }

    crate::output::dir::write_atomic(path, |out| write_arrays(out, n, &arrays))
}

/// The XML head and the appended section of [`write_points`].
fn write_arrays(out: &mut BufWriter<File>, n: usize, arrays: &[Array]) -> std::io::Result<()> {
    out.write_all(b"<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n")?;
    writeln!(
        out,
        "<UnstructuredGrid><Piece NumberOfPoints=\"{n}\" NumberOfCells=\"{n}\">"
    )?;
    for (section, part) in [
        ("Points", Part::Points),
        ("Cells", Part::Cells),
        ("PointData", Part::PointData),
    ] {
        writeln!(out, "<{section}>")?;
        for array in arrays.iter().filter(|a| a.part == part) {
            array.tag(out)?;
        }
        writeln!(out, "</{section}>")?;
    }
    out.write_all(b"</Piece></UnstructuredGrid>\n<AppendedData encoding=\"raw\">\n_")?;
    // Each block: its length in bytes (UInt64), then the values.
    for array in arrays {
        out.write_all(&(array.bytes as u64).to_le_bytes())?;
        (array.values)(out)?;
    }
    out.write_all(b"\n</AppendedData>\n</VTKFile>\n")?;
    out.flush()
}

/// VTK's cell type of a single point.
const VTK_VERTEX: u8 = 1;

/// Writes the values of one array to the file.
type Values<'a> = Box<dyn Fn(&mut BufWriter<File>) -> std::io::Result<()> + 'a>;

/// The value types the file uses.
#[derive(Clone, Copy, Debug)]
enum Kind {
    Float64,
    Int64,
    UInt32,
    UInt8,
}

impl Kind {
    /// VTK's name of the type.
    fn name(self) -> &'static str {
        match self {
            Kind::Float64 => "Float64",
            Kind::Int64 => "Int64",
            Kind::UInt32 => "UInt32",
            Kind::UInt8 => "UInt8",
        }
    }

    /// Bytes a value.
    fn size(self) -> usize {
        match self {
            Kind::Float64 | Kind::Int64 => 8,
            Kind::UInt32 => 4,
            Kind::UInt8 => 1,
        }
    }
}

/// One array of the appended section and the writer of its values.
struct Array<'a> {
    part: Part,
    name: &'static str,
    kind: Kind,
    components: usize,
    /// Length of the values in bytes (without the block's 8-byte header).
    bytes: usize,
    /// Where the block starts, in bytes after the `_` that opens the appended section.
    offset: usize,
    values: Values<'a>,
}

/// The element of a piece an array belongs to.
#[derive(Clone, Copy, PartialEq)]
enum Part {
    Points,
    Cells,
    PointData,
}

impl<'a> Array<'a> {
    fn new(
        part: Part,
        name: &'static str,
        kind: Kind,
        components: usize,
        points: usize,
        values: impl Fn(&mut BufWriter<File>) -> std::io::Result<()> + 'a,
    ) -> Self {
        Array {
            part,
            name,
            kind,
            components,
            bytes: points * components * kind.size(),
            offset: 0,
            values: Box::new(values),
        }
    }

    /// The array's `DataArray` element in the XML head.
    fn tag(&self, out: &mut BufWriter<File>) -> std::io::Result<()> {
        write!(out, "<DataArray type=\"{}\"", self.kind.name())?;
        // The points are the one unnamed array.
        if self.part != Part::Points {
            write!(out, " Name=\"{}\"", self.name)?;
        }
        // Scalars leave the component count at VTK's default of one, so that readers give
        // them one dimension.
        if self.components > 1 {
            write!(out, " NumberOfComponents=\"{}\"", self.components)?;
        }
        writeln!(out, " format=\"appended\" offset=\"{}\"/>", self.offset)
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
