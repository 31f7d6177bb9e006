//! Results on disk: `history.csv` (one row per output step), point snapshots as a
//! ParaView series (`points.pvd`, with the rigid bodies), `points.vtu` and `summary.json`.

pub mod bodies;
pub mod dir;
pub mod field_sample;
pub mod history;
pub mod plots;
pub mod progress;
pub mod recorder;
pub mod snapshots;
pub mod summary;
pub mod vtk;

pub use dir::{OutputDir, RowFile};
pub use history::{History, TracedGather};
pub use progress::Progress;
pub use recorder::Recorder;
pub use snapshots::{SnapshotSpec, SnapshotWriter, Snapshots};
pub use summary::{Outcome, Summary};
