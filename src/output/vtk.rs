//! Material points as a VTK XML unstructured grid (`.vtu`) with raw binary arrays, readable
//! by ParaView, VisIt, meshio and pyvista.

use crate::components::*;
use crate::dim::Dim;
use crate::infra::columns::{col, points_with};
use crate::materials::{extend_plastic_strain, extend_state_fields, state_field_names};
use crate::simulation::Simulation;
use crate::tensor::StoredSym;
use crate::water::Water;
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
    /// u = γ_w · depth below the point's piezometric surface (Pa, compression positive).
    PorePressure,
    /// σ = σ′ − u I (Pa, tension positive: xx yy zz xy yz zx).
    TotalStress,
    /// The material state's field of this index in [`Source::state_fields`] (0 for points
    /// whose state has no such field).
    State(usize),
}

/// The state field names of the points of `archs`, each once, in the order first met.
fn state_names(archs: &[&Archetype]) -> Vec<&'static str> {
    let mut names = Vec::new();
    for a in archs {
        for n in state_field_names(a) {
            if !names.contains(&n) {
                names.push(n);
            }
        }
    }
    names
}

/// The total stress of the effective stress `s` at `x` in `material`.
fn total(water: &Water, material: u16, x: [f64; 3], s: &[f64; 6]) -> [f64; 6] {
    let u = water.pore_pressure(material, x);
    [s[0] - u, s[1] - u, s[2] - u, s[3], s[4], s[5]]
}

/// Where a file's values come from: the live columns ([`write_points`]) or a copy taken
/// for the writer thread ([`Frame`]). One list of arrays ([`arrays`]) serves both.
trait Source {
    /// Number of points.
    fn len(&self) -> usize;
    /// True when displacements are kept (`output.displacements`).
    fn has_displacement(&self) -> bool;
    /// The water table, when the scene has one (the stress is then effective).
    fn water(&self) -> Option<&Water>;
    /// The names of the material states' fields the points carry (none for most models).
    fn state_fields(&self) -> &[&'static str];
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
    // Bodies without plastic state (elastic) write a plastic strain of zero. With water the
    // points' stress is effective: the pore pressure and the total stress follow it.
    let water: &[(&str, usize, Field)] = match src.water() {
        Some(_) => &[
            ("pore_pressure", 1, Field::PorePressure),
            ("total_stress", 6, Field::TotalStress),
        ],
        None => &[],
    };
    let fields = [
        ("velocity", 3, Field::Velocity),
        ("stress", 6, Field::Stress),
        ("mean_stress", 1, Field::MeanStress),
        ("deviatoric_stress", 1, Field::DeviatoricStress),
        ("volume", 1, Field::Volume),
        ("plastic_strain", 1, Field::PlasticStrain),
    ];
    for &(name, components, f) in fields.iter().chain(water) {
        arrays.push(Array::new(
            Part::PointData,
            name,
            Kind::Float64,
            components,
            n,
            field(f),
        ));
    }
    for (k, &name) in src.state_fields().iter().enumerate() {
        arrays.push(Array::new(
            Part::PointData,
            name,
            Kind::Float64,
            1,
            n,
            field(Field::State(k)),
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
/// strain (0 for bodies without plastic state). With water the stress is effective, and the
/// pore pressure (Pa, compression positive) and the total stress σ′ − u I follow. A
/// material state's fields follow last (`ModifiedCamClay`: `preconsolidation`,
/// `specific_volume`, `excess_pore_pressure`; 0 on the points of other materials); an
/// undrained clay's stress is σ′ − u I with its own excess pore pressure u.
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
    let columns = Columns::<D>::of(&sim.ctx.world, sim.ctx.model.water.clone());
    let arrays = arrays(&columns);
    crate::output::dir::write_atomic(path, |out| write_arrays(out, columns.len(), &arrays))
}

/// Writes `points.pvtu`, the file that ties together the pieces `parts` (file names next to
/// it) that the ranks of a run over MPI each wrote with [`write_points`], with the arrays
/// those pieces hold. Cells are not listed: a reader takes them from each piece.
pub fn write_parallel_points<D: Dim>(
    sim: &Simulation<D>,
    path: &Path,
    parts: &[String],
) -> std::io::Result<()> {
    let columns = Columns::<D>::of(&sim.ctx.world, sim.ctx.model.water.clone());
    let arrays = arrays(&columns);
    write_parallel(&arrays, path, parts)
}

/// The `.pvtu` of a snapshot taken over MPI ranks: `frame` (this rank's part) names the
/// arrays, `parts` the ranks' files.
pub fn write_parallel_frame(frame: &Frame, path: &Path, parts: &[String]) -> std::io::Result<()> {
    let arrays = arrays(frame);
    write_parallel(&arrays, path, parts)
}

/// A `.pvtu` of `arrays` over the pieces `parts` (file names relative to it).
fn write_parallel(arrays: &[Array<'_>], path: &Path, parts: &[String]) -> std::io::Result<()> {
    crate::output::dir::write_atomic(path, |out| {
        out.write_all(b"<?xml version=\"1.0\"?>\n<VTKFile type=\"PUnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n<PUnstructuredGrid GhostLevel=\"0\">\n")?;
        for (section, part) in [("PPoints", Part::Points), ("PPointData", Part::PointData)] {
            writeln!(out, "<{section}>")?;
            for a in arrays.iter().filter(|a| a.part == part) {
                writeln!(
                    out,
                    "<PDataArray type=\"{}\" Name=\"{}\" NumberOfComponents=\"{}\"/>",
                    a.kind.name(),
                    a.name,
                    a.components
                )?;
            }
            writeln!(out, "</{section}>")?;
        }
        for p in parts {
            writeln!(out, "<Piece Source=\"{p}\"/>")?;
        }
        out.write_all(b"</PUnstructuredGrid>\n</VTKFile>\n")?;
        out.flush()
    })
}

/// Writes a [`Frame`] as [`write_points`] writes the live points.
pub fn write_frame(frame: &Frame, path: &Path) -> std::io::Result<()> {
    let arrays = arrays(frame);
    crate::output::dir::write_atomic(path, |out| write_arrays(out, frame.len(), &arrays))
}

/// The live point columns, in id order.
struct Columns<'a, D: Dim> {
    archs: Vec<&'a Archetype>,
    /// Built by the first field written: a `.pvtu`, which only names the arrays, needs none.
    order: std::cell::OnceCell<Order>,
    n: usize,
    displacements: bool,
    water: Option<Water>,
    states: Vec<&'static str>,
    _marker: std::marker::PhantomData<fn() -> D>,
}

impl<'a, D: Dim> Columns<'a, D> {
    fn of(world: &'a World, water: Option<Water>) -> Self {
        let archs: Vec<&Archetype> = points_with::<Stress<D::Stress>>(world).collect();
        let n = archs.iter().map(|a| a.len() as usize).sum::<usize>();
        // Displacements only when the scene keeps them (`output.displacements`).
        let displacements = n > 0 && archs.iter().all(|a| a.has::<Displacement<D::Vec>>());
        Columns {
            states: state_names(&archs),
            archs,
            order: std::cell::OnceCell::new(),
            n,
            displacements,
            water,
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
    fn water(&self) -> Option<&Water> {
        self.water.as_ref()
    }
    fn state_fields(&self) -> &[&'static str] {
        &self.states
    }
    fn write(&self, field: Field, out: &mut BufWriter<File>) -> std::io::Result<()> {
        let archs = &self.archs[..];
        let order = self.order.get_or_init(|| Order::of(archs));
        match field {
            Field::Position => {
                each::<Position<D::Vec>>(archs, order, out, |out, x| f64s(out, &D::vec_to3(x.0)))
            }
            Field::Id => each::<PointId>(archs, order, out, |out, id| out.write_all(&id.0.to_le_bytes())),
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
            Field::PorePressure | Field::TotalStress => {
                let w = self.water.as_ref().expect("written only with water");
                // Read straight from the columns, in id order: no copy of the points.
                let xs: Vec<_> = archs.iter().map(|a| col::<Position<D::Vec>>(a)).collect();
                let ms: Vec<_> = archs.iter().map(|a| col::<MaterialId>(a)).collect();
                let ss: Vec<_> = archs.iter().map(|a| col::<Stress<D::Stress>>(a)).collect();
                order.points().try_for_each(|(a, r)| {
                    let (x, m) = (D::vec_to3(xs[a][r].0), ms[a][r].0);
                    match field {
                        Field::PorePressure => f64s(out, &[w.pore_pressure(m, x)]),
                        _ => f64s(out, &total(w, m, x, &voigt::<D>(&ss[a][r]))),
                    }
                })
            }
            Field::PlasticStrain => {
                let plastic: Vec<Vec<f64>> = archs
                    .iter()
                    .map(|a| {
                        let mut e = Vec::new();
                        extend_plastic_strain(a, &mut e);
                        e
                    })
                    .collect();
                order.points().try_for_each(|(a, r)| f64s(out, &[plastic[a][r]]))
            }
            Field::State(k) => {
                let name = [self.states[k]];
                let values: Vec<Vec<f64>> = archs
                    .iter()
                    .map(|a| {
                        let mut v = [Vec::new()];
                        extend_state_fields(a, &name, &mut v);
                        let [v] = v;
                        v
                    })
                    .collect();
                order.points().try_for_each(|(a, r)| f64s(out, &[values[a][r]]))
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
    /// The names of the material states' fields the points carry.
    pub state_names: Vec<&'static str>,
    /// Each of those fields, a value a point (0 where a point's state has no such field).
    pub state: Vec<Vec<f64>>,
    /// The water table, when the scene has one (the stress is then effective).
    pub water: Option<Water>,
    /// The rigid bodies where they are (none without).
    pub bodies: Vec<crate::rigid::Outline>,
}

impl Frame {
    /// Copies the points of `world` at `step` and `time` (about 140 bytes a point) in
    /// storage order: column by column, so the stepping thread only streams memory.
    /// [`Frame::in_id_order`] puts them in id order on the thread that writes them.
    pub fn capture<D: Dim>(world: &World, step: u64, time: f64, water: Option<Water>) -> Frame {
        let mut f = Frame::default();
        f.refill::<D>(world, step, time, water);
        f
    }

    /// [`Frame::capture`] into this frame's buffers, which keep their capacity: a frame
    /// handed back by the writer is filled again without touching fresh memory.
    pub fn refill<D: Dim>(&mut self, world: &World, step: u64, time: f64, water: Option<Water>) {
        self.water = water;
        let archs: Vec<&Archetype> = points_with::<Stress<D::Stress>>(world).collect();
        let n = archs.iter().map(|a| a.len() as usize).sum::<usize>();
        let displacements = n > 0 && archs.iter().all(|a| a.has::<Displacement<D::Vec>>());
        let mut u = self.displacement.take().unwrap_or_default();
        u.clear();
        (self.step, self.time) = (step, time);
        self.id.clear();
        self.material.clear();
        self.position.clear();
        self.velocity.clear();
        self.stress.clear();
        self.volume.clear();
        self.plastic_strain.clear();
        self.state_names = state_names(&archs);
        self.state.resize_with(self.state_names.len(), Vec::new);
        self.state.iter_mut().for_each(Vec::clear);
        for arch in archs {
            copy::<PointId, _>(arch, &mut self.id, |i| i.0);
            copy::<MaterialId, _>(arch, &mut self.material, |m| m.0);
            copy::<Position<D::Vec>, _>(arch, &mut self.position, |x| D::vec_to3(x.0));
            if displacements {
                copy::<Displacement<D::Vec>, _>(arch, &mut u, |u| D::vec_to3(u.0));
            }
            copy::<Velocity<D::Vec>, _>(arch, &mut self.velocity, |v| D::vec_to3(v.0));
            copy::<Stress<D::Stress>, _>(arch, &mut self.stress, voigt::<D>);
            copy::<Volume, _>(arch, &mut self.volume, |v| v.0);
            extend_plastic_strain(arch, &mut self.plastic_strain);
            extend_state_fields(arch, &self.state_names, &mut self.state);
        }
        self.displacement = displacements.then_some(u);
    }

    /// The same points sorted by id, as the written files hold them.
    pub fn in_id_order(&self) -> Frame {
        let mut sorted = Frame::default();
        self.sort_into(&mut sorted);
        sorted
    }

    /// [`Frame::in_id_order`] into `sorted`'s buffers, which keep their capacity (fresh
    /// memory would cost a page fault every 4 KiB).
    pub fn sort_into(&self, sorted: &mut Frame) {
        let mut order = std::mem::take(&mut sorted.id);
        id_order(self.id.iter().copied(), &mut order);
        (sorted.step, sorted.time, sorted.water) = (self.step, self.time, self.water.clone());
        permute(&self.material, &order, &mut sorted.material);
        permute(&self.position, &order, &mut sorted.position);
        match &self.displacement {
            Some(u) => permute(u, &order, sorted.displacement.get_or_insert_with(Vec::new)),
            None => sorted.displacement = None,
        }
        permute(&self.velocity, &order, &mut sorted.velocity);
        permute(&self.stress, &order, &mut sorted.stress);
        permute(&self.volume, &order, &mut sorted.volume);
        permute(&self.plastic_strain, &order, &mut sorted.plastic_strain);
        sorted.state_names.clone_from(&self.state_names);
        sorted.state.resize_with(self.state.len(), Vec::new);
        for (from, to) in self.state.iter().zip(&mut sorted.state) {
            permute(from, &order, to);
        }
        for r in order.iter_mut() {
            *r = self.id[*r as usize];
        }
        sorted.id = order;
    }
}

/// `into` becomes `v[order[0]], v[order[1]], ...`
fn permute<T: Copy>(v: &[T], order: &[u32], into: &mut Vec<T>) {
    into.clear();
    into.extend(order.iter().map(|&i| v[i as usize]));
}

/// Appends `value(T)` of every row of `arch`, in storage order.
fn copy<T: Component, V>(arch: &Archetype, into: &mut Vec<V>, value: impl Fn(&T) -> V) {
    into.extend(col::<T>(arch).iter().map(value));
}

impl Source for Frame {
    fn len(&self) -> usize {
        self.id.len()
    }
    fn has_displacement(&self) -> bool {
        self.displacement.is_some()
    }
    fn water(&self) -> Option<&Water> {
        self.water.as_ref()
    }
    fn state_fields(&self) -> &[&'static str] {
        &self.state_names
    }
    fn write(&self, field: Field, out: &mut BufWriter<File>) -> std::io::Result<()> {
        // Whole columns at a time: a frame is written on the writer thread, which shares
        // the cores with stepping, so it costs what a copy costs.
        match field {
            Field::Position => f64_block(out, flat3(&self.position)),
            Field::Id => {
                let ids: Vec<u8> = self.id.iter().flat_map(|i| i.to_le_bytes()).collect();
                out.write_all(&ids)
            }
            Field::Material => {
                let m: Vec<u8> = self
                    .material
                    .iter()
                    .flat_map(|&m| u32::from(m).to_le_bytes())
                    .collect();
                out.write_all(&m)
            }
            Field::Displacement => f64_block(out, self.displacement.as_deref().map_or(&[], flat3)),
            Field::Velocity => f64_block(out, flat3(&self.velocity)),
            Field::Stress => f64_block(out, bytemuck::cast_slice(&self.stress)),
            Field::MeanStress => f64_block(
                out,
                &self.stress.iter().map(|s| invariants(s).0).collect::<Vec<_>>(),
            ),
            Field::DeviatoricStress => f64_block(
                out,
                &self.stress.iter().map(|s| invariants(s).1).collect::<Vec<_>>(),
            ),
            Field::Volume => f64_block(out, &self.volume),
            Field::PlasticStrain => f64_block(out, &self.plastic_strain),
            Field::State(k) => f64_block(out, &self.state[k]),
            Field::PorePressure => {
                let w = self.water.as_ref().expect("written only with water");
                f64_block(
                    out,
                    &self
                        .position
                        .iter()
                        .zip(&self.material)
                        .map(|(&x, &m)| w.pore_pressure(m, x))
                        .collect::<Vec<_>>(),
                )
            }
            Field::TotalStress => {
                let w = self.water.as_ref().expect("written only with water");
                let t: Vec<[f64; 6]> = self
                    .position
                    .iter()
                    .zip(&self.material)
                    .zip(&self.stress)
                    .map(|((&x, &m), s)| total(w, m, x, s))
                    .collect();
                f64_block(out, bytemuck::cast_slice(&t))
            }
        }
    }
}

/// The components of a list of vectors, one after the other.
fn flat3(v: &[[f64; 3]]) -> &[f64] {
    bytemuck::cast_slice(v)
}

/// Writes `values` as little-endian f64, in one piece where the machine is little-endian.
fn f64_block(out: &mut BufWriter<File>, values: &[f64]) -> std::io::Result<()> {
    if cfg!(target_endian = "little") {
        out.write_all(bytemuck::cast_slice(values))
    } else {
        f64s(out, values)
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

/// The points in id order, each counted over the archetypes in turn.
struct Order {
    /// The points' counts over the archetypes, in id order.
    rows: Vec<u32>,
    /// Where each archetype's points start in that count (and the total last).
    starts: Vec<usize>,
}

impl Order {
    /// The points of `archs`, counted over them in turn, in id order.
    fn of(archs: &[&Archetype]) -> Order {
        let mut starts = vec![0usize];
        for arch in archs {
            starts.push(starts.last().expect("starts at 0") + arch.len() as usize);
        }
        let mut rows = Vec::new();
        let ids: Vec<_> = archs.iter().map(|a| col::<PointId>(a)).collect();
        id_order(ids.iter().flat_map(|c| c.iter().map(|id| id.0)), &mut rows);
        Order { rows, starts }
    }

    /// (archetype, row) of every point, in id order.
    fn points(&self) -> impl Iterator<Item = (usize, usize)> + '_ {
        self.rows.iter().map(|&k| {
            let k = k as usize;
            let a = self.starts.partition_point(|&s| s <= k) - 1;
            (a, k - self.starts[a])
        })
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
    for (a, r) in order.points() {
        field(out, &columns[a][r])?;
    }
    Ok(())
}
