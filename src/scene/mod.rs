//! Scenes: the RON description of a problem, its validation, and building a simulation.
//!
//! The format is documented field by field in `docs/scene-format.md`. Units are SI
//! (m, s, kg, Pa, N); angles are in degrees. Vectors are lists with one entry per axis.

//!
//! `spec.rs` is the schema (what serde reads), `loaded.rs` a scene with its text (for
//! messages that point into the file), `validate/` the rules it must hold, `build.rs` the
//! simulation made from a valid scene; this file only names what the others offer.

mod build;
mod initial_stress;
mod loaded;
pub mod locate;
mod region;
mod spec;
mod tractions;
mod validate;

pub use crate::materials::MaterialSpec;
pub use build::{build, build_part, RankPart};
pub use loaded::LoadedScene;
pub use spec::{
    BodySpec, BoundarySpec, CheckpointEvery, Condition, Dimension, GravitySpec, GridSpec, InitialStress,
    OutputSpec, PointLoadSpec, Region, Scene, SolverSpec, StageSpec, StrengthReductionSpec, TimeStep,
    TracedSpec, TractionSpec, TractionSurface,
};
pub use validate::{check, Checked, CheckedGrid, CheckedStage, Derived, Estimate, FaceHold};
