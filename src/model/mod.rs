//! The facade: [`Torso`] owns a compiled model (immutable, shared behind an `Arc`) and its
//! data (time, state, activations, drive, solver memory, cached observations). It is all that
//! the FMI layer, the C ABI, the fitting loop and the CLI need.
//!
//! ```no_run
//! use breathing_torso::{Config, Quantity, Torso};
//! use breathing_torso::model::Drive;
//! let mut config = Config::default();
//! config.drive = Drive::quiet();
//! let mut torso = Torso::new(config)?;
//! torso.advance_to(4.0)?;
//! let litres = torso.read(Quantity::LungVolume)?;
//! # Ok::<(), breathing_torso::Error>(())
//! ```

pub mod bounds;
mod config;
pub mod drive;
pub mod output;
mod quantity;
pub mod run;
mod snapshot;
mod torso;

pub use config::{
    Config, GroupGains, Scene, SolverConfig, parse_postural_tone, postural_tone_code,
    postural_tone_from_code,
};
pub(crate) use drive::check;
pub use drive::{Breath, Breaths, Drive, Wave};
pub use quantity::Quantity;
pub use snapshot::{Checkpoint, Snapshot};
pub use torso::{AIRWAY_OPENING_RANGE, AdvanceOptions, AdvanceStats, Compiled, Sample, Torso};
