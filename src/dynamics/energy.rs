//! Mechanical energy of a state, for tests of dissipation: kinetic energy of ribs, sternum and
//! vertices; elastic energy of elements (muscles count only when stretched, as they only pull;
//! evaluated at zero activation), vector springs and rib joints; the pressure potentials of the
//! abdomen, K (V - V0 - V0 ln(V/V0)), and of the lungs, the integral of their recoil
//! ([`super::pleural::PleuralLaw::energy`], E_L (V - V0)^2 / 2 near rest); gravity; and the
//! potential of the constant preloads.

use super::model::{Model, PASSIVE, RIBS, path_length, volume};
use super::state::Layout;
use super::{Data, kinematics};
use nalgebra::Vector3;

/// Total mechanical energy [J] of state `y` with no muscle activation.
pub fn mechanical_energy(model: &Model, data: &mut Data, y: &[f64]) -> f64 {
    let l = Layout::new(model);
    kinematics::positions_and_velocities(model, data, &l, y);
    let mut e = 0.0;
    // Kinetic.
    for r in 0..RIBS {
        e += 0.5 * model.rib_inertia[r] * y[l.theta_dot + r].powi(2);
    }
    let v = Vector3::new(y[l.sternum_v], y[l.sternum_v + 1], y[l.sternum_v + 2]);
    e += 0.5 * model.sternum_mass * v.norm_squared();
    let rot = data.sternum_rotation.to_rotation_matrix();
    let inertia = rot.matrix() * model.sternum_inertia * rot.matrix().transpose();
    e += 0.5 * data.sternum_w.dot(&(inertia * data.sternum_w));
    for (j, m) in model.vertex_mass.iter().enumerate() {
        let pv = l.vertex_v + 3 * j;
        e += 0.5 * m * (y[pv].powi(2) + y[pv + 1].powi(2) + y[pv + 2].powi(2));
    }
    // Elastic.
    let el = &model.elements;
    for i in 0..el.len() {
        let len = path_length(&data.pos, el.path_of(i));
        let stretch = len - el.rest_length[i];
        if el.group[i] == PASSIVE || stretch > 0.0 {
            e += 0.5 * el.stiffness[i] * stretch * stretch;
        }
    }
    let s = &model.springs;
    for i in 0..s.a.len() {
        let mut d = data.pos[s.b[i] as usize] - data.pos[s.a[i] as usize];
        if s.horizontal[i] {
            d.y = 0.0;
        }
        e += 0.5 * s.stiffness[i] * d.norm_squared();
    }
    for r in 0..RIBS {
        e += 0.5 * model.rib_stiffness[r] * y[l.theta + r].powi(2);
    }
    // Pressures.
    let (v0, va) = (
        model.abdomen_rest_volume,
        volume(&data.pos, &model.abdomen_triangles),
    );
    e += model.params.bulk_modulus * (va - v0 - v0 * (va / v0).ln());
    let vt = volume(&data.pos, &model.thorax_triangles);
    e += model.pleural.energy(vt);
    // Gravity and preloads (constant generalised forces have linear potentials).
    for r in 0..RIBS {
        let h = model.rib_head[r];
        let com = h + data.rib_rotation[r] * (model.rib_com[r] - h);
        e -= model.rib_mass[r] * model.gravity.dot(&com.coords);
        e -= model.rib_preload[r] * y[l.theta + r];
    }
    e -= (model.gravity * model.sternum_mass + model.sternum_preload).dot(&data.sternum_x.coords);
    for (j, m) in model.vertex_mass.iter().enumerate() {
        let px = l.vertex_x + 3 * j;
        let x = Vector3::new(y[px], y[px + 1], y[px + 2]);
        e -= (model.gravity * *m + model.vertex_preload[j]).dot(&x);
    }
    let _: &mut Data = data;
    e
}
