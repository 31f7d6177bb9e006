//! The surface of a body that the soil can meet: each part's own surface, less a face it
//! shares with another part (a point inside that part, as the face between a pile's base
//! and its shaft) and less what lies on or beyond a face of the grid (the axis of an
//! axisymmetric cone or pile, a wall's foot on the grid's base), where no soil flows.
//!
//! Two questions need it (`systems::rigid_contact`): which nodes past a corner a surface
//! sample lets go of ([`super::CornerTest`]), and which part bears the reaction of a node
//! inside a body of several parts ([`Exposed::bearing_part`]).

use super::geometry::polygon_edges;
use super::{Geometry, PartSpec};

/// A body's surface the soil can meet, in a grid (placed once per body and step).
#[derive(Clone, Copy, Debug)]
pub struct Exposed<'a> {
    /// The body's parts.
    pub(super) parts: &'a [PartSpec],
    /// Dimensions.
    pub(super) n: usize,
    /// The body's displacement from its starting frame (m).
    pub(super) offset: [f64; 3],
    /// The grid's corners (m) in the body's starting frame.
    lo: [f64; 3],
    /// Upper corner, as `lo`.
    hi: [f64; 3],
    /// Distances below this (m) are on a face: 1e-9 cell.
    pub(super) tolerance: f64,
}

impl<'a> Exposed<'a> {
    /// The surface of a body of `parts` displaced by `offset` (m) in an `n`-dimensional
    /// grid spanning `lo`..`hi` (m) in cells of `cell` m.
    pub fn new(
        parts: &'a [PartSpec],
        n: usize,
        offset: [f64; 3],
        (lo, hi): ([f64; 3], [f64; 3]),
        cell: f64,
    ) -> Self {
        Exposed {
            parts,
            n,
            offset,
            lo: std::array::from_fn(|a| lo[a] - offset[a]),
            hi: std::array::from_fn(|a| hi[a] - offset[a]),
            tolerance: 1e-9 * cell,
        }
    }

    /// Whether `x` (body frame) lies strictly inside the grid, off its faces.
    fn within_grid(&self, x: [f64; 3]) -> bool {
        let t = self.tolerance;
        (0..self.n).all(|a| x[a] > self.lo[a] + t && x[a] < self.hi[a] - t)
    }

    /// Whether `x` (body frame), a point of part `part`'s surface, is one the soil can
    /// meet: not inside another part, nor on or beyond a face of the grid.
    pub fn open(&self, x: [f64; 3], part: usize) -> bool {
        let t = self.tolerance;
        self.within_grid(x)
            && self
                .parts
                .iter()
                .enumerate()
                .all(|(j, p)| j == part || p.geometry.distance(x, self.n).0 > t)
    }

    /// Whether `x` (body frame), a node's nearest point of the body, is a point the soil
    /// can meet: not inside any part, nor on or beyond a face of the grid (a cone's apex
    /// on the axis is not another face of the clay below it).
    pub fn meets_soil(&self, x: [f64; 3]) -> bool {
        let t = self.tolerance;
        self.within_grid(x) && self.parts.iter().all(|p| p.geometry.distance(x, self.n).0 > -t)
    }

    /// `x` (m, grid frame) in the body's starting frame.
    pub fn in_body(&self, x: [f64; 3]) -> [f64; 3] {
        std::array::from_fn(|a| x[a] - self.offset[a])
    }

    /// Whether `f` holds for any of each part's points nearest `x` (body frame): a
    /// polygon's nearest point on each edge (its nearest edge may be one it shares with
    /// another part, with a face of the body behind it), another shape's one nearest
    /// point; in part order, stopping at the first that `f` holds for. Not checked against
    /// [`Exposed::open`].
    pub fn any_nearest(&self, x: [f64; 3], mut f: impl FnMut(Nearest) -> bool) -> bool {
        for (part, geometry) in self.parts.iter().map(|p| &p.geometry).enumerate() {
            if let Geometry::Polygon { vertices } = geometry {
                let mut edges = polygon_edges(vertices, x);
                if edges.any(|(a, b, point, normal)| {
                    f(Nearest {
                        point,
                        normal,
                        part,
                        edge: Some((a, b)),
                    })
                }) {
                    return true;
                }
            } else {
                let (d, normal) = geometry.distance(x, self.n);
                let point = std::array::from_fn(|a| x[a] - d * normal[a]);
                if f(Nearest {
                    point,
                    normal,
                    part,
                    edge: None,
                }) {
                    return true;
                }
            }
        }
        false
    }

    /// The part whose surface the soil meets nearest the node at `x` (m, grid frame)
    /// inside the body: the node's soil presses on the body there, so its constraint's
    /// force is that part's (a node inside a pile's shaft a cell above its base carries
    /// the clay under the base). A polygon's nearest point at a vertex is judged a hair
    /// (1e-6 cell) along its own edge, so that a vertex where two parts' open faces meet
    /// (a cone's shoulder) is theirs while a face two parts share is neither's. `None`
    /// when no part's nearest point is one the soil meets.
    pub fn bearing_part(&self, x: [f64; 3]) -> Option<usize> {
        let at = self.in_body(x);
        let hair = 1e3 * self.tolerance;
        let mut best: Option<(f64, usize)> = None;
        self.any_nearest(at, |n| {
            let p = n.point;
            let probe = match n.edge {
                Some((a, b)) => {
                    let (e, l) = ([b[0] - a[0], b[1] - a[1]], (b[0] - a[0]).hypot(b[1] - a[1]));
                    // At an end (a + 1·(b − a) need not round to b).
                    let at_end = |v: [f64; 2]| (p[0] - v[0]).hypot(p[1] - v[1]) <= self.tolerance;
                    let along = if at_end(a) {
                        hair / l
                    } else if at_end(b) {
                        -hair / l
                    } else {
                        0.0
                    };
                    [p[0] + along * e[0], p[1] + along * e[1], 0.0]
                }
                None => p,
            };
            let d2: f64 = (0..3).map(|a| (p[a] - at[a]).powi(2)).sum();
            if best.is_none_or(|(b, _)| d2 < b) && self.open(probe, n.part) {
                best = Some((d2, n.part));
            }
            false
        });
        best.map(|(_, k)| k)
    }
}

/// A part's point nearest a place ([`Exposed::any_nearest`]).
#[derive(Clone, Copy, Debug)]
pub struct Nearest {
    /// The point (m, body frame).
    pub point: [f64; 3],
    /// The outward unit normal there.
    pub normal: [f64; 3],
    /// The part's index.
    pub part: usize,
    /// A polygon's edge the point lies on, its two ends (m, body frame).
    pub edge: Option<([f64; 2], [f64; 2])>,
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rectangle(lo: [f64; 2], hi: [f64; 2]) -> PartSpec {
        PartSpec {
            name: "p".into(),
            geometry: Geometry::Polygon {
                vertices: vec![
                    vec![lo[0], lo[1]],
                    vec![hi[0], lo[1]],
                    vec![hi[0], hi[1]],
                    vec![lo[0], hi[1]],
                ],
            },
            area: None,
            interface: None,
        }
    }

    #[test]
    fn a_node_inside_a_pile_above_its_base_bears_on_the_base_unless_the_side_is_nearer() {
        // An axisymmetric pile on the axis r = 0: a base slab 0.0625 m thick under a
        // shaft, cells of 0.125 m.
        let parts = vec![
            rectangle([0.0, 0.0], [0.5, 0.0625]),
            rectangle([0.0, 0.0625], [0.5, 5.0]),
        ];
        let s = Exposed::new(&parts, 2, [0.0; 3], ([0.0, -10.0, 0.0], [10.0; 3]), 0.125);
        // Inside the shaft a cell above the base's bottom: the base's bottom is nearer than
        // the side (the face the two parts share and the axis are not the soil's).
        assert_eq!(s.bearing_part([0.25, 0.125, 0.0]), Some(0));
        assert_eq!(s.bearing_part([0.0625, 0.125, 0.0]), Some(0));
        // Half a cell from the side: the shaft's.
        assert_eq!(s.bearing_part([0.4375, 0.125, 0.0]), Some(1));
        assert_eq!(s.bearing_part([0.25, 1.0, 0.0]), Some(1));
        // At the corner where the base's side meets the shaft's: the side's, either part's
        // (here the base's, the first), not the far top of the shaft.
        assert_eq!(s.bearing_part([0.5, 0.0625, 0.0]), Some(0));
        // Displaced with the body: the same node relative to it.
        let moved = Exposed::new(&parts, 2, [0.0, -2.0, 0.0], ([0.0, -10.0, 0.0], [10.0; 3]), 0.125);
        assert_eq!(moved.bearing_part([0.25, -1.875, 0.0]), Some(0));
    }

    #[test]
    fn a_node_at_a_cones_shoulder_bears_on_the_tip_and_one_above_it_on_the_shaft() {
        // A 60° tip below a shaft that runs to the grid's top, on the axis.
        let tip = PartSpec {
            name: "tip".into(),
            geometry: Geometry::Polygon {
                vertices: vec![vec![0.0, 0.1339746], vec![0.5, 1.0], vec![0.0, 1.0]],
            },
            area: None,
            interface: None,
        };
        let parts = vec![tip, rectangle([0.0, 1.0], [0.5, 12.0])];
        let s = Exposed::new(&parts, 2, [0.0; 3], ([0.0, -10.0, 0.0], [10.0, 12.0, 0.0]), 0.25);
        assert_eq!(s.bearing_part([0.5, 1.0, 0.0]), Some(0));
        assert_eq!(s.bearing_part([0.25, 0.75, 0.0]), Some(0));
        assert_eq!(s.bearing_part([0.5, 1.25, 0.0]), Some(1));
        assert_eq!(s.bearing_part([0.25, 1.25, 0.0]), Some(1));
    }
}
