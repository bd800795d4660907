//! A [`Subject`] (sex, age, stature, mass, breast size, posture) turned into geometry: vertebra
//! frames, ribs with their hinge axes, sternum, cartilage joints, the abdominal cavity surface
//! and the muscle element layouts. Nothing here knows about time or forces.

mod muscles;
mod subject;

pub use muscles::MuscleGroup;
pub use subject::{Posture, Sex, Subject};
