//! A closed triangle mesh read from an STL file (ASCII or binary, [`super::stl`]): a rigid
//! body of any shape in 3D.
//!
//! The signed distance of a point is the distance to the nearest triangle, found through a
//! bounding-volume tree, with the sign of the angle-weighted pseudonormal of the feature
//! (face, edge or vertex) the closest point lies on (Bærentzen & Aanæs 2005, IEEE TVCG
//! 11(3)): exact for a closed, consistently oriented mesh, which [`TriangleMesh::read`] checks
//! (every edge shared by two faces of opposite senses), its shells apart. A mesh wound inwards (negative volume)
//! is turned outwards.

use std::collections::HashMap;
use std::path::Path;

type V3 = [f64; 3];

fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn add(a: V3, b: V3) -> V3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
fn mul(a: V3, s: f64) -> V3 {
    [a[0] * s, a[1] * s, a[2] * s]
}
fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn cross(a: V3, b: V3) -> V3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
fn unit(a: V3) -> V3 {
    let l = dot(a, a).sqrt();
    if l > 0.0 {
        mul(a, 1.0 / l)
    } else {
        a
    }
}

/// Where on a triangle its closest point to a query lies.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Feature {
    Face,
    /// The edge between the triangle's corners k and (k + 1) % 3.
    Edge(usize),
    /// Corner k.
    Vertex(usize),
}

/// A node of the bounding-volume tree: its box and either two children or a run of faces.
#[derive(Clone, Debug, PartialEq)]
struct Node {
    lo: V3,
    hi: V3,
    /// Children (inner node) or `usize::MAX`.
    children: [usize; 2],
    /// The node's faces: `order[first..first + count]` (a leaf).
    first: usize,
    count: usize,
}

/// A closed, outward-wound triangle mesh (m), ready for distance queries.
#[derive(Clone, Debug, PartialEq)]
pub struct TriangleMesh {
    vertices: Vec<V3>,
    faces: Vec<[usize; 3]>,
    /// Unit outward normal of each face.
    normals: Vec<V3>,
    /// Each face's area (m²).
    areas: Vec<f64>,
    /// Pseudonormal of each edge (sum of its two faces' normals), by (low, high) vertex.
    edges: HashMap<(usize, usize), V3>,
    /// Angle-weighted pseudonormal of each vertex.
    corners: Vec<V3>,
    /// Faces in tree order.
    order: Vec<usize>,
    tree: Vec<Node>,
}

/// Faces per leaf of the tree.
const LEAF: usize = 4;

impl TriangleMesh {
    /// Reads and checks the STL file at `path` ([`super::stl`]): an error says what is wrong
    /// with it. The surface must be closed (every edge met once each way) and its shells
    /// (the connected pieces) must neither cross nor hold one another.
    pub fn read(path: &Path) -> Result<Self, String> {
        let (vertices, faces) = super::stl::read(path)?;
        let shown = path.display();
        // A triangle with two equal corners has no edges of its own.
        let faces: Vec<[usize; 3]> = faces
            .into_iter()
            .filter(|f| f[0] != f[1] && f[1] != f[2] && f[2] != f[0])
            .collect();
        closed(&vertices, &faces).map_err(|e| {
            format!(
                "{shown} is not a closed surface ({e}): a body needs a watertight mesh, every edge \
                 shared by two triangles of opposite senses"
            )
        })?;
        let mesh = Self::new(vertices, faces)?;
        mesh.shells_apart().map_err(|e| format!("{shown}: {e}"))?;
        Ok(mesh)
    }

    /// The mesh of these vertices (m) and faces (corner indices); it must be closed.
    pub fn new(vertices: Vec<V3>, mut faces: Vec<[usize; 3]>) -> Result<Self, String> {
        if vertices.iter().flatten().any(|c| !c.is_finite()) {
            return Err("a vertex has a coordinate that is not a finite number".into());
        }
        let volume: f64 = faces
            .iter()
            .map(|f| dot(vertices[f[0]], cross(vertices[f[1]], vertices[f[2]])) / 6.0)
            .sum();
        if volume.abs() <= 0.0 {
            return Err("the mesh encloses no volume".into());
        }
        if volume < 0.0 {
            for f in &mut faces {
                f.swap(1, 2);
            }
        }
        let mut normals = Vec::with_capacity(faces.len());
        let mut areas = Vec::with_capacity(faces.len());
        let mut edges: HashMap<(usize, usize), V3> = HashMap::new();
        let mut corners = vec![[0.0; 3]; vertices.len()];
        for f in &faces {
            let [a, b, c] = f.map(|i| vertices[i]);
            let n = cross(sub(b, a), sub(c, a));
            let area = 0.5 * dot(n, n).sqrt();
            let n = unit(n);
            normals.push(n);
            areas.push(area);
            for k in 0..3 {
                let (i, j) = (f[k], f[(k + 1) % 3]);
                let e = edges.entry((i.min(j), i.max(j))).or_insert([0.0; 3]);
                *e = add(*e, n);
                // The angle at corner k weighs the face's normal there.
                let (p, q, r) = (vertices[f[k]], vertices[f[(k + 1) % 3]], vertices[f[(k + 2) % 3]]);
                let (u, w) = (unit(sub(q, p)), unit(sub(r, p)));
                let angle = dot(u, w).clamp(-1.0, 1.0).acos();
                corners[f[k]] = add(corners[f[k]], mul(n, angle));
            }
        }
        let mut mesh = TriangleMesh {
            vertices,
            faces,
            normals,
            areas,
            edges,
            corners,
            order: Vec::new(),
            tree: Vec::new(),
        };
        // A face of no area (a needle filling a crack) closes the surface but has no
        // point of its own: the tree and the samples leave it out.
        mesh.order = (0..mesh.faces.len()).filter(|&f| mesh.areas[f] > 0.0).collect();
        let n = mesh.order.len();
        if n == 0 {
            return Err("every triangle has zero area".into());
        }
        mesh.build(0, n);
        Ok(mesh)
    }

    fn face_box(&self, f: usize) -> (V3, V3) {
        let [a, b, c] = self.faces[f].map(|i| self.vertices[i]);
        (
            std::array::from_fn(|k| a[k].min(b[k]).min(c[k])),
            std::array::from_fn(|k| a[k].max(b[k]).max(c[k])),
        )
    }

    /// Builds the node over `order[first..first + count]`, splitting at the median centre
    /// along the longest side; returns its index.
    fn build(&mut self, first: usize, count: usize) -> usize {
        let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        for &f in &self.order[first..first + count] {
            let (l, h) = self.face_box(f);
            for k in 0..3 {
                lo[k] = lo[k].min(l[k]);
                hi[k] = hi[k].max(h[k]);
            }
        }
        let index = self.tree.len();
        self.tree.push(Node {
            lo,
            hi,
            children: [usize::MAX; 2],
            first,
            count,
        });
        if count <= LEAF {
            return index;
        }
        let axis = (0..3).fold(0, |m, k| if hi[k] - lo[k] > hi[m] - lo[m] { k } else { m });
        let centre =
            |f: usize, mesh: &Self| -> f64 { mesh.faces[f].iter().map(|&i| mesh.vertices[i][axis]).sum() };
        let half = count / 2;
        let mut run = self.order[first..first + count].to_vec();
        run.select_nth_unstable_by(half, |&p, &q| centre(p, self).total_cmp(&centre(q, self)));
        self.order[first..first + count].copy_from_slice(&run);
        let left = self.build(first, half);
        let right = self.build(first + half, count - half);
        self.tree[index].children = [left, right];
        index
    }

    /// Feeds its vertices and triangles to `h` (the fingerprint a checkpoint keeps).
    pub fn fingerprint(&self, h: &mut crc32fast::Hasher) {
        for v in &self.vertices {
            v.iter().for_each(|c| h.update(&c.to_le_bytes()));
        }
        for f in &self.faces {
            f.iter().for_each(|&i| h.update(&(i as u64).to_le_bytes()));
        }
    }

    /// Axis-aligned bounds (m).
    pub fn bounds(&self) -> (V3, V3) {
        (self.tree[0].lo, self.tree[0].hi)
    }

    /// Signed distance φ (m, negative inside) from `x` to the surface and the unit outward
    /// normal there: from the closest point to `x` outside, from `x` to it inside, the
    /// feature's pseudonormal on the surface itself.
    pub fn distance(&self, x: V3) -> (f64, V3) {
        let (mut best, mut at) = (f64::INFINITY, (0, [0.0; 3], Feature::Face));
        let mut stack = vec![0usize];
        while let Some(k) = stack.pop() {
            let node = &self.tree[k];
            if box_distance2(node.lo, node.hi, x) >= best {
                continue;
            }
            if node.children[0] == usize::MAX {
                for &f in &self.order[node.first..node.first + node.count] {
                    let (c, feature) = self.closest(f, x);
                    let d = sub(x, c);
                    let d2 = dot(d, d);
                    if d2 < best {
                        best = d2;
                        at = (f, c, feature);
                    }
                }
                continue;
            }
            let [l, r] = node.children;
            let (dl, dr) = (
                box_distance2(self.tree[l].lo, self.tree[l].hi, x),
                box_distance2(self.tree[r].lo, self.tree[r].hi, x),
            );
            // The nearer child last, so that it is searched first.
            if dl < dr {
                stack.extend([r, l]);
            } else {
                stack.extend([l, r]);
            }
        }
        let (f, c, feature) = at;
        let pseudo = match feature {
            Feature::Face => self.normals[f],
            Feature::Edge(k) => {
                let (i, j) = (self.faces[f][k], self.faces[f][(k + 1) % 3]);
                self.edges[&(i.min(j), i.max(j))]
            }
            Feature::Vertex(k) => self.corners[self.faces[f][k]],
        };
        let d = sub(x, c);
        let length = best.sqrt();
        let inside = dot(d, pseudo) < 0.0;
        let normal = if length > 1e-12 {
            mul(d, if inside { -1.0 / length } else { 1.0 / length })
        } else {
            unit(pseudo)
        };
        (if inside { -length } else { length }, normal)
    }

    /// The closest point of face `f` to `x` and the feature it lies on (Ericson 2005,
    /// Real-Time Collision Detection, §5.1.5).
    fn closest(&self, f: usize, x: V3) -> (V3, Feature) {
        let [a, b, c] = self.faces[f].map(|i| self.vertices[i]);
        let (ab, ac, ap) = (sub(b, a), sub(c, a), sub(x, a));
        let (d1, d2) = (dot(ab, ap), dot(ac, ap));
        if d1 <= 0.0 && d2 <= 0.0 {
            return (a, Feature::Vertex(0));
        }
        let bp = sub(x, b);
        let (d3, d4) = (dot(ab, bp), dot(ac, bp));
        if d3 >= 0.0 && d4 <= d3 {
            return (b, Feature::Vertex(1));
        }
        let vc = d1 * d4 - d3 * d2;
        if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
            return (add(a, mul(ab, d1 / (d1 - d3))), Feature::Edge(0));
        }
        let cp = sub(x, c);
        let (d5, d6) = (dot(ab, cp), dot(ac, cp));
        if d6 >= 0.0 && d5 <= d6 {
            return (c, Feature::Vertex(2));
        }
        let vb = d5 * d2 - d1 * d6;
        if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
            return (add(a, mul(ac, d2 / (d2 - d6))), Feature::Edge(2));
        }
        let va = d3 * d6 - d5 * d4;
        if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
            let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
            return (add(b, mul(sub(c, b), w)), Feature::Edge(1));
        }
        let denom = 1.0 / (va + vb + vc);
        let (v, w) = (vb * denom, vc * denom);
        (add(a, add(mul(ab, v), mul(ac, w))), Feature::Face)
    }

    /// Surface points about `spacing` (m) apart, each with the outward normal and the area
    /// (m²) it stands for, those whose places may lie in `reach`.
    ///
    /// Each face is cut into k² equal triangles (k the larger of √(2 area) and half the
    /// longest side, over `spacing`, rounded up: a right triangle of legs L in pieces of legs
    /// `spacing`), and the pieces are pooled by the cube of side `spacing` their centre lies
    /// in and by their normal (within 45° of the pool's mean, so that the faces on either
    /// side of an edge stay apart): one sample a pool, at the point of the surface nearest
    /// the pool's area-weighted centre, with its area-weighted mean normal and its area. A
    /// sample so stands for about spacing² of surface however finely the file facets it, as
    /// the samples of a `Sphere` or a `Box` do; a sample on every small face made a fine
    /// mesh's constraints many times as dense and stiffer (docs/verification.md).
    ///
    /// Only the pieces whose centres may lie in `reach` are visited: a face's pieces are
    /// those of the parallelogram a + i u + j v, and the reach's corners, projected on the
    /// face's plane, bound the (i, j) it can hold.
    pub fn samples(&self, spacing: f64, reach: &super::reach::Reach) -> Vec<(V3, V3, f64)> {
        let mut pools = Pools::new(spacing);
        for (f, face) in self.faces.iter().enumerate() {
            if self.areas[f] <= 0.0 {
                continue;
            }
            let [a, b, c] = face.map(|i| self.vertices[i]);
            if apart(self.face_box(f), (reach.lo, reach.hi)) {
                continue;
            }
            let longest = [sub(b, a), sub(c, b), sub(a, c)]
                .iter()
                .map(|e| dot(*e, *e).sqrt())
                .fold(0.0, f64::max);
            let k = ((2.0 * self.areas[f]).sqrt().max(0.5 * longest) / spacing)
                .ceil()
                .max(1.0) as usize;
            let (u, v) = (mul(sub(b, a), 1.0 / k as f64), mul(sub(c, a), 1.0 / k as f64));
            let at = |i: f64, j: f64| add(a, add(mul(u, i), mul(v, j)));
            let piece = self.areas[f] / (k * k) as f64;
            let normal = self.normals[f];
            let (irange, jrange) = piece_range(a, u, v, k, reach);
            for i in irange {
                for j in jrange.start..jrange.end.min(k - i) {
                    let (fi, fj) = (i as f64, j as f64);
                    pools.add(at(fi + 1.0 / 3.0, fj + 1.0 / 3.0), normal, piece);
                    if i + j + 1 < k {
                        pools.add(at(fi + 2.0 / 3.0, fj + 2.0 / 3.0), normal, piece);
                    }
                }
            }
        }
        pools
            .into_samples()
            .map(|(centre, normal, area)| {
                let (phi, towards) = self.distance(centre);
                (sub(centre, mul(towards, phi)), normal, area)
            })
            .collect()
    }
}

/// Surface pieces pooled by the cube of side `spacing` (m) their centre lies in and by
/// normal: key order, then the order each pool began, so that the samples come in the same
/// order on every run.
struct Pools {
    spacing: f64,
    /// Per cube: each pool's Σ A x (m³), Σ A n (m²) and Σ A (m²).
    cubes: std::collections::BTreeMap<[i64; 3], Vec<(V3, V3, f64)>>,
}

/// The cosine of the largest angle (45°) between a piece's normal and its pool's mean.
const POOL_COS: f64 = std::f64::consts::FRAC_1_SQRT_2;

impl Pools {
    fn new(spacing: f64) -> Self {
        Pools {
            spacing,
            cubes: Default::default(),
        }
    }

    /// A piece of area `area` (m²) centred at `x` (m) with unit normal `n`.
    fn add(&mut self, x: V3, n: V3, area: f64) {
        let key = x.map(|c| (c / self.spacing).floor() as i64);
        let pools = self.cubes.entry(key).or_default();
        let near = |p: &&mut (V3, V3, f64)| dot(p.1, n) >= POOL_COS * dot(p.1, p.1).sqrt();
        match pools.iter_mut().find(near) {
            Some(p) => *p = (add(p.0, mul(x, area)), add(p.1, mul(n, area)), p.2 + area),
            None => pools.push((mul(x, area), mul(n, area), area)),
        }
    }

    /// Each pool's area-weighted centre (m), its mean unit normal and its area (m²).
    fn into_samples(self) -> impl Iterator<Item = (V3, V3, f64)> {
        self.cubes
            .into_values()
            .flatten()
            .map(|(moment, normal, area)| (mul(moment, 1.0 / area), unit(normal), area))
    }
}

/// The rows i and columns j of a face's pieces (a + i u + j v, k a side) whose centres may
/// lie in `reach`: the parallelogram coordinates of the reach's corners projected on the
/// face's plane bound them (the map to (i, j) is affine, so the box's part in the plane maps
/// inside its corners' hull); all of them when the reach is unbounded.
fn piece_range(
    a: V3,
    u: V3,
    v: V3,
    k: usize,
    reach: &super::reach::Reach,
) -> (std::ops::Range<usize>, std::ops::Range<usize>) {
    let all = (0..k, 0..k);
    if (0..3).any(|d| !reach.lo[d].is_finite() || !reach.hi[d].is_finite()) {
        return all;
    }
    // (i, j) of x: solve [u·u u·v; u·v v·v] (i, j) = (u·(x − a), v·(x − a)).
    let (uu, uv, vv) = (dot(u, u), dot(u, v), dot(v, v));
    let det = uu * vv - uv * uv;
    if det.is_nan() || det <= 0.0 {
        return all;
    }
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for corner in 0..8 {
        let x: V3 = std::array::from_fn(|d| {
            if (corner >> d) & 1 == 1 {
                reach.hi[d]
            } else {
                reach.lo[d]
            }
        });
        let (pu, pv) = (dot(u, sub(x, a)), dot(v, sub(x, a)));
        let ij = [(vv * pu - uv * pv) / det, (uu * pv - uv * pu) / det];
        for m in 0..2 {
            lo[m] = lo[m].min(ij[m]);
            hi[m] = hi[m].max(ij[m]);
        }
    }
    let span = |m: usize| {
        let first = (lo[m] - 1.0).floor().max(0.0).min(k as f64) as usize;
        let last = (hi[m] + 1.0).ceil().max(0.0).min(k as f64) as usize;
        first..last.max(first)
    };
    (span(0), span(1))
}

/// Checks that every directed edge of `faces` is met once and its reverse once: a closed,
/// consistently wound surface.
fn closed(vertices: &[V3], faces: &[[usize; 3]]) -> Result<(), String> {
    let mut count: HashMap<(usize, usize), u32> = HashMap::new();
    for f in faces {
        for k in 0..3 {
            *count.entry((f[k], f[(k + 1) % 3])).or_insert(0) += 1;
        }
    }
    for (&(i, j), &c) in &count {
        let back = count.get(&(j, i)).copied().unwrap_or(0);
        if c != 1 || back != 1 {
            return Err(format!(
                "the edge from {:?} to {:?} is met {c} time(s) that way and {back} the other",
                vertices[i], vertices[j]
            ));
        }
    }
    Ok(())
}

impl TriangleMesh {
    /// The shells: sets of faces joined by shared corners, each a closed surface of its own.
    fn shells(&self) -> Vec<Vec<usize>> {
        let mut parent: Vec<usize> = (0..self.vertices.len()).collect();
        fn root(parent: &mut [usize], mut i: usize) -> usize {
            while parent[i] != i {
                parent[i] = parent[parent[i]];
                i = parent[i];
            }
            i
        }
        for f in &self.faces {
            for k in 1..3 {
                let (a, b) = (root(&mut parent, f[0]), root(&mut parent, f[k]));
                parent[a.max(b)] = a.min(b);
            }
        }
        let mut by_root: std::collections::BTreeMap<usize, Vec<usize>> = Default::default();
        for (i, f) in self.faces.iter().enumerate() {
            by_root.entry(root(&mut parent, f[0])).or_default().push(i);
        }
        by_root.into_values().collect()
    }

    /// Refuses shells that cross or hold one another: the distance to the whole mesh is the
    /// nearest shell's, so inside two overlapping shells it is too shallow, and points placed
    /// in their common part stay inside the body.
    fn shells_apart(&self) -> Result<(), String> {
        let shells = self.shells();
        if shells.len() < 2 {
            return Ok(());
        }
        let meshes: Vec<TriangleMesh> = shells
            .iter()
            .map(|s| {
                let faces = s.iter().map(|&f| self.faces[f]).collect();
                TriangleMesh::new(self.vertices.clone(), faces)
            })
            .collect::<Result<_, _>>()?;
        let (lo, hi) = self.bounds();
        let tol = 1e-9 * dot(sub(hi, lo), sub(hi, lo)).sqrt();
        for (a, ma) in meshes.iter().enumerate() {
            for (b, mb) in meshes.iter().enumerate().filter(|&(b, _)| b != a) {
                if apart(ma.bounds(), mb.bounds()) {
                    continue;
                }
                // Corners and face centres: shells that share a plane (two boxes side by
                // side, overlapping) have no corner inside the other, but a face centre.
                let corners = ma.faces.iter().flatten().map(|&i| ma.vertices[i]);
                let centres = ma.faces.iter().map(|f| {
                    mul(
                        add(add(ma.vertices[f[0]], ma.vertices[f[1]]), ma.vertices[f[2]]),
                        1.0 / 3.0,
                    )
                });
                // Or an edge of one through a face of the other (two boxes crossed like a
                // plus sign hold no corner or face centre of each other).
                let mut edges = ma
                    .faces
                    .iter()
                    .flat_map(|f| (0..3).map(move |k| (f[k], f[(k + 1) % 3])));
                let met = corners
                    .chain(centres)
                    .find(|&v| mb.distance(v).0 < -tol)
                    .or_else(|| {
                        edges
                            .find(|&(i, j)| mb.segment_crosses(ma.vertices[i], ma.vertices[j], tol))
                            .map(|(i, _)| ma.vertices[i])
                    });
                if let Some(at) = met {
                    return Err(format!(
                        "its closed shells {a} and {b} (of {}) cross or one holds the other (near \
                         {at:?}): give the body one closed surface, their union, or each shell as a \
                         part of its own",
                        shells.len()
                    ));
                }
            }
        }
        Ok(())
    }

    /// True when the segment `p`–`q` passes through a face's inside (by more than `tol` from
    /// its ends and the face's edges, Möller & Trumbore 1997).
    fn segment_crosses(&self, p: V3, q: V3, tol: f64) -> bool {
        let d = sub(q, p);
        let span: (V3, V3) = (
            std::array::from_fn(|k| p[k].min(q[k]) - tol),
            std::array::from_fn(|k| p[k].max(q[k]) + tol),
        );
        // The tolerance as a share of the segment's length.
        let margin = tol / dot(d, d).sqrt().max(f64::MIN_POSITIVE);
        let mut stack = vec![0usize];
        while let Some(k) = stack.pop() {
            let node = &self.tree[k];
            if apart((node.lo, node.hi), span) {
                continue;
            }
            if node.children[0] != usize::MAX {
                stack.extend(node.children);
                continue;
            }
            for &f in &self.order[node.first..node.first + node.count] {
                let [a, b, c] = self.faces[f].map(|i| self.vertices[i]);
                let (e1, e2) = (sub(b, a), sub(c, a));
                let h = cross(d, e2);
                let det = dot(e1, h);
                if det.abs() <= f64::MIN_POSITIVE {
                    continue; // along the face's plane: touching, not crossing
                }
                let s = sub(p, a);
                let u = dot(s, h) / det;
                let qv = cross(s, e1);
                let v = dot(d, qv) / det;
                let t = dot(e2, qv) / det;
                let edge = tol / (dot(e1, e1).sqrt().max(dot(e2, e2).sqrt()));
                if u > edge && v > edge && u + v < 1.0 - edge && t > margin && t < 1.0 - margin {
                    return true;
                }
            }
        }
        false
    }
}

/// True when the boxes `a` and `b` (lower and upper corners) have no point in common.
fn apart(a: (V3, V3), b: (V3, V3)) -> bool {
    (0..3).any(|k| a.1[k] < b.0[k] || b.1[k] < a.0[k])
}

/// Squared distance from `x` to the box `lo..hi` (0 inside).
fn box_distance2(lo: V3, hi: V3, x: V3) -> f64 {
    (0..3)
        .map(|k| {
            let d = (lo[k] - x[k]).max(x[k] - hi[k]).max(0.0);
            d * d
        })
        .sum()
}

/// A UV sphere's triangles (centre and radius in m), wound outwards: `rings` bands of
/// latitude, each cut into `around` pieces of longitude (2 · around · (rings − 1)
/// triangles): an STL file's content for a faceted ball, to set beside the `Sphere` shape.
pub fn sphere_triangles(centre: V3, radius: f64, around: usize, rings: usize) -> Vec<[V3; 3]> {
    use std::f64::consts::PI;
    let at = |i: usize, j: usize| -> V3 {
        let (t, f) = (
            PI * i as f64 / rings as f64,
            2.0 * PI * (j % around) as f64 / around as f64,
        );
        let n = [t.sin() * f.cos(), t.sin() * f.sin(), t.cos()];
        std::array::from_fn(|a| centre[a] + radius * n[a])
    };
    let mut out = Vec::with_capacity(2 * around * rings);
    for j in 0..around {
        out.push([at(0, 0), at(1, j), at(1, j + 1)]);
        for i in 1..rings - 1 {
            out.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
            out.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
        }
        out.push([at(rings - 1, j), at(rings, 0), at(rings - 1, j + 1)]);
    }
    out
}

/// The twelve triangles of the box `lo`..`hi` (m), two a face, wound outwards: an STL
/// file's content for a box, to set beside the `Box` shape.
pub fn box_triangles(lo: V3, hi: V3) -> Vec<[V3; 3]> {
    let corner = |i: usize| -> V3 { std::array::from_fn(|a| if (i >> a) & 1 == 1 { hi[a] } else { lo[a] }) };
    // Each face's corners in order, seen from outside.
    let quads = [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ];
    quads
        .iter()
        .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
        .map(|t| t.map(corner))
        .collect()
}

/// The mesh of a cube of side `side` at the origin, its corners shared (a test shape).
#[cfg(test)]
fn cube(side: f64) -> (Vec<V3>, Vec<[usize; 3]>) {
    let mut vertices: Vec<V3> = Vec::new();
    let faces = box_triangles([0.0; 3], [side; 3])
        .into_iter()
        .map(|t| {
            t.map(|v| match vertices.iter().position(|w| *w == v) {
                Some(i) => i,
                None => {
                    vertices.push(v);
                    vertices.len() - 1
                }
            })
        })
        .collect();
    (vertices, faces)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_cube_mesh_measures_to_its_faces_edges_and_corners_with_the_sign_of_inside() {
        let (v, f) = cube(2.0);
        let m = TriangleMesh::new(v, f).unwrap();
        let (phi, n) = m.distance([1.0, 1.0, 2.5]);
        assert!(
            (phi - 0.5).abs() < 1e-12 && (n[2] - 1.0).abs() < 1e-12,
            "{phi} {n:?}"
        );
        let (phi, n) = m.distance([1.0, 0.5, 1.0]);
        assert!(
            (phi + 0.5).abs() < 1e-12 && (n[1] + 1.0).abs() < 1e-12,
            "{phi} {n:?}"
        );
        // Beyond an edge and beyond a corner.
        let (phi, _) = m.distance([3.0, 1.0, 3.0]);
        assert!((phi - 2f64.sqrt()).abs() < 1e-12, "{phi}");
        let (phi, n) = m.distance([-1.0, -1.0, -1.0]);
        assert!((phi - 3f64.sqrt()).abs() < 1e-12 && n[0] < 0.0, "{phi} {n:?}");
        // The centre is a side's half deep.
        assert!((m.distance([1.0, 1.0, 1.0]).0 + 1.0).abs() < 1e-12);
    }

    #[test]
    fn a_mesh_wound_inwards_is_turned_outwards_and_an_open_one_has_no_volume_to_turn() {
        let (v, f) = cube(1.0);
        let inwards: Vec<[usize; 3]> = f.iter().map(|t| [t[0], t[2], t[1]]).collect();
        let m = TriangleMesh::new(v.clone(), inwards).unwrap();
        assert!(m.distance([0.5, 0.5, 0.5]).0 < 0.0);
        assert!(m.distance([0.5, 0.5, 1.5]).0 > 0.0);
        assert!(TriangleMesh::new(v, vec![[0, 1, 2], [1, 2, 3]]).is_err());
    }

    #[test]
    fn a_cube_mesh_samples_its_whole_surface() {
        let (v, f) = cube(1.0);
        let m = TriangleMesh::new(v, f).unwrap();
        let s = m.samples(0.1, &crate::rigid::Reach::ALL);
        let area: f64 = s.iter().map(|p| p.2).sum();
        assert!((area - 6.0).abs() < 1e-9, "{area}");
        // Every sample on the surface, its normal the face's.
        for (x, n, _) in &s {
            let (phi, normal) = m.distance(*x);
            assert!(phi.abs() < 1e-12, "{x:?} {phi}");
            assert!(dot(*n, normal) > 0.999, "{x:?} {n:?} {normal:?}");
        }
    }
    /// A ball faceted coarsely or finely samples as densely as the smooth `Sphere`: each
    /// sample on the faceted surface with a normal near the radial one, the whole area
    /// counted once. (A sample on every small face once made 40 000 triangles' samples
    /// 30 times as dense.)
    #[test]
    fn a_faceted_ball_samples_as_densely_as_the_smooth_one_whatever_its_facets() {
        use crate::rigid::{Geometry, Reach};
        let spacing = 0.125;
        let smooth = Geometry::Sphere {
            centre: vec![0.0; 3],
            radius: 0.5,
        }
        .samples(spacing, &Reach::ALL)
        .len() as f64;
        for (around, rings) in [(24, 12), (60, 30), (200, 101)] {
            let t = sphere_triangles([0.0; 3], 0.5, around, rings);
            let (v, f) = super::super::stl::weld(&t);
            let m = TriangleMesh::new(v, f).unwrap();
            let s = m.samples(spacing, &Reach::ALL);
            let area: f64 = s.iter().map(|p| p.2).sum();
            let faces: f64 = m.areas.iter().sum();
            assert!((area / faces - 1.0).abs() < 1e-12, "{area} {faces}");
            let ratio = s.len() as f64 / smooth;
            assert!(
                (0.7..1.6).contains(&ratio),
                "{} triangles: {} samples against {smooth}",
                t.len(),
                s.len()
            );
            for (x, n, _) in &s {
                assert!(m.distance(*x).0.abs() < 1e-12, "{x:?}");
                let radial = unit(*x);
                assert!(dot(*n, radial) > 0.97, "{x:?} {n:?}");
            }
        }
    }
}
