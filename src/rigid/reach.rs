//! Where a body's surface can meet the grid: the box its samples are cut to.

/// A box (m, x y z) in the body's starting frame: the places its surface can reach the grid
/// from over its travel, with the shape functions' support around it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Reach {
    /// Lower corner.
    pub lo: [f64; 3],
    /// Upper corner.
    pub hi: [f64; 3],
}

impl Reach {
    /// Everywhere (tests, and shapes known to be small).
    pub const ALL: Reach = Reach {
        lo: [f64::NEG_INFINITY; 3],
        hi: [f64::INFINITY; 3],
    };

    /// Whether `x` (m) lies in the box.
    pub(crate) fn holds(&self, x: [f64; 3]) -> bool {
        (0..3).all(|a| x[a] >= self.lo[a] && x[a] <= self.hi[a])
    }
}
