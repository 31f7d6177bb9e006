//! Which grid nodes beyond a body's surface a surface sample holds: not those that face a
//! corner of the body.
//!
//! A sample's soil velocity is the mean of its nodes' (`systems::rigid_contact`), and the
//! nodes at and inside the body already move with it; so whatever node outside the body a
//! sample reaches moves with it too, up to 1.5 h beyond the surface. Under a flat face that
//! is the soil the face pushes. Past a corner it is not: below a footing's edge the soil
//! within a node's distance of the edge is not under the base (Prandtl's active wedge
//! narrows to nothing at the edge), and holding it to the base widened a rigid strip
//! footing by that band, +11.6 % on Prandtl's pressure at h = B/8 (+9.2 % at B/16; the
//! node-driven footing, which holds one row, −2 %).
//!
//! Two tests, both from the exact geometry. First, the node must face the sample's face: a
//! node whose own nearest surface point has a normal more than 45° from the sample's
//! ([`CORNER`]) is another face's soil, as the sand under a wall's foot is beside the
//! wall's face, or the clay beside a footing above its base is beside the base; a sample
//! holding it moved it with the wrong face (a smooth wall in sand that goes on below its
//! toe bore the sand under its foot as if the wall were a cell taller: +7.4 % on Rankine
//! over 2–10 % of H at h = H/20, +1.8 % once it lets go).
//!
//! Second, the node's mirror image in the surface. A node at distance φ outside the
//! body, with outward normal n at its nearest surface point, has its mirror at
//! q = x − 2φ n, at depth φ in the body. Where the surface round the node's foot is flat
//! (or curves away, as a sphere's) no surface point lies nearer q than φ; where it turns at
//! a corner within that reach, the other face does. A sample does not hold a node when a
//! point of the body's surface nearer its mirror than φ has a normal more than 45° from
//! the sample's own ([`CORNER`]): a box's or a footing's edge (90°) and a pile's base edge
//! are corners; a cone's shoulder (30°) and a faceted sphere's edges are not. A node
//! diagonally past an edge, whose nearest surface point is the edge itself, mirrors to a
//! point as far from the side as the node is, nearer than φ: not held either.
//!
//! The surface is the one the soil meets ([`Exposed`]): each part's exact geometry (the
//! nearest point of each part to the mirror, of each edge of a polygon), less the face a
//! cone's tip and shaft share and what lies on a face of the grid, such as the axis.

use super::exposed::Exposed;
use serde::{Deserialize, Serialize};

/// cos 45°: a surface point whose normal's cosine with a sample's is below this is
/// another face.
pub const CORNER: f64 = std::f64::consts::FRAC_1_SQRT_2;

/// Whether a body's contact samples hold the soil past its corners (`corners` of a rigid
/// body in a scene).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum Corners {
    /// A sample holds every node of its support that carries soil.
    #[default]
    Held,
    /// A sample does not hold the nodes past a corner ([`CornerTest`]).
    Released,
}

/// A node's place against a body ([`CornerTest::locate`]).
#[derive(Clone, Copy, Debug)]
pub struct Located {
    /// The node in the body's starting frame (m).
    pub at: [f64; 3],
    /// Its signed distance from the body (m, outside when positive).
    pub phi: f64,
    /// The outward unit normal at its nearest surface point.
    pub nearest: [f64; 3],
}

/// A body's corner test in a grid (`systems::rigid_contact` places one per body a step).
#[derive(Clone, Copy, Debug)]
pub struct CornerTest<'a> {
    /// The body's surface the soil meets.
    surface: Exposed<'a>,
}

impl<'a> CornerTest<'a> {
    /// The test of a body whose surface the soil meets is `surface`.
    pub fn new(surface: Exposed<'a>) -> Self {
        CornerTest { surface }
    }

    /// Where the node at `x` (m, in the grid's frame) stands to the body: its place in the
    /// body's frame, its distance (m, outside when positive) and the outward normal at its
    /// nearest surface point, the arguments of [`CornerTest::holds`] that do not depend on
    /// the sample (found once a node and step by `systems::rigid_contact`).
    pub fn locate(&self, x: [f64; 3]) -> Located {
        let s = &self.surface;
        let at = s.in_body(x);
        let (phi, nearest, _) = super::distance(s.parts, at, s.n);
        Located { at, phi, nearest }
    }

    /// Whether a sample with outward `normal` holds the node `node` ([`CornerTest::locate`]).
    pub fn holds_node(&self, node: &Located, normal: [f64; 3]) -> bool {
        self.holds(node.at, node.phi, node.nearest, normal)
    }

    /// Whether a sample with outward `normal` holds a node at `at` (body frame, m) that
    /// lies `phi` m from the body (outside when positive) with outward normal `nearest` at
    /// its nearest surface point: false when `nearest` is more than 45° from `normal` at a
    /// point the soil meets (the node faces another face), or when a surface point nearer
    /// the node's mirror `at − 2 φ n` than φ has a normal more than 45° from `normal`.
    pub fn holds(&self, at: [f64; 3], phi: f64, nearest: [f64; 3], normal: [f64; 3]) -> bool {
        if phi <= self.surface.tolerance {
            return true;
        }
        let facing: f64 = (0..3).map(|a| nearest[a] * normal[a]).sum();
        if facing < CORNER
            && self
                .surface
                .meets_soil(std::array::from_fn(|a| at[a] - phi * nearest[a]))
        {
            return false;
        }
        let q: [f64; 3] = std::array::from_fn(|a| at[a] - 2.0 * phi * nearest[a]);
        let reach = phi * (1.0 - 1e-9);
        // A face nearer the mirror than φ, turned from the sample's, and the body's surface.
        !self.surface.any_nearest(q, |n| {
            let d2: f64 = (0..3).map(|a| (n.point[a] - q[a]).powi(2)).sum();
            let cos: f64 = (0..3).map(|a| n.normal[a] * normal[a]).sum();
            d2 < reach * reach && cos < CORNER && self.surface.open(n.point, n.part)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rigid::{Geometry, PartSpec};

    fn part(geometry: Geometry) -> PartSpec {
        PartSpec {
            name: "p".into(),
            geometry,
            area: None,
            interface: None,
        }
    }

    fn corners(parts: &[PartSpec]) -> CornerTest<'_> {
        CornerTest::new(Exposed::new(parts, 2, [0.0; 3], ([-10.0; 3], [10.0; 3]), 1e-3))
    }

    /// The axis-aligned rectangle from `lo` to `hi` (m), a part of its own.
    fn rectangle(lo: [f64; 2], hi: [f64; 2]) -> PartSpec {
        part(Geometry::Polygon {
            vertices: vec![
                vec![lo[0], lo[1]],
                vec![hi[0], lo[1]],
                vec![hi[0], hi[1]],
                vec![lo[0], hi[1]],
            ],
        })
    }

    /// A 2 m × 0.5 m block whose base lies on y = 0.
    fn block() -> Vec<PartSpec> {
        vec![rectangle([-1.0, 0.0], [1.0, 0.5])]
    }

    #[test]
    fn a_base_sample_holds_the_nodes_under_the_base_and_not_those_past_its_edge() {
        let parts = block();
        let c = corners(&parts);
        let down = [0.0, -1.0, 0.0];
        // A cell below the middle of the base, and one 0.5 m in from the edge.
        assert!(c.holds([0.0, -0.25, 0.0], 0.25, down, down));
        assert!(c.holds([0.5, -0.25, 0.0], 0.25, down, down));
        // Below the edge, and nearer the side than the node's depth: the side is nearer
        // the mirror than the node.
        assert!(!c.holds([1.0, -0.25, 0.0], 0.25, down, down));
        assert!(!c.holds([0.9, -0.25, 0.0], 0.25, down, down));
        // Diagonally past the edge.
        let d = (0.2f64 * 0.2 + 0.05 * 0.05).sqrt();
        let diagonal = [0.2 / d, -0.05 / d, 0.0];
        assert!(!c.holds([1.2, -0.05, 0.0], d, diagonal, down));
        // A node on or inside the body is always held.
        assert!(c.holds([1.0, 0.1, 0.0], -0.1, down, down));
    }

    #[test]
    fn a_face_sample_does_not_hold_the_soil_under_the_bodys_foot() {
        // A wall 0.4 m thick whose foot lies on y = 0, its face on x = 0, sand in front
        // and below.
        let parts = vec![rectangle([-0.4, 0.0], [0.0, 2.6])];
        let c = corners(&parts);
        let face = [1.0, 0.0, 0.0];
        let down = [0.0, -1.0, 0.0];
        // In front of the face, above the toe: held.
        assert!(c.holds([0.1, 0.5, 0.0], 0.1, face, face));
        // Under the foot, a few centimetres behind the face: the foot's soil, not the
        // face's, though its mirror finds no face nearer than its own.
        assert!(!c.holds([-0.05, -0.1, 0.0], 0.1, down, face));
        assert!(!c.holds([-0.1, -0.1, 0.0], 0.1, down, face));
        // The foot's own samples hold it.
        assert!(c.holds([-0.1, -0.1, 0.0], 0.1, down, down));
    }

    #[test]
    fn a_circle_and_a_blunt_bend_have_no_corners() {
        let parts = vec![part(Geometry::Circle {
            centre: vec![0.0, 0.0],
            radius: 0.5,
        })];
        let c = corners(&parts);
        for k in 0..36 {
            let t = k as f64 * std::f64::consts::PI / 18.0;
            let n = [t.cos(), t.sin(), 0.0];
            for phi in [0.05, 0.1, 0.1875] {
                let at = n.map(|c| c * (0.5 + phi));
                assert!(c.holds(at, phi, n, n), "angle {t}, distance {phi}");
            }
        }
        // A 30° bend (a cone's shoulder: its face's normal 30° below the shaft's): the
        // face beyond the bend is not another face for the nodes in front of it.
        let rise = 60f64.to_radians().tan();
        let parts = vec![part(Geometry::Polygon {
            vertices: vec![
                vec![0.0, -1.0],
                vec![1.0, -1.0 + rise],
                vec![1.0, 2.0],
                vec![0.0, 2.0],
            ],
        })];
        let c = corners(&parts);
        let face = [30f64.to_radians().cos(), -0.5, 0.0];
        let foot = [0.95, -1.0 + 0.95 * rise, 0.0];
        for phi in [0.05, 0.1, 0.1875] {
            let at: [f64; 3] = std::array::from_fn(|a| foot[a] + phi * face[a]);
            assert!(c.holds(at, phi, face, face), "distance {phi}");
        }
    }

    #[test]
    fn a_face_two_parts_share_and_a_face_on_the_grid_are_not_corners() {
        // A pile: a thin base under a shaft, on the axis x = 0 of an axisymmetric grid.
        let parts = vec![
            rectangle([0.0, 0.0], [0.5, 0.0625]),
            rectangle([0.0, 0.0625], [0.5, 5.0]),
        ];
        let c = CornerTest::new(Exposed::new(
            &parts,
            2,
            [0.0; 3],
            ([0.0, -10.0, 0.0], [10.0; 3]),
            1e-3,
        ));
        let down = [0.0, -1.0, 0.0];
        // Under the base's middle and on the axis, a cell down: held (the base part's top,
        // the shaft's bottom and the axis are not faces the soil meets).
        assert!(c.holds([0.25, -0.125, 0.0], 0.125, down, down));
        assert!(c.holds([0.0, -0.125, 0.0], 0.125, down, down));
        // Under the pile's edge: its side is a face.
        assert!(!c.holds([0.5, -0.125, 0.0], 0.125, down, down));
        // A 60° cone's apex on the axis: the clay below it, nearest the apex, is the
        // face's, though its nearest point's normal is 60° from the face's.
        let rise = 60f64.to_radians().tan();
        let parts = vec![part(Geometry::Polygon {
            vertices: vec![
                vec![0.0, 0.0],
                vec![0.5, 0.5 * rise],
                vec![0.5, 3.0],
                vec![0.0, 3.0],
            ],
        })];
        let c = CornerTest::new(Exposed::new(
            &parts,
            2,
            [0.0; 3],
            ([0.0, -10.0, 0.0], [10.0; 3]),
            1e-3,
        ));
        let face = [30f64.to_radians().cos(), -0.5, 0.0];
        let at = [0.0625, -0.3, 0.0];
        let phi = (0.0625f64.powi(2) + 0.09).sqrt();
        let nearest = [0.0625 / phi, -0.3 / phi, 0.0];
        assert!((face[0] * nearest[0] + face[1] * nearest[1]) < CORNER);
        assert!(c.holds(at, phi, nearest, face));
    }
}
