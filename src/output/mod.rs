//! Results on disk: `history.csv` (one row per output step) and `summary.json`.

pub mod dir;
pub mod history;
pub mod summary;
pub mod vtk;

pub use dir::{OutputDir, RowFile};
pub use history::History;
pub use summary::{Outcome, Summary};
