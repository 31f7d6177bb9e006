//! The shapes of rigid bodies: signed distance to the surface and the outward normal.
//!
//! Every shape answers one question, [`Geometry::distance`]: for a point x (m), the signed
//! distance φ to the body's surface (negative inside) and the unit outward normal of the
//! surface at the closest point. Contact reads the normal from the geometry, not from the
//! soil's mass gradient, so a flat face pushes straight and a circle pushes radially.

use super::mesh::TriangleMesh;
use crate::error::Refusal;
use serde::{Deserialize, Serialize};
use std::sync::Arc;

/// A body's shape at its starting position, in scene coordinates (m).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum Geometry {
    /// 2D: a disc (a T-bar or pipe section in plane strain).
    Circle {
        /// Centre (m, x y).
        centre: Vec<f64>,
        /// Radius (m).
        radius: f64,
    },
    /// 2D: a simple polygon, its vertices in order (either sense); no two edges cross.
    Polygon {
        /// Vertices (m, x y), at least three.
        vertices: Vec<Vec<f64>>,
    },
    /// 2D or 3D: an axis-aligned box.
    Box {
        /// Lower corner (m).
        min: Vec<f64>,
        /// Upper corner (m).
        max: Vec<f64>,
    },
    /// 3D: a ball.
    Sphere {
        /// Centre (m, x y z).
        centre: Vec<f64>,
        /// Radius (m).
        radius: f64,
    },
    /// 3D: a cylinder along a coordinate axis.
    Cylinder {
        /// Centre of its lower end (m, x y z).
        base: Vec<f64>,
        /// The axis it lies along (0 = x, 1 = y, 2 = z).
        axis: usize,
        /// Length along the axis (m).
        length: f64,
        /// Radius (m).
        radius: f64,
    },
    /// 3D: a closed triangle mesh read from an STL file (ASCII or binary, coordinates in
    /// m), its path relative to the scene file.
    Mesh {
        /// The STL file.
        file: String,
        /// The mesh as read when the scene was loaded.
        #[serde(skip)]
        mesh: Option<Arc<TriangleMesh>>,
    },
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn norm(a: [f64; 3]) -> f64 {
    (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
}

fn scale(a: [f64; 3], s: f64) -> [f64; 3] {
    [a[0] * s, a[1] * s, a[2] * s]
}

fn point(v: &[f64]) -> [f64; 3] {
    std::array::from_fn(|a| v.get(a).copied().unwrap_or(0.0))
}

/// Unit vector along `d`, or `fallback` when `d` is (numerically) zero.
fn unit_or(d: [f64; 3], fallback: [f64; 3]) -> [f64; 3] {
    let l = norm(d);
    if l > 1e-300 {
        scale(d, 1.0 / l)
    } else {
        fallback
    }
}

impl Geometry {
    /// Signed distance φ (m, negative inside) from `x` to the surface, and the unit outward
    /// normal there. `n` is the number of dimensions (unused coordinates are zero).
    pub fn distance(&self, x: [f64; 3], n: usize) -> (f64, [f64; 3]) {
        match self {
            Geometry::Circle { centre, radius } | Geometry::Sphere { centre, radius } => {
                let d = sub(x, point(centre));
                let up = if n == 2 { [0.0, 1.0, 0.0] } else { [0.0, 0.0, 1.0] };
                (norm(d) - radius, unit_or(d, up))
            }
            Geometry::Polygon { vertices } => polygon(vertices, x),
            Geometry::Box { min, max } => cuboid(point(min), point(max), x, n),
            Geometry::Cylinder {
                base,
                axis,
                length,
                radius,
            } => cylinder(point(base), *axis, *length, *radius, x),
            Geometry::Mesh { mesh, .. } => loaded(mesh).distance(x),
        }
    }

    /// The axis-aligned bounds (m) of the shape at its starting position.
    pub fn bounds(&self, n: usize) -> ([f64; 3], [f64; 3]) {
        match self {
            Geometry::Circle { centre, radius } | Geometry::Sphere { centre, radius } => {
                let c = point(centre);
                let r = |a: usize, s: f64| if a < n { c[a] + s * radius } else { 0.0 };
                (
                    std::array::from_fn(|a| r(a, -1.0)),
                    std::array::from_fn(|a| r(a, 1.0)),
                )
            }
            Geometry::Polygon { vertices } => crate::polygon::bounds(vertices),
            Geometry::Box { min, max } => (point(min), point(max)),
            Geometry::Cylinder {
                base,
                axis,
                length,
                radius,
            } => {
                let b = point(base);
                let lo = std::array::from_fn(|a| if a == *axis { b[a] } else { b[a] - radius });
                let hi = std::array::from_fn(|a| if a == *axis { b[a] + length } else { b[a] + radius });
                (lo, hi)
            }
            Geometry::Mesh { mesh, .. } => loaded(mesh).bounds(),
        }
    }

    /// Reads a mesh's STL file, `dir` the scene file's directory; other shapes have nothing
    /// to read. An error names the field and what is wrong with the file.
    pub fn read(&mut self, dir: &std::path::Path) -> Result<(), Refusal> {
        if let Geometry::Mesh { file, mesh } = self {
            let m = TriangleMesh::read(&dir.join(&*file)).map_err(|e| Refusal::new("geometry.file", e))?;
            *mesh = Some(Arc::new(m));
        }
        Ok(())
    }
}

/// The mesh a scene's loading read ([`Geometry::read`]); a scene checks that it did.
fn loaded(mesh: &Option<Arc<TriangleMesh>>) -> &TriangleMesh {
    mesh.as_deref().expect("meshes are read as the scene loads")
}

impl Geometry {
    /// A `Mesh`'s triangles, as read with the scene.
    pub fn mesh(&self) -> &TriangleMesh {
        match self {
            Geometry::Mesh { mesh, .. } => loaded(mesh),
            _ => unreachable!("only a Mesh has triangles"),
        }
    }
}

impl Geometry {
    /// The rules a shape holds in `n` dimensions (`axisymmetric`: in (r, z), where a
    /// polygon turns about the axis and a circle centred on it is a ball), or the
    /// [`Refusal`] of the field.
    pub fn check(&self, n: usize, axisymmetric: bool) -> Result<(), Refusal> {
        let bad = |f: &str, r: String| Err(Refusal::new(f.to_string(), r));
        let finite = |v: &[f64]| v.iter().all(|c| c.is_finite());
        let plane = matches!(self, Geometry::Circle { .. } | Geometry::Polygon { .. });
        if axisymmetric && !plane {
            return bad(
                "geometry",
                "an axisymmetric scene takes a Polygon or a Circle in (r, z), turned about the \
                 axis; a box, sphere, cylinder or mesh is a 3D shape"
                    .into(),
            );
        }
        match self {
            Geometry::Circle { centre, radius } | Geometry::Sphere { centre, radius } => {
                let (name, dims) = match self {
                    Geometry::Circle { .. } => ("a circle", 2),
                    _ => ("a sphere", 3),
                };
                if n != dims {
                    return bad(
                        "geometry",
                        format!("{name} is a {dims}D shape; the scene is {n}D"),
                    );
                }
                if centre.len() != n || !finite(centre) {
                    return bad(
                        "geometry.centre",
                        format!("needs {n} finite coordinates, found {centre:?}"),
                    );
                }
                if !(radius.is_finite() && *radius > 0.0) {
                    return bad("geometry.radius", format!("must be above 0 m, found {radius}"));
                }
            }
            Geometry::Polygon { vertices } => {
                if n != 2 {
                    return bad("geometry", format!("a polygon is a 2D shape; the scene is {n}D"));
                }
                if vertices.len() < 3 || !vertices.iter().all(|v| v.len() == 2 && finite(v)) {
                    return bad(
                        "geometry.vertices",
                        "needs at least three vertices, each two finite coordinates [x, y]".into(),
                    );
                }
                if let Some(rule) = crate::polygon::fault(vertices) {
                    return bad("geometry.vertices", rule);
                }
            }
            Geometry::Box { min, max } => {
                if min.len() != n || max.len() != n || !finite(min) || !finite(max) {
                    return bad(
                        "geometry.min",
                        format!("a box needs {n} finite coordinates a corner"),
                    );
                }
                if min.iter().zip(max).any(|(lo, hi)| lo >= hi) {
                    return bad("geometry.max", "every entry must be above min's".into());
                }
            }
            Geometry::Cylinder {
                base,
                axis,
                length,
                radius,
            } => {
                if n != 3 {
                    return bad("geometry", format!("a cylinder is a 3D shape; the scene is {n}D"));
                }
                if base.len() != 3 || !finite(base) {
                    return bad("geometry.base", "needs 3 finite coordinates".into());
                }
                if *axis > 2 {
                    return bad("geometry.axis", format!("is 0, 1 or 2, found {axis}"));
                }
                if !(length.is_finite() && *length > 0.0 && radius.is_finite() && *radius > 0.0) {
                    return bad("geometry.radius", "length and radius must be above 0 m".into());
                }
            }
            Geometry::Mesh { mesh, .. } => {
                if n != 3 {
                    return bad(
                        "geometry",
                        format!("an STL mesh is a 3D shape; the scene is {n}D"),
                    );
                }
                if mesh.is_none() {
                    return bad("geometry.file", "the mesh was not read with the scene".into());
                }
            }
        }
        if axisymmetric {
            let below = match self {
                Geometry::Circle { centre, .. } => centre[0] < 0.0,
                Geometry::Polygon { vertices } => vertices.iter().any(|v| v[0] < 0.0),
                _ => false,
            };
            if below {
                return bad(
                    "geometry",
                    "reaches r < 0: an axisymmetric body lies at r ≥ 0 (a circle's centre, every \
                     vertex of a polygon)"
                        .into(),
                );
            }
        }
        Ok(())
    }
}

/// A point of a body's surface where contact is held: its place and outward normal in the
/// body's starting frame, and the surface it stands for (m in 2D, m² in 3D).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    /// Place (m, x y z).
    pub x: [f64; 3],
    /// Unit outward normal.
    pub normal: [f64; 3],
    /// Surface it stands for (m per metre of thickness in 2D; m² in 3D).
    pub measure: f64,
}

/// Each edge of a polygon (vertices `v`, either way round) with a length: its ends, its
/// nearest point to `x` and its outward unit normal.
pub(crate) fn polygon_edges(
    v: &[Vec<f64>],
    x: [f64; 3],
) -> impl Iterator<Item = ([f64; 2], [f64; 2], [f64; 3], [f64; 3])> + '_ {
    let ccw = crate::polygon::signed_area(v) > 0.0;
    (0..v.len()).filter_map(move |i| {
        let (a, b) = (&v[i], &v[(i + 1) % v.len()]);
        let e = [b[0] - a[0], b[1] - a[1]];
        let len2 = e[0] * e[0] + e[1] * e[1];
        if len2 <= 0.0 {
            return None;
        }
        let t = (((x[0] - a[0]) * e[0] + (x[1] - a[1]) * e[1]) / len2).clamp(0.0, 1.0);
        // Outward: to the right of the edge when the vertices run counter-clockwise.
        let l = len2.sqrt();
        let out = [e[1] / l, -e[0] / l, 0.0];
        let normal = if ccw { out } else { scale(out, -1.0) };
        Some((
            [a[0], a[1]],
            [b[0], b[1]],
            [a[0] + t * e[0], a[1] + t * e[1], 0.0],
            normal,
        ))
    })
}

/// Signed distance to a simple polygon: the nearest edge's distance, negative inside
/// (crossing number); the normal points from the closest point to `x` outside, from `x` to
/// it inside, and is the edge's outward normal on the surface itself.
fn polygon(v: &[Vec<f64>], x: [f64; 3]) -> (f64, [f64; 3]) {
    let (mut best, mut closest, mut edge_normal) = (f64::INFINITY, [0.0; 3], [0.0; 3]);
    let mut inside = false;
    for (a, b, c, normal) in polygon_edges(v, x) {
        let d = norm(sub(x, c));
        if d < best {
            best = d;
            closest = c;
            edge_normal = normal;
        }
        if (a[1] > x[1]) != (b[1] > x[1]) && x[0] < a[0] + (x[1] - a[1]) / (b[1] - a[1]) * (b[0] - a[0]) {
            inside = !inside;
        }
    }
    let sign = if inside { -1.0 } else { 1.0 };
    let n = unit_or(scale(sub(x, closest), sign), edge_normal);
    (sign * best, n)
}

/// Signed distance to an axis-aligned box in `n` dimensions.
fn cuboid(lo: [f64; 3], hi: [f64; 3], x: [f64; 3], n: usize) -> (f64, [f64; 3]) {
    let mut outside = [0.0; 3];
    let (mut deepest, mut deepest_axis, mut deepest_sign) = (f64::NEG_INFINITY, 0, 1.0);
    for a in 0..n {
        let (below, above) = (lo[a] - x[a], x[a] - hi[a]);
        outside[a] = below.max(above).max(0.0) * if above > below { 1.0 } else { -1.0 };
        // Inside, the nearest face: the largest (least negative) of the two gaps.
        let (g, s) = if above > below {
            (above, 1.0)
        } else {
            (below, -1.0)
        };
        if g > deepest {
            (deepest, deepest_axis, deepest_sign) = (g, a, s);
        }
    }
    let out = norm(outside);
    if out > 0.0 {
        return (out, scale(outside, 1.0 / out));
    }
    let mut normal = [0.0; 3];
    normal[deepest_axis] = deepest_sign;
    (deepest, normal)
}

/// Signed distance to a capped cylinder along `axis`.
fn cylinder(base: [f64; 3], axis: usize, length: f64, radius: f64, x: [f64; 3]) -> (f64, [f64; 3]) {
    let d = sub(x, base);
    let mut radial = d;
    radial[axis] = 0.0;
    let r = norm(radial);
    let half = 0.5 * length;
    let along = d[axis] - half;
    let (dr, da) = (r - radius, along.abs() - half);
    let mut cap = [0.0; 3];
    cap[axis] = along.signum();
    let side = unit_or(radial, {
        let mut u = [0.0; 3];
        u[(axis + 1) % 3] = 1.0;
        u
    });
    if dr > 0.0 && da > 0.0 {
        let l = (dr * dr + da * da).sqrt();
        let n = [
            side[0] * dr / l + cap[0] * da / l,
            side[1] * dr / l + cap[1] * da / l,
            side[2] * dr / l + cap[2] * da / l,
        ];
        (l, n)
    } else if dr > da {
        (dr, side)
    } else {
        (da, cap)
    }
}

impl Geometry {
    /// The shape to draw (m, at its starting place): in 2D and axisymmetric scenes its
    /// outline, closed (a polygon's vertices, a circle in 72 pieces, `true`); in 3D the
    /// surface samples every `spacing` m within `reach` as a cloud of points (`false`).
    pub fn outline(&self, spacing: f64, reach: &super::reach::Reach) -> (Vec<[f64; 3]>, bool) {
        match self {
            Geometry::Polygon { vertices } => (vertices.iter().map(|v| [v[0], v[1], 0.0]).collect(), true),
            Geometry::Circle { centre, radius } => (
                (0..72)
                    .map(|k| {
                        let t = std::f64::consts::TAU * f64::from(k) / 72.0;
                        [centre[0] + radius * t.cos(), centre[1] + radius * t.sin(), 0.0]
                    })
                    .collect(),
                true,
            ),
            _ => (
                self.samples(spacing, reach).into_iter().map(|s| s.x).collect(),
                false,
            ),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_circle_is_negative_inside_and_pushes_radially() {
        let c = Geometry::Circle {
            centre: vec![1.0, 2.0],
            radius: 0.5,
        };
        let (phi, n) = c.distance([1.0, 1.0, 0.0], 2);
        assert!((phi - 0.5).abs() < 1e-15);
        assert_eq!(n, [0.0, -1.0, 0.0]);
        assert!((c.distance([1.2, 2.0, 0.0], 2).0 + 0.3).abs() < 1e-15);
    }

    #[test]
    fn a_polygon_of_either_sense_has_the_same_distances_and_outward_normals() {
        let ccw = vec![vec![0.0, 0.0], vec![2.0, 0.0], vec![2.0, 1.0], vec![0.0, 1.0]];
        let cw: Vec<Vec<f64>> = ccw.iter().rev().cloned().collect();
        for v in [ccw, cw] {
            let p = Geometry::Polygon { vertices: v };
            let (phi, n) = p.distance([1.0, -0.25, 0.0], 2);
            assert!((phi - 0.25).abs() < 1e-15 && n == [0.0, -1.0, 0.0], "{phi} {n:?}");
            let (phi, n) = p.distance([1.0, 0.2, 0.0], 2);
            assert!((phi + 0.2).abs() < 1e-15 && n == [0.0, -1.0, 0.0], "{phi} {n:?}");
            // On the surface: the edge's own normal.
            let (phi, n) = p.distance([2.0, 0.5, 0.0], 2);
            assert!(phi.abs() < 1e-15 && n == [1.0, 0.0, 0.0], "{phi} {n:?}");
        }
    }

    #[test]
    fn a_box_and_a_cylinder_measure_to_their_nearest_face() {
        let b = Geometry::Box {
            min: vec![0.0, 0.0, 0.0],
            max: vec![1.0, 1.0, 2.0],
        };
        let (phi, n) = b.distance([0.5, 0.5, 1.8], 3);
        assert!((phi + 0.2).abs() < 1e-12 && n == [0.0, 0.0, 1.0]);
        let (phi, _) = b.distance([2.0, 2.0, 1.0], 3);
        assert!((phi - 2f64.sqrt()).abs() < 1e-12);
        let c = Geometry::Cylinder {
            base: vec![0.0, 0.0, 0.0],
            axis: 2,
            length: 2.0,
            radius: 0.5,
        };
        let (phi, n) = c.distance([0.0, 0.8, 1.0], 3);
        assert!((phi - 0.3).abs() < 1e-12 && n == [0.0, 1.0, 0.0]);
        let (phi, n) = c.distance([0.0, 0.1, -0.4], 3);
        assert!((phi - 0.4).abs() < 1e-12 && n == [0.0, 0.0, -1.0]);
    }
}
