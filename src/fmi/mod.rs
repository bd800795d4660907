//! The FMI 2.0 co-simulation layer: the variable table ([`variables`]), the generated model
//! description and documentation ([`xml`]), the instance state machine ([`instance`]), the 34
//! exported C functions ([`ffi`]) with their C types ([`types`]), resource URIs ([`uri`]), SSP
//! parameter sets ([`ssv`]), personalised FMUs ([`personal`]) and the packaging of
//! `BreathingTorso.fmu` ([`package`]); and the FMI 3.0 co-simulation layer over the same table
//! and instance ([`fmi3`]). It knows the model only through the
//! [`crate::model::Torso`] facade.

pub mod ffi;
pub mod fmi3;
pub mod instance;
pub mod package;
pub mod personal;
pub mod ssv;
pub mod types;
pub mod uri;
pub mod variables;
pub mod xml;

pub use instance::{FmuState, Instance, Phase};
pub use variables::{MODEL_IDENTIFIER, table};
