//! Mechanical energy of a state, for tests of dissipation: kinetic energy of ribs, sternum and
//! vertices; elastic energy of elements (muscles and the dome's membrane edges count only
//! when stretched, as they only pull; the abdominal membrane's edges, linear springs, in
//! compression too; the muscles at zero activation or at held activations), vector springs
//! and rib joints; the pressure potentials of the abdomen, K (V - V0 - V0 ln(V/V0)), and of
//! the lungs, the integral of their recoil ([`super::pleural::PleuralLaw::energy`],
//! E_L (V - V0)^2 / 2 near rest); gravity; and the potential of the constant preloads.

use super::model::Model;
use super::structure::{RIBS, path_length, volume};
use super::{Activations, Data, kinematics};
use nalgebra::Vector3;

/// Total mechanical energy [J] of state `y` with no muscle activation.
pub fn mechanical_energy(model: &Model, data: &mut Data, y: &[f64]) -> f64 {
    mechanical_energy_at(model, data, y, &Activations::default())
}

/// Total mechanical energy [J] of state `y` with the muscles held at the activations `act`
/// (their levels; the airway's pressure and occlusion are not counted): each muscle's elastic
/// energy is the potential of its force at that activation, so that under a constant
/// activation (the standing abdominal tone, a held input), with the airway open at zero
/// pressure, motion only loses energy. Under
/// the thesis's law an active element is its spring about the shortened rest length
/// l0 (1 - a g), g its contraction per unit activation ([`super::Elements::gain`]); under the
/// passive-and-active law the integral of its tension
/// ([`super::muscle::energy`]).
pub fn mechanical_energy_at(model: &Model, data: &mut Data, y: &[f64], act: &Activations) -> f64 {
    let l = model.layout;
    let level = act.table();
    kinematics::positions_and_velocities(model, data, &l, y);
    let mut e = 0.0;
    // Kinetic: the generalised velocities (rib rates, sternum velocity and angular
    // velocity, vertex velocities) are contiguous in the state.
    e += model.mass.kinetic_energy(&y[l.theta_dot..]);
    // Elastic: an element's tension is the softplus of its spring force (`forces::tension`),
    // whose potential is the integral of that softplus over the stretch.
    let el = &model.elements;
    let toe = model.params.tension_toe;
    for i in 0..el.len() {
        let len = path_length(&data.pos, el.path_of(i));
        if el.max_force[i] > 0.0 {
            // a muscle under the passive-and-active law: its tension's potential at its
            // activation (as `forces` applies it: the slot's level times the element's drive)
            let (slack, f_max) = (el.slack_length[i], el.max_force[i]);
            let a = level[el.slot[i] as usize] * el.drive[i];
            e += super::muscle::energy(
                len,
                el.optimal_length[i],
                slack,
                f_max,
                a,
                super::muscle::active_stiffness(),
                toe,
            );
            continue;
        }
        // the rest length under the activation, l0 (1 - a g) (`forces`; a membrane's gain is 0)
        let rest = el.rest_length[i] * (1.0 - level[el.slot[i] as usize] * el.gain[i]);
        let stretch = len - rest;
        let k = el.stiffness[i];
        if el.slot[i] == super::structure::PASSIVE {
            // an abdominal membrane edge with linear edges (the thesis law's wall): a linear
            // spring in compression as in tension (`forces`; under
            // `Params::abdominal_wall_tension_only` its slot is `PASSIVE_SLACK`, below)
            e += 0.5 * k * stretch * stretch;
            continue;
        }
        e += softplus_integral(k * stretch, toe) / k;
    }
    let s = &model.springs;
    for i in 0..s.a.len() {
        let mut d = data.pos[s.b[i] as usize] - data.pos[s.a[i] as usize];
        if s.horizontal[i] {
            d.y = 0.0;
        }
        e += 0.5 * s.stiffness[i] * d.norm_squared();
        let lambda = s.unloading[i];
        if lambda > 0.0 {
            // the normal part's linear energy replaced by the unloading law's
            let u = -d.dot(&s.normal[i]);
            let k = s.stiffness[i];
            e += super::forces::unloading_energy(k, lambda, u) - 0.5 * k * u * u;
        }
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
        e -= model.preload.rib[r] * y[l.theta + r];
    }
    e -= (model.gravity * model.sternum_mass + model.preload.sternum_force)
        .dot(&data.sternum_x.coords);
    // the constant torque's potential over the sternum's rotation from rest (its rotation
    // vector: exact for rotations about a fixed axis, and to second order otherwise)
    e -= model
        .preload
        .sternum_torque
        .dot(&data.sternum_rotation.scaled_axis());
    for (j, m) in model.vertex_mass.iter().enumerate() {
        let px = l.vertex_x + 3 * j;
        let x = Vector3::new(y[px], y[px + 1], y[px + 2]);
        e -= (model.vertex_gravity * *m + model.preload.vertex[j]).dot(&x);
    }
    e += hydrostatic_energy(model, &data.pos);
    let _: &mut Data = data;
    e
}

/// Potential energy [J] of the abdominal contents' hydrostatic pressure
/// ([`super::forces`]): -rho g . integral over the cavity of (x - x_c) dV, the contents'
/// weight's potential relative to their rest centroid x_c, written by the divergence theorem
/// as a sum over the cavity's triangles, -rho (g . A_2) Q / (24 |g|^2) with A_2 the doubled
/// area vector and Q = s_a^2 + s_b^2 + s_c^2 + s_a s_b + s_b s_c + s_c s_a, s = g . (x - x_c)
/// at the corners. Zero without gravity or contents.
pub fn hydrostatic_energy(model: &super::Structure, pos: &[nalgebra::Point3<f64>]) -> f64 {
    let (rho, g) = (model.contents_density, model.gravity);
    let g2 = g.norm_squared();
    if rho == 0.0 || g2 == 0.0 {
        return 0.0;
    }
    let c = model.contents_centre;
    let mut sum = 0.0;
    for t in &model.abdomen_triangles {
        let [a, b, d] = t.map(|i| pos[i as usize]);
        let face = (b - a).cross(&(d - a));
        let [sa, sb, sd] = [a, b, d].map(|p| g.dot(&(p - c)));
        let q = sa * sa + sb * sb + sd * sd + sa * sb + sb * sd + sd * sa;
        sum += g.dot(&face) * q;
    }
    -rho * sum / (24.0 * g2)
}

/// The integral of the softplus eps ln(1 + exp(u / eps)) from 0 to `x`. Beyond 40 eps from
/// zero the softplus is max(u, 0) to rounding (`forces::tension`), so the tails are exact:
/// eps^2 (pi^2 / 12 + 800) + (x^2 - (40 eps)^2) / 2 above and -eps^2 pi^2 / 12 below
/// (-Li2(-1) = pi^2 / 12, and -Li2(-e^40) = 800 + pi^2 / 6 to rounding); in between,
/// 16-point Gauss-Legendre quadrature on panels at most 2 eps wide (the integrand is analytic
/// within pi eps of the real axis).
pub fn softplus_integral(x: f64, eps: f64) -> f64 {
    use std::f64::consts::PI;
    let cut = 40.0 * eps;
    let base = eps * eps * PI * PI / 12.0;
    if x >= cut {
        return eps * eps * 800.0 + base + 0.5 * (x * x - cut * cut);
    }
    if x <= -cut {
        return -base;
    }
    let panels = (x.abs() / (2.0 * eps)).ceil().max(1.0) as usize;
    let w = x / panels as f64;
    let mut sum = 0.0;
    for p in 0..panels {
        let (a, b) = (p as f64 * w, (p + 1) as f64 * w);
        let (mid, half) = (0.5 * (a + b), 0.5 * (b - a));
        for (node, weight) in GAUSS_LEGENDRE_16 {
            for u in [mid - half * node, mid + half * node] {
                sum += weight * half * super::forces::tension(u, eps);
            }
        }
    }
    sum
}

/// The positive nodes and their weights of 16-point Gauss-Legendre quadrature on [-1, 1]
/// (Abramowitz & Stegun 25.4.29).
const GAUSS_LEGENDRE_16: [(f64, f64); 8] = [
    (0.095_012_509_837_637_44, 0.189_450_610_455_068_5),
    (0.281_603_550_779_258_9, 0.182_603_415_044_923_6),
    (0.458_016_777_657_227_4, 0.169_156_519_395_002_5),
    (0.617_876_244_402_643_8, 0.149_595_988_816_576_7),
    (0.755_404_408_355_003, 0.124_628_971_255_533_9),
    (0.865_631_202_387_831_7, 0.095_158_511_682_492_8),
    (0.944_575_023_073_232_6, 0.062_253_523_938_647_9),
    (0.989_400_934_991_649_9, 0.027_152_459_411_754_1),
];

#[cfg(test)]
mod tests {
    use super::super::muscle::MuscleLaw;
    use super::super::{Activations, Data, Model, Params, forces, kinematics, rest_state};
    use super::{mechanical_energy, mechanical_energy_at, softplus_integral};
    use crate::anatomy::{Anatomy, MuscleGroup, Subject};

    /// What the activations add to the energy is the potential of what they add to the forces
    /// (`forces::accumulate`), under both laws: minus its derivative in a coordinate (central
    /// differences) is the generalised force the added anchor forces make along it,
    /// sum_a dF_a . dx_a/dq (the anchors' motion also by central differences), for every rib's
    /// angle and for every free vertex a muscle reaches, in a deformed state at rest
    /// (velocities zero).
    #[test]
    fn held_energy_is_the_potential_of_the_activations_forces() {
        let anatomy = Anatomy::build(&Subject::default(), 0).unwrap();
        for law in [MuscleLaw::Thesis, MuscleLaw::Hill] {
            let params = Params::for_posture_and_law(anatomy.subject.posture, law);
            let model = Model::compile(&anatomy, params);
            let l = model.layout;
            let mut y = rest_state(&model);
            for r in 0..super::RIBS {
                y[l.theta + r] = 0.02 * ((r as f64) * 0.7).sin();
                y[l.theta_dot + r] = 0.0;
            }
            for i in 0..3 * l.vertices {
                y[l.vertex_x + i] += 0.003 * ((i as f64) * 0.37).sin();
                y[l.vertex_v + i] = 0.0;
            }
            let act = Activations::new(&[0.3; MuscleGroup::COUNT], 1.0, 0.8);
            let mut data = Data::new(&model);
            kinematics::positions_and_velocities(&model, &mut data, &l, &y);
            forces::accumulate(&model, &mut data, &act);
            let with = data.force.clone();
            forces::accumulate(&model, &mut data, &Activations::default());
            let added_force: Vec<_> = with.iter().zip(&data.force).map(|(a, b)| a - b).collect();
            // the rib angles and the free vertices the muscles reach
            let el = &model.elements;
            let reached: std::collections::BTreeSet<u32> = (0..model.muscle_count)
                .flat_map(|e| el.path[el.start[e] as usize..el.start[e + 1] as usize].to_vec())
                .collect();
            let mut coordinates: Vec<usize> = (0..super::RIBS).map(|r| l.theta + r).collect();
            for j in (0..l.vertices).filter(|&j| reached.contains(&model.vertex_anchor[j])) {
                coordinates.extend((0..3).map(|k| l.vertex_x + 3 * j + k));
            }
            assert!(
                coordinates.len() > 60,
                "{law:?}: {} coordinates",
                coordinates.len()
            );
            let added = |y: &[f64], data: &mut Data| {
                mechanical_energy_at(&model, data, y, &act) - mechanical_energy(&model, data, y)
            };
            let (mut worst, mut largest) = (0.0f64, 0.0f64);
            for &i in &coordinates {
                let h = 1e-6;
                let (mut yp, mut ym) = (y.clone(), y.clone());
                yp[i] += h;
                ym[i] -= h;
                let de = (added(&yp, &mut data) - added(&ym, &mut data)) / (2.0 * h);
                kinematics::positions_and_velocities(&model, &mut data, &l, &yp);
                let plus = data.pos.clone();
                kinematics::positions_and_velocities(&model, &mut data, &l, &ym);
                let q: f64 = added_force
                    .iter()
                    .zip(plus.iter().zip(&data.pos))
                    .map(|(f, (p, m))| f.dot(&((p - m) / (2.0 * h))))
                    .sum();
                worst = worst.max((de + q).abs());
                largest = largest.max(q.abs());
            }
            assert!(
                largest > 1.0,
                "{law:?}: the activations add {largest} at most"
            );
            assert!(
                worst < 1e-4 * largest,
                "{law:?}: -dE/dq and the generalised force differ by {worst} (largest {largest})"
            );
        }
    }

    /// The integral's derivative is the softplus, across the cuts and the panel changes.
    #[test]
    fn softplus_integral_differentiates_to_the_softplus() {
        let eps = 0.1;
        for x in [-5.0, -4.0001, -1.3, -0.05, 0.0, 0.07, 0.9, 3.99, 4.01, 12.0] {
            let h = 1e-5;
            let d = (softplus_integral(x + h, eps) - softplus_integral(x - h, eps)) / (2.0 * h);
            let f = crate::dynamics::forces::tension(x, eps);
            assert!((d - f).abs() < 1e-7 * (1.0 + f), "{x}: {d} vs {f}");
        }
        assert_eq!(softplus_integral(0.0, eps), 0.0);
    }
}
