//! The engine's tests, one module per behaviour area, in one test binary: the engine's
//! generic code is compiled once for all of them (a binary per file compiled it thirty
//! times over), and the harness spreads every test over its threads at once.
//! `cargo test --release slope::` runs one area.

#[path = "../common/mod.rs"]
mod common;

mod anti_locking;

mod axisymmetric;
mod bar;
mod byte_budget;
mod cam_clay;
mod checkpoint_integrity;
mod checkpoint_resume;
mod custom_system;
mod determinism;
mod extremes;
mod fos;
mod friction;
mod fuzz_scenes;
mod geostatic;
mod pay_for_what_you_use;
mod plane_strain;
mod prescribed_motion;
mod rank_parts;
mod refine;
mod rigid_bodies;
mod robustness;
mod robustness_bodies;
mod robustness_features;
mod run_in_process;
mod scene_errors;
mod self_weight;
mod slope;
mod snapshots;
mod softening;
mod spatial_sort;
mod stages;
mod stress_update_lanes;
mod tractions;
mod vtk_output;
mod water;
