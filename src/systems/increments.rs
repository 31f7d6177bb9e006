//! The stepping a displacement control shares, whether it drives grid nodes
//! (`prescribed_motion`) or a rigid body (`rigid_control`): travel at a constant velocity,
//! in increments, the last step of each covering only what is left of it.

/// A displacement control: its velocity, the distance to travel and the increment.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Increments {
    /// Velocity (m/s, x y z).
    pub vector: [f64; 3],
    /// Distance to travel along it (m).
    pub travel: f64,
    /// Distance of one increment (m); `None`: the whole travel in one.
    pub increment: Option<f64>,
}

impl Increments {
    /// A control at `vector` (m/s) over `travel` (m), in increments of `increment` (m).
    pub fn new(vector: [f64; 3], travel: f64, increment: Option<f64>) -> Self {
        Increments {
            vector,
            travel,
            increment,
        }
    }

    /// Travel at the end of increment `k` (0-based), m.
    pub fn target(&self, k: u32) -> f64 {
        match self.increment {
            Some(inc) => (inc * f64::from(k + 1)).min(self.travel),
            None => self.travel,
        }
    }

    /// One step of a control moving at `velocity` (m/s) in increment `k`: adds the distance
    /// it moved in the step's `moved` seconds (0 in a kinetic-damping reset) to `travel`, and
    /// sets `velocity` for the next step of `full` seconds: held at the end of the
    /// increment, scaled down to what is left of it in its last step. Returns the
    /// displacement of the step (m, x y z).
    pub fn advance(
        &self,
        velocity: &mut [f64; 3],
        travel: &mut f64,
        k: u32,
        moved: f64,
        full: f64,
    ) -> [f64; 3] {
        let speed = velocity.iter().map(|v| v * v).sum::<f64>().sqrt();
        *travel += speed * moved;
        let shift = velocity.map(|v| v * moved);
        let left = self.target(k) - *travel;
        let whole = self.vector.iter().map(|v| v * v).sum::<f64>().sqrt() * full;
        *velocity = if left <= 1e-12 * self.travel {
            [0.0; 3]
        } else if left < whole {
            self.vector.map(|v| v * left / whole)
        } else {
            self.vector
        };
        shift
    }
}
