//! # kdmpm
//!
//! An explicit Material Point Method turned into a static solver by dynamic relaxation with
//! kinetic damping (Sun, Song & Yang, "Application of kinetic damping in dynamic material
//! point method for static problems").
//!
//! Material points and background-grid nodes are entities of a [`hecs::World`]; their data
//! live in component columns ([`components`]). One explicit step is a [`Schedule`] of named
//! [`System`]s ([`systems`]), each timed. A [`scene`] (RON) describes a problem and builds a
//! [`Simulation`] with the schedule it needs.
//!
//! Units are SI throughout; stresses are tension positive.
//!
//! ## Where to start
//!
//! - Run a scene: [`LoadedScene::from_file`], then [`Run`] (into a directory, in memory,
//!   resumed from a checkpoint); its [`RunReport`] holds the [`Summary`].
//! - Step it yourself: [`scene::build`] gives an [`AnySimulation`]; [`Simulation::step`]
//!   and [`Simulation::run`], the state in [`SolverState`].
//! - Add a system to the schedule: [`System`], [`FnSystem`], [`Context`]; the columns a
//!   system reads are [`components`], reached through [`infra::columns`]
//!   (docs/writing-a-system.md).
//! - Add a material: [`materials`] (docs/writing-a-material.md).
//! - Analyses over runs: [`fos`] (factor of safety by strength reduction) and [`study`]
//!   (speed against accuracy).
//!
//! The machinery beneath (allocation, SIMD lanes, threads and MPI ranks) is in [`infra`].
#![warn(missing_docs)]

// First, with `#[macro_use]`: their `macro_rules!` (`point_components!`, `with_simulation!`)
// are in scope in every module declared after them, without a path back to the crate root.
#[macro_use]
pub mod components;
#[macro_use]
mod simulation;

pub mod checkpoint;
mod context;
mod dim;
pub mod element_test;
mod error;
pub mod fos;
mod grid;
pub mod infra;
mod interrupt;
pub mod materials;
pub mod measure;
pub mod model;
pub mod output;
pub(crate) mod parallel;
pub(crate) mod polygon;
pub mod refine;
pub mod rigid;
pub mod run;
pub mod scene;
mod schedule;
pub mod shape;
pub mod state;
pub mod study;
mod surface_pressure;
pub mod systems;
pub mod tensor;
#[cfg(test)]
mod testing;
pub(crate) mod unique_map;
pub mod water;

pub use context::Context;
pub use dim::{Dim, Dim2, Dim3, DimAxi, Vector};
pub use error::{Ending, Refusal, SceneError, StepError};
pub use grid::{Axis, Face, Grid, NodeBox};
pub use interrupt::{catch_signals, StopSignal};
pub use output::{Outcome, Summary};
/// The scatters' grouping of points, kept in the [`Context`]: a system that moves or
/// reorders points calls `ctx.slabs.invalidate()`.
pub use parallel::SlabCache;
pub use run::{Run, RunError, RunReport};
pub use scene::LoadedScene;
pub use schedule::{FnSystem, Schedule, System, Timing};
pub use simulation::{AnySimulation, Simulation, TracedResult};
pub use state::SolverState;
pub use surface_pressure::{ArcPoint, SurfacePoint, SurfacePressures};
