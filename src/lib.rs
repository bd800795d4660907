//! # breathing_torso
//!
//! A physically based model of the human torso that breathes: rib cage, sternum, spine,
//! respiratory muscles as spring-damper elements, an incompressible abdominal cavity and a
//! skin carrying a grid of surface markers. The model follows Maldonado's 2011 Cambridge
//! thesis on breathing simulation for Structured Light Plethysmography (SLP); the mesh
//! preparation follows Peeters & Pronost 2013.
//!
//! The crate is layered; a module may use the ones above it in this list, never below:
//!
//! | module | owns |
//! |---|---|
//! | [`numeric`] | generic minimisers over a box and a seeded random number generator |
//! | [`mesh`] | triangle meshes: volume, normals, adjacency, I/O, smoothing, repair |
//! | [`recording`] | marker recordings: one file per format (grid CSV, named CSV, TRC, C3D) |
//! | [`anatomy`] | a [`anatomy::Subject`] turned into geometry and muscle layouts |
//! | [`solver`] | embedded Runge-Kutta pairs, step control, dense output, generic over [`solver::Ode`] |
//! | [`dynamics`] | the state vector and the right-hand side of the equations of motion |
//! | [`observe`] | volumes, pressures and displacements read off a state |
//! | [`model`] | the facade [`model::Torso`] |
//! | [`fit`], [`stats`] | fitting the model to SLP recordings; validation statistics against spirometry |
//! | [`fmi`], [`capi`] | the FMI 2.0 and 3.0 co-simulation layer and the native C ABI |
//! | `cli`, `bench` | the `torso` command-line tool and its measurements (feature `tools`) |
//!
//! The command-line tool and the benchmarks behind `torso bench` are compiled only with the
//! default feature `tools`. The library shipped inside the FMU is built without it
//! (`--no-default-features`, scripts/deploy.sh), so it carries neither them nor `clap`.

pub mod anatomy;
#[cfg(feature = "tools")]
pub mod bench;
pub mod capi;
#[cfg(feature = "tools")]
pub mod cli;
pub mod dynamics;
pub mod error;
pub mod fit;
pub mod fmi;
pub mod mesh;
pub mod model;
pub mod numeric;
pub mod observe;
pub mod recording;
pub mod solver;
pub mod stats;

pub use error::{Error, Result};
pub use model::{Config, Quantity, Torso};
