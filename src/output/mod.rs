//! Results on disk: `history.csv` (one row per output step) and `summary.json`.

pub mod history;
pub mod summary;
pub mod vtk;

pub use history::History;
pub use summary::Summary;
