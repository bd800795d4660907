//! The FMI 3.0 co-simulation layer over the same variable table and the same [`Instance`] as
//! the FMI 2.0 one: the FMI 3.0 view of the table ([`view`]: types, the marker array, the
//! enumerations), the generated `modelDescription.xml` and `terminalsAndIcons.xml`
//! ([`xml`]), the exported `fmi3*` C functions ([`ffi`]) with their C types ([`types`]) and
//! the packaging of `BreathingTorso3.fmu` ([`package`]).
//!
//! [`Instance`]: super::Instance

pub mod ffi;
pub mod package;
pub mod types;
pub mod view;
pub mod xml;
