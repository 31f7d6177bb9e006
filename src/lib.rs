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
#![warn(missing_docs)]

pub mod alloc;
pub mod checkpoint;
pub mod columns;
pub mod comm;
pub mod components;
pub mod context;
pub mod decomposition;
pub mod dim;
pub mod distributed;
pub mod error;
pub mod fos;
pub mod grid;
pub mod interrupt;
pub mod lanes;
pub mod materials;
pub mod measure;
pub mod output;
pub mod parallel;
pub mod scene;
pub mod schedule;
pub mod shape;
pub mod simulation;
pub mod state;
pub mod study;
pub mod systems;
pub mod tensor;
#[cfg(test)]
mod testing;

pub use context::Context;
pub use dim::{Dim, Dim2, Dim3};
pub use error::{SceneError, StepError};
pub use schedule::{FnSystem, Schedule, System};
pub use simulation::{AnySimulation, Simulation};
