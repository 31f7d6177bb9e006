//! The machinery under the engine, below every domain module: how columns are allocated
//! and reached, SIMD lanes, the MPI communicator and its split of the grid, the
//! Chrome-trace timeline and the byte count of the profile. A user needs it to set the global allocator
//! ([`alloc::Coloured`]), to run over ranks ([`comm::Comm`]), or to read component columns
//! in a system of its own ([`columns`]); the simulation itself starts at the crate root.

pub mod alloc;
pub mod columns;
pub mod comm;
pub mod decomposition;
pub mod lanes;
pub mod trace;
pub mod traffic;
