//! The FMI co-simulation layer, one version-neutral core under two thin interfaces. The
//! core: the variable table ([`variables`]), the instance state machine ([`instance`]) with
//! its neutral [`Status`] and the names each interface gives the functions it mentions
//! ([`status`]), and the guards every exported function runs behind ([`guard`]). FMI 2.0:
//! the 34 exported C functions ([`ffi`]) with their C types ([`types`]), the generated model
//! description and documentation ([`xml`]), resource URIs ([`uri`]), SSP parameter sets
//! ([`ssv`]), personalised FMUs ([`personal`]) and the packaging of `BreathingTorso.fmu`
//! ([`package`]); FMI 3.0 over the same table and instance ([`fmi3`]). It knows the model
//! only through the [`crate::model::Torso`] facade.

pub mod ffi;
pub mod fmi3;
pub mod guard;
pub mod instance;
pub mod package;
pub mod personal;
pub mod ssv;
pub mod status;
pub mod types;
pub mod uri;
pub mod variables;
pub mod xml;

pub use instance::{FmuState, Instance, Phase};
pub use status::{Api, FMI2, FMI3, Status};
pub use variables::{MODEL_IDENTIFIER, table};
