//! What is read off a state: volumes, pressures, and markers via skinning.

pub mod skinning;
