//! What one evaluation of the right-hand side reads and writes besides the model and the
//! state: the muscles' [`Activations`] (per group and side, and the pressure at the airway
//! opening) and the scratch memory [`Data`] (poses, anchor positions, velocities and forces,
//! the cavities' volumes and pressures of the last evaluation), sized once per model so
//! that the right-hand side allocates nothing.

use super::{RIBS, Structure, forces};
use crate::anatomy::MuscleGroup;
use nalgebra::{Matrix3, Point3, UnitQuaternion, Vector3};

/// What drives the model in one evaluation: the activations applied to the muscles, per
/// group, per side (right, left, midline), already clamped and multiplied by the side gains,
/// and the pressure at the airway opening (a ventilator's, 0 when breathing air at the
/// body's surface pressure).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Activations {
    /// `[group][side]`.
    pub level: [[f64; 3]; MuscleGroup::COUNT],
    /// Pressure at the airway opening relative to the body surface [Pa]: it reaches the
    /// alveoli through the airway resistance and pushes the thoracic wall outward.
    pub airway_opening: f64,
    /// The airway occluded at the mouth: `Some(n)`, the dry gas content of the lungs
    /// (P_B + P_alv - P_H2O) V_gas [Pa m^3] fixed when the airway closed, so that the alveolar
    /// pressure follows Boyle's law ([`super::airway`]) and no gas flows; `None`: open.
    pub occlusion: Option<f64>,
}

impl Activations {
    /// From per-group activations in [0, 1] and the left/right gains: a = min(1, a_g G_side).
    pub fn new(groups: &[f64; MuscleGroup::COUNT], gain_right: f64, gain_left: f64) -> Activations {
        Activations::per_group(
            groups,
            &[gain_right; MuscleGroup::COUNT],
            &[gain_left; MuscleGroup::COUNT],
        )
    }

    /// From per-group activations in [0, 1] and per-group gains of each side: a = min(1,
    /// a_g G_g,side); midline elements take the mean of the two sides' gains.
    pub fn per_group(
        groups: &[f64; MuscleGroup::COUNT],
        right: &[f64; MuscleGroup::COUNT],
        left: &[f64; MuscleGroup::COUNT],
    ) -> Activations {
        let mut level = [[0.0; 3]; MuscleGroup::COUNT];
        for (g, a) in groups.iter().enumerate() {
            let a = a.clamp(0.0, 1.0);
            let (r, l) = (right[g], left[g]);
            level[g] = [
                (a * r).min(1.0),
                (a * l).min(1.0),
                (a * 0.5 * (r + l)).min(1.0),
            ];
        }
        Activations {
            level,
            airway_opening: 0.0,
            occlusion: None,
        }
    }

    /// The same activations with the airway opening at `pressure` [Pa].
    pub fn with_airway_opening(self, pressure: f64) -> Activations {
        Activations {
            airway_opening: pressure,
            ..self
        }
    }

    /// The same activations with the airway occluded on the dry gas content `content`
    /// [Pa m^3] (`None`: open; [`super::airway::gas_content`]).
    pub fn with_occlusion(self, content: Option<f64>) -> Activations {
        Activations {
            occlusion: content,
            ..self
        }
    }

    /// The levels as a table indexed by an element's [`Elements::slot`](super::Elements::slot) (3 group + side);
    /// every other entry, [`PASSIVE`](super::PASSIVE)'s included, is 0. It has 256 entries so that indexing
    /// it with a `u8` needs no bounds check.
    pub fn table(&self) -> [f64; 256] {
        let mut table = [0.0; 256];
        for (g, sides) in self.level.iter().enumerate() {
            table[3 * g..3 * g + 3].copy_from_slice(sides);
        }
        table
    }

    /// Whether every group is inactive and the airway open at the surface pressure.
    pub fn is_zero(&self) -> bool {
        self.airway_opening == 0.0
            && self.occlusion.is_none()
            && self.level.iter().all(|s| s.iter().all(|a| *a == 0.0))
    }
}

/// Scratch memory of the right-hand side, sized once per model.
#[derive(Clone, Debug)]
pub struct Data {
    /// Rib rotation matrices.
    pub rib_rotation: Vec<Matrix3<f64>>,
    /// Sternum orientation.
    pub sternum_rotation: UnitQuaternion<f64>,
    /// Sternum centre of mass.
    pub sternum_x: Point3<f64>,
    /// Sternum angular velocity (world).
    pub sternum_w: Vector3<f64>,
    /// Anchor positions.
    pub pos: Vec<Point3<f64>>,
    /// Anchor velocities.
    pub vel: Vec<Vector3<f64>>,
    /// Forces on anchors.
    pub force: Vec<Vector3<f64>>,
    /// Doubled area vector (b - a) x (c - a) of each abdominal triangle, then of each
    /// thoracic triangle (scratch of the pressure forces). The entries of the triangles fixed
    /// to the ground are filled once, at the rest positions, and never rewritten.
    pub face: Vec<Vector3<f64>>,
    /// Volume term a . (b x c) of each abdominal triangle, then of each thoracic one
    /// (scratch: the thoracic dome reuses the abdominal ones; the fixed triangles' terms are
    /// the constants filled by [`Data::new`], which the volume sums read).
    pub term: Vec<f64>,
    /// Generalised torque per rib.
    pub rib_torque: Vec<f64>,
    /// Net force on the sternum.
    pub sternum_force: Vector3<f64>,
    /// Net torque on the sternum about its centre of mass.
    pub sternum_torque: Vector3<f64>,
    /// Abdominal volume of the last evaluation [m^3].
    pub abdomen_volume: f64,
    /// Abdominal pressure of the last evaluation [Pa].
    pub abdomen_pressure: f64,
    /// Thoracic volume of the last evaluation [m^3].
    pub thorax_volume: f64,
    /// Pleural pressure change of the last evaluation [Pa].
    pub pleural_pressure: f64,
}

impl Data {
    /// Scratch memory for a model of structure `model`.
    pub fn new(model: &Structure) -> Data {
        let n = model.rest.len();
        let mut data = Data {
            rib_rotation: vec![Matrix3::identity(); RIBS],
            sternum_rotation: UnitQuaternion::identity(),
            sternum_x: model.sternum_com,
            sternum_w: Vector3::zeros(),
            pos: model.rest.clone(),
            vel: vec![Vector3::zeros(); n],
            force: vec![Vector3::zeros(); n],
            face: vec![
                Vector3::zeros();
                model.abdomen_triangles.len() + model.thorax_triangles.len()
            ],
            term: vec![0.0; model.abdomen_triangles.len() + model.thorax_triangles.len()],
            rib_torque: vec![0.0; RIBS],
            sternum_force: Vector3::zeros(),
            sternum_torque: Vector3::zeros(),
            abdomen_volume: model.abdomen_rest_volume,
            abdomen_pressure: 0.0,
            thorax_volume: model.thorax_rest_volume,
            pleural_pressure: 0.0,
        };
        forces::rest_terms(model, &mut data.face, &mut data.term);
        data
    }
}
