//! Material points as a VTK XML unstructured grid (`.vtu`) with raw binary arrays, readable
//! by ParaView, VisIt, meshio and pyvista.

use crate::columns::{col, points_with};
use crate::components::*;
use crate::dim::Dim;
use crate::simulation::Simulation;
use crate::tensor::StoredSym;
use hecs::{Archetype, Component, World};
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

/// The point fields of a `.vtu` file, each written in [`PointId`] order.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Field {
    Position,
    Id,
    Material,
    Displacement,
    Velocity,
    Stress,
    MeanStress,
    DeviatoricStress,
    Volume,
    PlasticStrain,
}

/// Where a file's values come from: the live columns ([`write_points`]) or a copy taken
/// for the writer thread ([`Frame`]). One list of arrays ([`arrays`]) serves both.
trait Source {
    /// Number of points.
    fn len(&self) -> usize;
    /// True when displacements are kept (`output.displacements`).
    fn has_displacement(&self) -> bool;
    /// Writes `field` of every point, in id order.
    fn write(&self, field: Field, out: &mut BufWriter<File>) -> std::io::Result<()>;
}

/// A point's stress as written: xx yy zz xy yz zx (Pa).
fn voigt<D: Dim>(s: &Stress<D::Stress>) -> [f64; 6] {
    let s = s.0.to_sym3();
    [s.xx, s.yy, s.zz, s.xy, s.yz, s.zx]
}

/// The mean stress p = tr σ / 3 and the deviatoric stress q = √(3 J₂) (Pa) of a stress
/// (xx yy zz xy yz zx).
fn invariants(s: &[f64; 6]) -> (f64, f64) {
    let p = (s[0] + s[1] + s[2]) / 3.0;
    let (dx, dy, dz) = (s[0] - p, s[1] - p, s[2] - p);
    let j2 = 0.5 * (dx * dx + dy * dy + dz * dz) + s[3] * s[3] + s[4] * s[4] + s[5] * s[5];
    (p, (3.0 * j2).sqrt())
}

/// Every array of a points file: the XML head and the appended section are both made from
/// this one list, so the offsets cannot disagree with the blocks.
fn arrays<S: Source>(src: &S) -> Vec<Array<'_>> {
    let n = src.len();
    let field = |f: Field| move |out: &mut BufWriter<File>| src.write(f, out);
    let mut arrays = vec![
        Array::new(
            Part::Points,
            "Points",
            Kind::Float64,
            3,
            n,
            field(Field::Position),
        ),
        // One vertex cell per point.
        Array::new(Part::Cells, "connectivity", Kind::Int64, 1, n, move |out| {
            (0..n as i64).try_for_each(|i| out.write_all(&i.to_le_bytes()))
        }),
        Array::new(Part::Cells, "offsets", Kind::Int64, 1, n, move |out| {
            (1..=n as i64).try_for_each(|i| out.write_all(&i.to_le_bytes()))
        }),
        Array::new(Part::Cells, "types", Kind::UInt8, 1, n, move |out| {
            (0..n).try_for_each(|_| out.write_all(&[VTK_VERTEX]))
        }),
        Array::new(Part::PointData, "id", Kind::UInt32, 1, n, field(Field::Id)),
        Array::new(
            Part::PointData,
            "material",
            Kind::UInt32,
            1,
            n,
            field(Field::Material),
        ),
    ];
    if src.has_displacement() {
        arrays.push(Array::new(
            Part::PointData,
            "displacement",
            Kind::Float64,
            3,
            n,
            field(Field::Displacement),
        ));
    }
    // Bodies without plastic state (elastic) write a plastic strain of zero.
    for (name, components, f) in [
        ("velocity", 3, Field::Velocity),
        ("stress", 6, Field::Stress),
        ("mean_stress", 1, Field::MeanStress),
        ("deviatoric_stress", 1, Field::DeviatoricStress),
        ("volume", 1, Field::Volume),
        ("plastic_strain", 1, Field::PlasticStrain),
    ] {
        arrays.push(Array::new(
            Part::PointData,
            name,
            Kind::Float64,
            components,
            n,
            field(f),
        ));
    }
    let mut offset = 0;
    for array in &mut arrays {
        array.offset = offset;
        offset += 8 + array.bytes;
    }
    arrays
}

/// Writes (whole or not at all, see [`crate::output::dir::write_atomic`]) every material
/// point (load carriers excluded) in [`PointId`] order, whatever order the spatial sort
/// left them in, with its id, material (index in the scene's name order), displacement (m,
/// when kept), velocity (m/s), stress (Pa, tension positive: xx yy zz xy yz zx), mean
/// stress p and deviatoric stress q = √(3J₂) (Pa), volume (m³) and accumulated plastic
/// strain (0 for bodies without plastic state).
///
/// The arrays are raw little-endian binary in the file's appended section (VTK XML's
/// `format="appended"`, `encoding="raw"`, 64-bit block headers), the form ParaView itself
/// writes: every value to the last bit, at about half the size of decimal text and without
/// the cost of formatting it.
///
/// The file is streamed array by array straight from the columns: besides the buffered
/// writer, writing holds 8 bytes a point (where each id is), so the final output does not
/// raise the run's peak memory. Snapshots during a run copy the points into a [`Frame`]
/// instead, for the writer thread.
pub fn write_points<D: Dim>(sim: &Simulation<D>, path: &Path) -> std::io::Result<()> {
    let columns = Columns::<D>::of(&sim.ctx.world);
    let arrays = arrays(&columns);
    crate::output::dir::write_atomic(path, |out| write_arrays(out, columns.len(), &arrays))
}

/// Writes a [`Frame`] as [`write_points`] writes the live points.
pub fn write_frame(frame: &Frame, path: &Path) -> std::io::Result<()> {
    let arrays = arrays(frame);
    crate::output::dir::write_atomic(path, |out| write_arrays(out, frame.len(), &arrays))
}

/// The live point columns, in id order.
struct Columns<'a, D: Dim> {
    archs: Vec<&'a Archetype>,
    order: Order,
    n: usize,
    displacements: bool,
    _marker: std::marker::PhantomData<fn() -> D>,
}

impl<'a, D: Dim> Columns<'a, D> {
    fn of(world: &'a World) -> Self {
        let archs: Vec<&Archetype> = points_with::<Stress<D::Stress>>(world).collect();
        // Where the point of each id is: archetype in the high half, row in the low half (the
        // load carriers' ids are gaps).
        let n = archs.iter().map(|a| a.len() as usize).sum::<usize>();
        let mut at = Vec::with_capacity(n);
        for (a, arch) in archs.iter().enumerate() {
            for (r, id) in col::<PointId>(arch).iter().enumerate() {
                id.place(&mut at, (a as u64) << 32 | r as u64, NONE);
            }
        }
        // Displacements only when the scene keeps them (`output.displacements`).
        let displacements = n > 0 && archs.iter().all(|a| a.has::<Displacement<D::Vec>>());
        Columns {
            archs,
            order: Order(at),
            n,
            displacements,
            _marker: std::marker::PhantomData,
        }
    }
}

impl<D: Dim> Source for Columns<'_, D> {
    fn len(&self) -> usize {
        self.n
    }
    fn has_displacement(&self) -> bool {
        self.displacements
    }
    fn write(&self, field: Field, out: &mut BufWriter<File>) -> std::io::Result<()> {
        let (archs, order) = (&self.archs[..], &self.order);
        match field {
            Field::Position => {
                each::<Position<D::Vec>>(archs, order, out, |out, x| f64s(out, &D::vec_to3(x.0)))
            }
            Field::Id => order
                .points()
                .try_for_each(|(id, _, _)| out.write_all(&(id as u32).to_le_bytes())),
            Field::Material => each::<MaterialId>(archs, order, out, |out, m| {
                out.write_all(&u32::from(m.0).to_le_bytes())
            }),
            Field::Displacement => {
                each::<Displacement<D::Vec>>(archs, order, out, |out, u| f64s(out, &D::vec_to3(u.0)))
            }
            Field::Velocity => {
                each::<Velocity<D::Vec>>(archs, order, out, |out, v| f64s(out, &D::vec_to3(v.0)))
            }
            Field::Stress => each::<Stress<D::Stress>>(archs, order, out, |out, s| f64s(out, &voigt::<D>(s))),
            Field::MeanStress => each::<Stress<D::Stress>>(archs, order, out, |out, s| {
                f64s(out, &[invariants(&voigt::<D>(s)).0])
            }),
            Field::DeviatoricStress => each::<Stress<D::Stress>>(archs, order, out, |out, s| {
                f64s(out, &[invariants(&voigt::<D>(s)).1])
            }),
            Field::Volume => each::<Volume>(archs, order, out, |out, v| f64s(out, &[v.0])),
            Field::PlasticStrain => {
                let plastic: Vec<_> = archs.iter().map(|a| a.get::<&PlasticStrain>()).collect();
                order
                    .points()
                    .try_for_each(|(_, a, r)| f64s(out, &[plastic[a].as_ref().map_or(0.0, |e| e[r].0)]))
            }
        }
    }
}

/// A copy of every material point, in id order, for a snapshot written by another thread.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Frame {
    /// Step of the snapshot.
    pub step: u64,
    /// Simulated time (s).
    pub time: f64,
    /// Point ids.
    pub id: Vec<u32>,
    /// Material index (scene's name order).
    pub material: Vec<u16>,
    /// Positions (m, x y z).
    pub position: Vec<[f64; 3]>,
    /// Displacements (m), when the scene keeps them.
    pub displacement: Option<Vec<[f64; 3]>>,
    /// Velocities (m/s).
    pub velocity: Vec<[f64; 3]>,
    /// Stresses (Pa: xx yy zz xy yz zx).
    pub stress: Vec<[f64; 6]>,
    /// Volumes (m³).
    pub volume: Vec<f64>,
    /// Accumulated plastic strain (0 without plastic state).
    pub plastic_strain: Vec<f64>,
}

impl Frame {
    /// Copies the points of `world` at `step` and `time` (about 140 bytes a point).
    pub fn capture<D: Dim>(world: &World, step: u64, time: f64) -> Frame {
        let c = Columns::<D>::of(world);
        let (archs, order) = (&c.archs[..], &c.order);
        let mut f = Frame {
            step,
            time,
            ..Frame::default()
        };
        let n = c.n;
        f.id.reserve(n);
        for (id, _, _) in order.points() {
            f.id.push(id as u32);
        }
        gather::<MaterialId, _>(archs, order, &mut f.material, |m| m.0);
        gather::<Position<D::Vec>, _>(archs, order, &mut f.position, |x| D::vec_to3(x.0));
        if c.displacements {
            let mut u = Vec::with_capacity(n);
            gather::<Displacement<D::Vec>, _>(archs, order, &mut u, |u| D::vec_to3(u.0));
            f.displacement = Some(u);
        }
        gather::<Velocity<D::Vec>, _>(archs, order, &mut f.velocity, |v| D::vec_to3(v.0));
        gather::<Stress<D::Stress>, _>(archs, order, &mut f.stress, voigt::<D>);
        gather::<Volume, _>(archs, order, &mut f.volume, |v| v.0);
        let plastic: Vec<_> = archs.iter().map(|a| a.get::<&PlasticStrain>()).collect();
        f.plastic_strain = order
            .points()
            .map(|(_, a, r)| plastic[a].as_ref().map_or(0.0, |e| e[r].0))
            .collect();
        f
    }
}

/// Appends `value(T)` of every point, in id order.
fn gather<T: Component, V>(archs: &[&Archetype], order: &Order, into: &mut Vec<V>, value: impl Fn(&T) -> V) {
    let columns: Vec<_> = archs.iter().map(|a| col::<T>(a)).collect();
    into.extend(order.points().map(|(_, a, r)| value(&columns[a][r])));
}

impl Source for Frame {
    fn len(&self) -> usize {
        self.id.len()
    }
    fn has_displacement(&self) -> bool {
        self.displacement.is_some()
    }
    fn write(&self, field: Field, out: &mut BufWriter<File>) -> std::io::Result<()> {
        match field {
            Field::Position => self.position.iter().try_for_each(|x| f64s(out, x)),
            Field::Id => self.id.iter().try_for_each(|i| out.write_all(&i.to_le_bytes())),
            Field::Material => self
                .material
                .iter()
                .try_for_each(|m| out.write_all(&u32::from(*m).to_le_bytes())),
            Field::Displacement => self.displacement.iter().flatten().try_for_each(|u| f64s(out, u)),
            Field::Velocity => self.velocity.iter().try_for_each(|v| f64s(out, v)),
            Field::Stress => self.stress.iter().try_for_each(|s| f64s(out, s)),
            Field::MeanStress => self.stress.iter().try_for_each(|s| f64s(out, &[invariants(s).0])),
            Field::DeviatoricStress => self.stress.iter().try_for_each(|s| f64s(out, &[invariants(s).1])),
            Field::Volume => self.volume.iter().try_for_each(|v| f64s(out, &[*v])),
            Field::PlasticStrain => self.plastic_strain.iter().try_for_each(|e| f64s(out, &[*e])),
        }
    }
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
