//! Stage 2: forces on anchors.
//!
//! - Muscle and membrane elements (thesis eq. 2.2): f = c e + gamma e', e = |r| - l(t), with
//!   l(t) = l0 r(t) (eq. 2.3) and r = 1 - beta_max a g for muscles (a the side's activation of
//!   the group, g the element's regional gain). Muscles only pull (Zajac 1989, thesis 2.1):
//!   f is clamped at zero.
//! - Zero-length vector springs (cartilage ball joints, wall foundation): F = k d + c d'.
//! - Abdominal pressure (eq. 2.5): P = K (V0/V - 1); each triangle pushes each of its corners
//!   with P A n / 3 (eq. 2.6), which on a closed surface is exactly P dV/dx.
//! - Pleural pressure: P_pl = -E_L (V_th - V_th0) on the thoracic surface (lung recoil).

use super::model::{Model, PASSIVE, volume};
use super::{Activations, Data};
use nalgebra::Vector3;

/// Computes `data.force` for every anchor.
pub fn accumulate(model: &Model, data: &mut Data, act: &Activations) {
    local_forces(model, data, act);
    abdominal_pressure(model, data);
    pleural_pressure(model, data);
}

/// As [`accumulate`], but with the abdominal and pleural pressures held at the given values
/// `[abdominal, pleural]` [Pa] instead of computed from the volumes: the local part of the
/// forces, whose Jacobian is sparse (used by `dynamics::jacobian`). `data`'s volumes and
/// pressures are left as they were.
pub fn accumulate_frozen(model: &Model, data: &mut Data, act: &Activations, pressures: [f64; 2]) {
    local_forces(model, data, act);
    apply_pressure(&model.abdomen_triangles, pressures[0], data);
    apply_pressure(&model.thorax_triangles, pressures[1], data);
}

/// Element and vector-spring forces (everything but the pressures).
fn local_forces(model: &Model, data: &mut Data, act: &Activations) {
    for f in data.force.iter_mut() {
        *f = Vector3::zeros();
    }
    elements(model, data, act);
    vector_springs(model, data);
}

/// Muscle and membrane elements. An element along a path p_0 .. p_m has length
/// L = sum |p_{k+1} - p_k| and rate L' = sum (v_{k+1} - v_k) . n_k; its tension f acts on each
/// via point along the bisector n_k - n_{k-1}, on the origin along n_0 and on the insertion
/// along -n_{m-1}.
fn elements(model: &Model, data: &mut Data, act: &Activations) {
    let el = &model.elements;
    for e in 0..el.len() {
        let path = el.path_of(e);
        let group = el.group[e];
        let (rest, muscle) = if group == PASSIVE {
            (el.rest_length[e], false)
        } else {
            let a_g = act.level[group as usize][el.side[e] as usize];
            (el.rest_length[e] * (1.0 - a_g * el.gain[e]), true)
        };
        if path.len() == 2 {
            let (a, b) = (path[0] as usize, path[1] as usize);
            let d = data.pos[b] - data.pos[a];
            let len = d.norm();
            if len < 1e-12 {
                continue;
            }
            let n = d / len;
            let rate = (data.vel[b] - data.vel[a]).dot(&n);
            let mut f = el.stiffness[e] * (len - rest) + el.damping[e] * rate;
            if muscle && f < 0.0 {
                f = 0.0;
            }
            let fv = n * f;
            data.force[a] += fv;
            data.force[b] -= fv;
            continue;
        }
        let (mut len, mut rate) = (0.0, 0.0);
        for w in path.windows(2) {
            let (a, b) = (w[0] as usize, w[1] as usize);
            let d = data.pos[b] - data.pos[a];
            let l = d.norm();
            len += l;
            if l > 1e-12 {
                rate += (data.vel[b] - data.vel[a]).dot(&d) / l;
            }
        }
        let mut f = el.stiffness[e] * (len - rest) + el.damping[e] * rate;
        if muscle && f < 0.0 {
            f = 0.0;
        }
        if f == 0.0 {
            continue;
        }
        for w in path.windows(2) {
            let (a, b) = (w[0] as usize, w[1] as usize);
            let d = data.pos[b] - data.pos[a];
            let l = d.norm();
            if l > 1e-12 {
                let fv = d * (f / l);
                data.force[a] += fv;
                data.force[b] -= fv;
            }
        }
    }
}

/// Cartilage joints and wall foundation.
fn vector_springs(model: &Model, data: &mut Data) {
    let s = &model.springs;
    for i in 0..s.a.len() {
        let (a, b) = (s.a[i] as usize, s.b[i] as usize);
        let mut f = (data.pos[b] - data.pos[a]) * s.stiffness[i]
            + (data.vel[b] - data.vel[a]) * s.damping[i];
        if s.horizontal[i] {
            f.y = 0.0;
        }
        data.force[a] += f;
        data.force[b] -= f;
    }
}

/// Pushes `pressure` on a closed surface: each corner receives P/6 (b - a) x (c - a).
fn apply_pressure(tris: &[[u32; 3]], pressure: f64, data: &mut Data) {
    if pressure == 0.0 {
        return;
    }
    for t in tris {
        let (a, b, c) = (t[0] as usize, t[1] as usize, t[2] as usize);
        let f = (data.pos[b] - data.pos[a]).cross(&(data.pos[c] - data.pos[a])) * (pressure / 6.0);
        data.force[a] += f;
        data.force[b] += f;
        data.force[c] += f;
    }
}

/// Abdominal pressure from the current cavity volume (eq. 2.5-2.6).
fn abdominal_pressure(model: &Model, data: &mut Data) {
    let v = volume(&data.pos, &model.abdomen_triangles);
    let p = model.params.bulk_modulus * (model.abdomen_rest_volume / v - 1.0);
    data.abdomen_volume = v;
    data.abdomen_pressure = p;
    apply_pressure(&model.abdomen_triangles, p, data);
}

/// Pleural pressure from the thoracic volume: the lungs' elastic recoil.
fn pleural_pressure(model: &Model, data: &mut Data) {
    let v = volume(&data.pos, &model.thorax_triangles);
    let p = -model.params.lung_elastance * (v - model.thorax_rest_volume);
    data.thorax_volume = v;
    data.pleural_pressure = p;
    apply_pressure(&model.thorax_triangles, p, data);
}
