//! The reference loads carried by tension in the tissues, under
//! [`super::GravityLoads::Acting`]: the axial elements' rest lengths (a linear element's rest
//! length, a passive-and-active muscle's slack length) are shortened so that at the reference
//! (the generated standing anatomy under standard gravity) their own tensions hold as much of
//! the reference's generalised loads as they can; what they cannot hold stays a constant
//! preload ([`super::accelerations::Preload::at_rest`] of the changed structure).
//!
//! The tensions t_e >= 0 solve a bounded, regularised least-squares problem
//!
//! ```text
//! minimise |W (B t - p)|^2 + lambda sum_e (t_e / s_e)^2,  0 <= t_e <= cap_e
//! ```
//!
//! with p the generalised loads the preloads would supply at the reference, B_e the
//! generalised force of a unit tension in element e there (its unit vectors on its anchors,
//! reduced to rib torques, sternum force and torque and vertex forces as stage 3 reduces
//! them), W the rows' weights (a torque row over the body's radius of gyration, so that every
//! row is a force), s_e the element's force per unit strain (c l0 for a linear element,
//! F_max / e0 for a muscle under the passive-and-active law) and lambda
//! [`REGULARISATION`] times the mean of |W B_e|^2 s_e^2: among the tension patterns that carry
//! the loads equally well, the one of smallest strains. It is solved by projected coordinate
//! descent (each sweep minimises exactly over one t_e at a time; convex, so it converges).
//!
//! Which elements: every muscle and membrane element, tension only (muscles pull, Zajac 1989;
//! a membrane wrinkles rather than carry compression). A muscle's tension at the reference is
//! bounded by its largest isometric force F_max (the passive curve's cited range, Thelen 2003:
//! the relaxed tissue carries F_max at the strain e0 = [`super::muscle::PASSIVE_STRAIN`]); under
//! the thesis's linear law by the same strain, c l0 e0. The zero-length vector springs and the
//! rib joints are linear about the rest (the abdominal wall's foundation under
//! `Params::abdominal_wall_unloading` too, up to its unloading length): a rest offset in them
//! is a constant load, so they are left out and their share stays a preload.

use super::accelerations::Preload;
use super::muscle::{MuscleLaw, PASSIVE_SHAPE, PASSIVE_STRAIN};
use super::structure::{Carrier, RIBS, Structure, via_segment_length};
use nalgebra::Vector3;

/// The regulariser's weight relative to the mean squared column of the least-squares problem
/// (module doc): a numerical choice, not a physical constant and not fitted to any figure,
/// small so that carrying the loads comes first and the regulariser only picks among the
/// tension patterns that carry them about equally well. Measured at level 1 under the hill
/// law (docs/dynamics.md, "Gravity that acts"): 1e-6 moves the relaxed compliance by 2 %; 1e-2
/// carries too little and the standing rest buckles again.
pub const REGULARISATION: f64 = 1e-4;

/// Projected coordinate-descent sweeps over the elements.
const SWEEPS: usize = 400;

/// What [`carry`] did.
#[derive(Clone, Debug, Default)]
pub struct Carried {
    /// Tension added to each element at the reference [N].
    pub tension: Vec<f64>,
    /// |W p|: the weighted norm of the loads the preloads supplied [N].
    pub loads: f64,
    /// |W (p - B t)|: what is left to the preloads [N].
    pub residual: f64,
    /// Elements at their cap.
    pub capped: usize,
    /// Largest added strain t_e / s_e of a muscle and of a membrane element.
    pub largest_strain: [f64; 2],
    /// Largest tension of a muscle over its F_max (0 under the thesis's law, whose muscles
    /// carry no F_max), and largest tension over length of a membrane element [N/m].
    pub largest_load: [f64; 2],
}

/// The generalised-force rows: rib torques, then sternum force and torque, then the free
/// vertices' forces.
fn rows(structure: &Structure) -> usize {
    RIBS + 6 + 3 * structure.free_vertices()
}

/// The preload `p` as one vector of generalised loads.
fn flatten(p: &Preload) -> Vec<f64> {
    let mut v = p.rib.clone();
    v.extend(p.sternum_force.iter());
    v.extend(p.sternum_torque.iter());
    for f in &p.vertex {
        v.extend(f.iter());
    }
    v
}

/// Adds the generalised force of anchor force `f` on anchor `a` (at its rest position) to
/// the sparse column `col`.
fn reduce(structure: &Structure, a: usize, f: Vector3<f64>, col: &mut Vec<(usize, f64)>) {
    let x = structure.rest[a];
    match structure.carrier[a] {
        Carrier::Ground => {}
        Carrier::Rib(r) => {
            let r = r as usize;
            let m = (x - structure.rib_head[r]).cross(&f);
            col.push((r, m.dot(&structure.rib_axis[r])));
        }
        Carrier::Sternum => {
            let m = (x - structure.sternum_com).cross(&f);
            for k in 0..3 {
                col.push((RIBS + k, f[k]));
                col.push((RIBS + 3 + k, m[k]));
            }
        }
        Carrier::Vertex(j) => {
            for k in 0..3 {
                col.push((RIBS + 6 + 3 * j as usize + k, f[k]));
            }
        }
    }
}

/// The generalised force of a unit tension in element `e` at the reference, sparse.
fn column(structure: &Structure, e: usize) -> Vec<(usize, f64)> {
    let path = structure.elements.path_of(e);
    let mut col = Vec::new();
    let via = path.len() > 2;
    for w in path.windows(2) {
        let (a, b) = (w[0] as usize, w[1] as usize);
        let d = structure.rest[b] - structure.rest[a];
        let len = if via {
            via_segment_length(&d)
        } else {
            d.norm()
        };
        if len < 1e-12 {
            continue;
        }
        let n = d / len;
        reduce(structure, a, n, &mut col);
        reduce(structure, b, -n, &mut col);
    }
    col.sort_by_key(|c| c.0);
    let mut merged: Vec<(usize, f64)> = Vec::with_capacity(col.len());
    for (i, v) in col {
        match merged.last_mut() {
            Some(last) if last.0 == i => last.1 += v,
            _ => merged.push((i, v)),
        }
    }
    merged
}

/// Length of element `e` at the reference.
fn reference_length(structure: &Structure, e: usize) -> f64 {
    let path = structure.elements.path_of(e);
    if path.len() > 2 {
        path.windows(2)
            .map(|w| {
                via_segment_length(&(structure.rest[w[1] as usize] - structure.rest[w[0] as usize]))
            })
            .sum()
    } else {
        (structure.rest[path[1] as usize] - structure.rest[path[0] as usize]).norm()
    }
}

/// Whether element `e` follows the passive-and-active law.
fn is_hill(structure: &Structure, e: usize) -> bool {
    structure.params.muscle_law == MuscleLaw::Hill && structure.elements.max_force[e] > 0.0
}

/// Shortens the elements of `structure` so that their tensions at the reference carry the
/// loads `p` of the reference (the preloads [`Preload::at_rest`] finds there) as far as they
/// can (module doc), and says how far.
pub fn carry(structure: &mut Structure, p: &Preload) -> Carried {
    let n = rows(structure);
    let p = flatten(p);
    debug_assert_eq!(p.len(), n);
    // Row weights: a torque over the body's radius of gyration.
    let mut w = vec![1.0; n];
    for (wr, (i, m)) in w
        .iter_mut()
        .zip(structure.rib_inertia.iter().zip(&structure.rib_mass))
    {
        *wr = 1.0 / (i / m).sqrt();
    }
    let gyration = (structure.sternum_inertia.trace() / (3.0 * structure.sternum_mass)).sqrt();
    for wk in &mut w[RIBS + 3..RIBS + 6] {
        *wk = 1.0 / gyration;
    }
    let el = &structure.elements;
    let ne = el.len();
    let cols: Vec<Vec<(usize, f64)>> = (0..ne)
        .map(|e| {
            column(structure, e)
                .into_iter()
                .map(|(i, v)| (i, v * w[i]))
                .collect()
        })
        .collect();
    let lengths: Vec<f64> = (0..ne).map(|e| reference_length(structure, e)).collect();
    // force per unit strain and cap of each element
    let (scale, cap): (Vec<f64>, Vec<f64>) = (0..ne)
        .map(|e| {
            if is_hill(structure, e) {
                let f = el.max_force[e];
                (f / PASSIVE_STRAIN, f)
            } else {
                let s = el.stiffness[e] * lengths[e];
                let cap = if e < structure.muscle_count {
                    s * PASSIVE_STRAIN
                } else {
                    f64::INFINITY
                };
                (s, cap)
            }
        })
        .unzip();
    let norm2: Vec<f64> = cols
        .iter()
        .map(|c| c.iter().map(|(_, v)| v * v).sum())
        .collect();
    let mean = norm2
        .iter()
        .zip(&scale)
        .map(|(c, s)| c * s * s)
        .sum::<f64>()
        / ne as f64;
    let lambda = REGULARISATION * mean;
    // residual r = W (p - B t)
    let mut r: Vec<f64> = p.iter().zip(&w).map(|(p, w)| p * w).collect();
    let loads = r.iter().map(|x| x * x).sum::<f64>().sqrt();
    let mut t = vec![0.0; ne];
    for _ in 0..SWEEPS {
        for e in 0..ne {
            let reg = lambda / (scale[e] * scale[e]);
            let h = norm2[e] + reg;
            if h == 0.0 {
                continue;
            }
            let g: f64 = cols[e].iter().map(|(i, v)| v * r[*i]).sum::<f64>() - reg * t[e];
            let new = (t[e] + g / h).clamp(0.0, cap[e]);
            let dt = new - t[e];
            if dt != 0.0 {
                for (i, v) in &cols[e] {
                    r[*i] -= v * dt;
                }
                t[e] = new;
            }
        }
    }
    let residual = r.iter().map(|x| x * x).sum::<f64>().sqrt();
    let mut largest_strain = [0.0f64; 2];
    let mut capped = 0;
    let mut largest_load = [0.0f64; 2];
    let el = &mut structure.elements;
    for e in 0..ne {
        if t[e] >= cap[e] {
            capped += 1;
        }
        let k = usize::from(e >= structure.muscle_count);
        largest_strain[k] = largest_strain[k].max(t[e] / scale[e]);
        let load = if k == 1 {
            t[e] / lengths[e]
        } else if el.max_force[e] > 0.0 {
            t[e] / el.max_force[e]
        } else {
            0.0
        };
        largest_load[k] = largest_load[k].max(load);
        if t[e] == 0.0 {
            continue;
        }
        if structure.params.muscle_law == MuscleLaw::Hill && el.max_force[e] > 0.0 {
            // F_max f_PE(l / l_s - 1) = the tension it had plus t_e (Thelen's curve inverted)
            let f = el.max_force[e];
            let l = lengths[e];
            let before = f * super::muscle::passive(l / el.slack_length[e] - 1.0).0;
            let y = ((before.max(0.0) + t[e]) / f) * (PASSIVE_SHAPE.exp() - 1.0);
            let strain = PASSIVE_STRAIN / PASSIVE_SHAPE * y.ln_1p();
            el.slack_length[e] = l / (1.0 + strain);
        } else {
            el.rest_length[e] -= t[e] / el.stiffness[e];
        }
    }
    Carried {
        tension: t,
        loads,
        residual,
        capped,
        largest_strain,
        largest_load,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::anatomy::{Anatomy, Posture, Subject};
    use crate::dynamics::{GRAVITY, GravityLoads, Params};

    /// The tissues carry what the solve says they carry: the preload recomputed on the
    /// shortened structure at the reference is the residual p - B t (so each element's new
    /// rest or slack length gives it the tension it was assigned there), every tension is
    /// within its bounds, and the loads left to the preloads are fewer than before.
    #[test]
    fn the_shortened_tissues_carry_their_tensions() {
        let anatomy = Anatomy::build(&Subject::default(), 0).unwrap();
        for law in [MuscleLaw::Thesis, MuscleLaw::Hill] {
            let mut params = Params::for_posture(Posture::Standing);
            params.gravity_loads = GravityLoads::Acting;
            params.muscle_law = law;
            let mut structure = Structure::compile(&anatomy, params);
            let g = Params::gravity_direction(Posture::Standing);
            structure.gravity = Vector3::new(g[0], g[1], g[2]) * GRAVITY;
            let before = structure.clone();
            let p = Preload::at_rest(&structure);
            let carried = carry(&mut structure, &p);
            let after = flatten(&Preload::at_rest(&structure));
            // the predicted residual, unweighted: p - B t
            let mut predicted = flatten(&p);
            for (e, t) in carried.tension.iter().enumerate() {
                assert!(*t >= 0.0, "{law:?}: element {e} pushes ({t} N)");
                if before.params.muscle_law == MuscleLaw::Hill && before.elements.max_force[e] > 0.0
                {
                    assert!(*t <= before.elements.max_force[e], "{law:?}: element {e}");
                }
                for (i, v) in column(&before, e) {
                    predicted[i] -= v * t;
                }
            }
            let worst = after
                .iter()
                .zip(&predicted)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            // the softplus toe of a tension-only element that was slack at the reference
            // (tension_toe ln 2) is the only difference allowed
            assert!(
                worst < 10.0 * structure.params.tension_toe,
                "{law:?}: preload off the prediction by {worst}"
            );
            assert!(carried.residual < carried.loads, "{law:?}: {carried:?}");
        }
    }
}
