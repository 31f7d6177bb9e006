//! Linear hat functions (bilinear/trilinear by tensor product).

use super::{Shape, Stencil1};
use crate::grid::{cell_index, index_to_f64, Axis};

/// Linear hat function: w = 1 − |x − x_i|/h on the two nodes of the cell holding the point.
#[derive(Clone, Copy, Debug, Default)]
pub struct Linear;

impl Shape for Linear {
    const NAME: &'static str = "Linear";
    const SUPPORT: usize = 2;

    #[inline(always)]
    fn eval_1d(xi: f64, axis: &Axis) -> Stencil1 {
        // A point on the upper face belongs to the last cell, so it never reaches a node
        // beyond the grid.
        let base = cell_index(xi, axis);
        let f = xi - index_to_f64(base);
        Stencil1 {
            base,
            w: [1.0 - f, f, 0.0],
            dw: [-axis.inv_h, axis.inv_h, 0.0],
        }
    }
}
