//! The Jacobian of the right-hand side for the stiff method and for the equilibrium's
//! Newton iterations, as a sparse part plus a low-rank part.
//!
//! [`TorsoJacobian::new`] gives the Jacobian of the block-local right-hand side (the mass
//! matrix's blocks of each body alone, [`super::accelerations::compute_local`]), sparse plus
//! rank 2: J_b = S + u_A (dP_A/dV_A) (dV_A/dy)^T + u_T (dP_T/dV_T) (dV_T/dy)^T.
//!
//! - S is the Jacobian with the abdominal and pleural pressures frozen
//!   ([`super::forces::accumulate_frozen`]): every force is then local (elements, springs,
//!   the pressure acting on each triangle), so S is sparse. Its pattern is built per body
//!   ("carrier": a rib, the sternum or a free vertex): the accelerations of a body depend on
//!   the positions and velocities of the bodies it shares an element, a spring or a pressure
//!   triangle with. S is estimated by forward differences, one evaluation per colour of a
//!   distance-2 column colouring (Curtis, Powell & Reid 1974).
//! - The two global pressures (thesis eq. 2.5: P_A = K (V0/V - 1) - mu dV/dt; lung recoil
//!   and airway flow P_T = P_ao - P_L(V_T) - R dV_T/dt, or with the airway occluded Boyle's
//!   law's P_alv(V_T) - P_L(V_T), `super::airway`) couple every wall point to every other.
//!   Their part is exact in rank: u = ∂f/∂P, the response of the accelerations to a unit
//!   pressure (f is linear in each pressure, so one evaluation with P + 1 gives it exactly),
//!   times dP/dV (-K V0 / V^2 and -E_L, less n / V^2 occluded), times the volume gradient dV/dy, plus the viscous
//!   terms' -eta dV/dy on the matching velocities: for a free vertex the area-weighted
//!   normal Σ (b x c)/6 over its triangles (divergence theorem), for the ribs and the
//!   sternum (whose anchors carry wall points) central differences of the volume.
//!
//! [`TorsoJacobian::full`] gives the Jacobian of the full right-hand side ([`super::rhs`],
//! the whole mass matrix M, whose rigid bodies are coupled and whose cavities add rank-two
//! volume inertances), which the stiff method (ROS34PW2, a W-method) uses. Forces f and
//! accelerations relate by a = M^-1 f = L M_b^-1 f with L = M^-1 M_b, M_b the block
//! diagonal; L does not depend on the state, so the full Jacobian is L J_b. L is the
//! identity plus 32 rank-one terms a_k b_k^T ([`super::inertia::MassMatrix::local_to_full`]:
//! 30 for the rigid bodies' coupled block, 2 for the volume inertances), and
//! L J_b = J_b + Σ a_k (J_b^T b_k)^T keeps S as the sparse part and grows the rank from 2
//! to 34. Differencing the full right-hand side instead would make every row dense. The
//! equilibrium's Newton iterations keep the block-local Jacobian: their residual is the
//! block-local accelerations, which vanish where the true ones do, and J_b is exactly its
//! Jacobian.

use super::forces;
use super::model::Model;
use super::state::Layout;
use super::structure::{Carrier, RIBS, volume};
use super::{Activations, Data, kinematics};
use crate::solver::{Colouring, Jacobian, JacobianStructure, Pattern};
use nalgebra::{Point3, Vector3};

/// The pattern, colouring and scratch memory of the torso's Jacobian, built once per model.
#[derive(Clone, Debug)]
pub struct TorsoJacobian {
    structure: JacobianStructure,
    colouring: Colouring,
    floor: Vec<f64>,
    ypert: Vec<f64>,
    f1: Vec<f64>,
    f2: Vec<f64>,
    /// The frozen right-hand side at the evaluation point (the differences' base).
    f0: Vec<f64>,
    grad: Vec<Vector3<f64>>,
    /// The pairs (a_k, b_k) of L = M^-1 M_b = I + Σ a_k b_k^T
    /// ([`super::inertia::MassMatrix::local_to_full`]) in the state's acceleration rows,
    /// when the Jacobian is that of the full right-hand side ([`TorsoJacobian::full`]);
    /// empty for the local one ([`TorsoJacobian::new`]).
    full_mass: Vec<(Vec<f64>, Vec<f64>)>,
}

/// For each body (block index of [`body_of`]), the bodies it interacts with, itself
/// included, sorted: those it shares an element, a vector spring or a pressure triangle with.
/// The block pattern of the Jacobians of the inertial right-hand side and of the static
/// residual (`dynamics::statics`).
pub(super) fn body_adjacency(model: &Model) -> Vec<Vec<u32>> {
    let bodies = RIBS + 1 + model.free_vertices();
    let mut adj: Vec<Vec<u32>> = (0..bodies).map(|b| vec![b as u32]).collect();
    let mut link = |anchors: &mut dyn Iterator<Item = u32>| {
        let mut set: Vec<usize> = anchors
            .filter_map(|a| body_of(model.carrier[a as usize]))
            .collect();
        set.sort_unstable();
        set.dedup();
        for &a in &set {
            adj[a].extend(set.iter().map(|&b| b as u32));
        }
    };
    let el = &model.elements;
    for e in 0..el.len() {
        link(&mut el.path_of(e).iter().copied());
    }
    for i in 0..model.springs.a.len() {
        link(&mut [model.springs.a[i], model.springs.b[i]].into_iter());
    }
    for t in model
        .abdomen_triangles
        .iter()
        .chain(&model.thorax_triangles)
    {
        link(&mut t.iter().copied());
    }
    for nb in &mut adj {
        nb.sort_unstable();
        nb.dedup();
    }
    adj
}

/// Block index of a body: ribs 0..24, the sternum 24, free vertex j 25 + j.
fn body_of(c: Carrier) -> Option<usize> {
    match c {
        Carrier::Ground => None,
        Carrier::Rib(r) => Some(r as usize),
        Carrier::Sternum => Some(RIBS),
        Carrier::Vertex(j) => Some(RIBS + 1 + j as usize),
    }
}

/// State entries of body `b` (positions and velocities).
fn body_columns(l: &Layout, b: usize) -> Vec<u32> {
    let c = |r: std::ops::Range<usize>| r.map(|i| i as u32).collect::<Vec<_>>();
    if b < RIBS {
        vec![(l.theta + b) as u32, (l.theta_dot + b) as u32]
    } else if b == RIBS {
        let mut v = c(l.sternum_x..l.sternum_x + 7);
        v.extend(c(l.sternum_v..l.sternum_v + 6));
        v
    } else {
        let j = b - RIBS - 1;
        let mut v = c(l.vertex_x + 3 * j..l.vertex_x + 3 * j + 3);
        v.extend(c(l.vertex_v + 3 * j..l.vertex_v + 3 * j + 3));
        v
    }
}

impl TorsoJacobian {
    /// Pattern (per body pair that interacts), block grouping (one block per body) and
    /// colouring for `model`.
    pub fn new(model: &Model) -> TorsoJacobian {
        let l = model.layout;
        let adj = body_adjacency(model);
        let mut rows: Vec<Vec<u32>> = vec![Vec::new(); l.len];
        let mut groups = vec![0u32; l.len];
        for (b, nb) in adj.iter().enumerate() {
            let mut cols = Vec::new();
            for &o in nb.iter() {
                cols.extend(body_columns(&l, o as usize));
            }
            for &i in &body_columns(&l, b) {
                groups[i as usize] = b as u32;
            }
            // acceleration rows
            let acc: Vec<usize> = if b < RIBS {
                vec![l.theta_dot + b]
            } else if b == RIBS {
                (l.sternum_v..l.sternum_v + 6).collect()
            } else {
                let j = b - RIBS - 1;
                (l.vertex_v + 3 * j..l.vertex_v + 3 * j + 3).collect()
            };
            for i in acc {
                rows[i] = cols.clone();
            }
        }
        // kinematic rows: position rates are the velocities; q' = (0, w) q / 2
        for r in 0..RIBS {
            rows[l.theta + r] = vec![(l.theta_dot + r) as u32];
        }
        for k in 0..3 {
            rows[l.sternum_x + k] = vec![(l.sternum_v + k) as u32];
        }
        for k in 0..4 {
            rows[l.sternum_q + k] = (l.sternum_q..l.sternum_q + 4)
                .chain(l.sternum_w..l.sternum_w + 3)
                .map(|i| i as u32)
                .collect();
        }
        for i in 0..3 * l.vertices {
            rows[l.vertex_x + i] = vec![(l.vertex_v + i) as u32];
        }
        let pattern = Pattern::from_rows(rows);
        let colouring = Colouring::new(&pattern);
        let n = l.len;
        TorsoJacobian {
            structure: JacobianStructure {
                pattern,
                groups,
                rank: 2,
            },
            colouring,
            floor: vec![1e-2; n],
            ypert: vec![0.0; n],
            f1: vec![0.0; n],
            f2: vec![0.0; n],
            f0: vec![0.0; n],
            grad: vec![Vector3::zeros(); model.rest.len()],
            full_mass: Vec::new(),
        }
    }

    /// The Jacobian of the full right-hand side ([`super::rhs`], the scaled mass matrix
    /// whole), for the stiff integrator: the local one's image under L = M^-1 M_b, whose
    /// sparse part is the local one's and whose low rank grows from 2 to 34 (module doc).
    pub fn full(model: &Model) -> TorsoJacobian {
        let mut j = TorsoJacobian::new(model);
        let l = model.layout;
        let n = l.len;
        let embed = |g: &[f64]| {
            let mut v = vec![0.0; n];
            v[l.theta_dot..].copy_from_slice(g);
            v
        };
        j.full_mass = model
            .mass
            .local_to_full()
            .iter()
            .map(|(a, b)| (embed(a), embed(b)))
            .collect();
        j.structure.rank = 2 + j.full_mass.len();
        j
    }

    /// Pattern, grouping and rank, for the solver.
    pub fn structure(&self) -> JacobianStructure {
        self.structure.clone()
    }

    /// Number of colours (right-hand-side evaluations per sparse part).
    pub fn colours(&self) -> usize {
        self.colouring.colours
    }

    /// Fills `jac` at `y` (f0 = f(y) with activations `act`). Returns the number of
    /// right-hand-side evaluations made.
    pub fn evaluate(
        &mut self,
        model: &Model,
        data: &mut Data,
        act: &Activations,
        y: &[f64],
        f0: &[f64],
        jac: &mut Jacobian,
    ) -> u64 {
        let l = model.layout;
        let n = l.len;
        // the pressures at y (and the volumes they come from)
        kinematics::positions_and_velocities(model, data, &l, y);
        let va = volume(&data.pos, &model.abdomen_triangles);
        let vt = volume(&data.pos, &model.thorax_triangles);
        let p = &model.params;
        let rates = [
            volume_rate(model, data, &model.abdomen_triangles),
            volume_rate(model, data, &model.thorax_triangles),
        ];
        // the airway's alveolar pressure: -R dV/dt open, Boyle's law's slope occluded
        let alveolar = model.alveolar(act, vt, rates[1]);
        let viscous = [model.abdomen_viscosity, -alveolar.per_rate];
        let pa = p.bulk_modulus * (model.abdomen_rest_volume / va - 1.0) - viscous[0] * rates[0];
        let pt = alveolar.pressure - model.pleural.recoil(vt);
        let frozen = [pa, pt];
        // the base of the differences: the frozen right-hand side itself (the block-diagonal
        // mass solve of `rhs_frozen` differs from the full one's by the volume inertances)
        let _ = f0;
        rhs_frozen(model, data, act, y, &mut self.f0, frozen);
        let f0 = &self.f0;
        let mut f = |yy: &[f64], out: &mut [f64]| rhs_frozen(model, data, act, yy, out, frozen);
        let mut evals = 1 + self.colouring.differences(
            &mut f,
            y,
            f0,
            &self.floor,
            &mut self.ypert,
            &mut self.f1,
            &mut jac.values,
        );
        // u = ∂f/∂P (exact: f is affine in each pressure); V = (dP/dV) dV/dy
        let slopes = [
            -p.bulk_modulus * model.abdomen_rest_volume / (va * va),
            alveolar.per_volume - model.pleural.slope(vt),
        ];
        for k in 0..2 {
            let mut bumped = frozen;
            bumped[k] += 1.0;
            rhs_frozen(model, data, act, y, &mut self.f2, bumped);
            evals += 1;
            // self.f0 is the right-hand side with exactly these pressures
            for ((u, &a), &b) in jac.u[k * n..(k + 1) * n]
                .iter_mut()
                .zip(&self.f2)
                .zip(&self.f0)
            {
                *u = a - b;
            }
            let tris = if k == 0 {
                &model.abdomen_triangles
            } else {
                &model.thorax_triangles
            };
            let vk = &mut jac.v[k * n..(k + 1) * n];
            volume_gradient(
                model,
                data,
                &l,
                y,
                tris,
                &mut self.grad,
                &mut self.ypert,
                vk,
            );
            // the viscous pressure -eta dV/dt: dV/dt = (dV/dq) q', so its velocity columns
            // take the position columns' gradient (the sternum's angular velocity its own)
            let grad_q: Vec<f64> = vk.to_vec();
            vk.iter_mut().for_each(|v| *v *= slopes[k]);
            let eta = viscous[k];
            for r in 0..RIBS {
                vk[l.theta_dot + r] = -eta * grad_q[l.theta + r];
            }
            for c in 0..3 {
                vk[l.sternum_v + c] = -eta * grad_q[l.sternum_x + c];
            }
            for i in 0..3 * l.vertices {
                vk[l.vertex_v + i] = -eta * grad_q[l.vertex_x + i];
            }
            // and dV/dt changes with the positions too: -eta d(dV/dt)/dq on the positions
            let mut rate_grad = std::mem::take(&mut self.f2);
            volume_rate_gradient(
                model,
                data,
                &l,
                y,
                tris,
                &mut self.grad,
                &mut self.ypert,
                &mut rate_grad,
            );
            for (v, g) in vk.iter_mut().zip(&rate_grad) {
                *v -= eta * g;
            }
            self.f2 = rate_grad;
            self.ypert.copy_from_slice(y);
            for c in 0..3 {
                let i = l.sternum_w + c;
                let d = 1e-6;
                self.ypert[i] = y[i] + d;
                kinematics::positions_and_velocities(model, data, &l, &self.ypert);
                let up = volume_rate(model, data, tris);
                self.ypert[i] = y[i] - d;
                kinematics::positions_and_velocities(model, data, &l, &self.ypert);
                let down = volume_rate(model, data, tris);
                self.ypert[i] = y[i];
                vk[i] = -eta * (up - down) / (2.0 * d);
            }
        }
        // the full right-hand side's Jacobian: L J_local = J_local + Σ a_k (J_local^T b_k)^T
        for (k, (a, b)) in self.full_mass.iter().enumerate() {
            let r = 2 + k;
            jac.u[r * n..(r + 1) * n].copy_from_slice(a);
            let (head, tail) = jac.v.split_at_mut(r * n);
            let vr = &mut tail[..n];
            vr.fill(0.0);
            for (i, &bi) in b.iter().enumerate() {
                if bi == 0.0 {
                    continue;
                }
                for (&c, &s) in jac
                    .pattern
                    .row(i)
                    .iter()
                    .zip(&jac.values[jac.pattern.row_range(i)])
                {
                    vr[c as usize] += s * bi;
                }
            }
            for p in 0..2 {
                let ub: f64 = jac.u[p * n..(p + 1) * n]
                    .iter()
                    .zip(b)
                    .map(|(x, y)| x * y)
                    .sum();
                if ub != 0.0 {
                    for (v, &w) in vr.iter_mut().zip(&head[p * n..(p + 1) * n]) {
                        *v += ub * w;
                    }
                }
            }
        }
        evals
    }
}

/// d(dV/dt)/dy over the positions of `y` (zero on the velocities) into `out`: analytic for
/// free vertices (for a triangle (a, b, c) with w = v_a + v_b + v_c, the derivatives of
/// w . ((b - a) x (c - a)) are w x (c - b), (c - a) x w and w x (b - a)), central
/// differences for the rib angles and the sternum pose. `grad` and `ytmp` are scratch.
#[allow(clippy::too_many_arguments)]
fn volume_rate_gradient(
    model: &Model,
    data: &mut Data,
    l: &Layout,
    y: &[f64],
    tris: &[[u32; 3]],
    grad: &mut [Vector3<f64>],
    ytmp: &mut [f64],
    out: &mut [f64],
) {
    out.fill(0.0);
    kinematics::positions_and_velocities(model, data, l, y);
    grad.iter_mut().for_each(|g| *g = Vector3::zeros());
    let (pos, vel) = (&data.pos, &data.vel);
    for t in tris {
        let [a, b, c] = t.map(|i| i as usize);
        let w = vel[a] + vel[b] + vel[c];
        grad[a] += w.cross(&(pos[c] - pos[b])) / 6.0;
        grad[b] += (pos[c] - pos[a]).cross(&w) / 6.0;
        grad[c] += w.cross(&(pos[b] - pos[a])) / 6.0;
    }
    for (j, &a) in model.vertex_anchor.iter().enumerate() {
        let g = grad[a as usize];
        out[l.vertex_x + 3 * j..l.vertex_x + 3 * j + 3].copy_from_slice(g.as_slice());
    }
    ytmp.copy_from_slice(y);
    for i in (l.theta..l.theta + RIBS).chain(l.sternum_x..l.sternum_x + 7) {
        let d = 1e-6 * y[i].abs().max(1.0);
        ytmp[i] = y[i] + d;
        kinematics::positions_and_velocities(model, data, l, ytmp);
        let up = volume_rate(model, data, tris);
        ytmp[i] = y[i] - d;
        kinematics::positions_and_velocities(model, data, l, ytmp);
        let down = volume_rate(model, data, tris);
        ytmp[i] = y[i];
        out[i] = (up - down) / (2.0 * d);
    }
}

/// dV/dt of the volume enclosed by `tris` at the positions and velocities in `data`.
fn volume_rate(model: &Model, data: &Data, tris: &[[u32; 3]]) -> f64 {
    let (pos, vel) = (&data.pos, &data.vel);
    let mut rate = 0.0;
    for t in tris {
        let [a, b, c] = t.map(|i| i as usize);
        let face = (pos[b] - pos[a]).cross(&(pos[c] - pos[a]));
        rate += face.dot(&(vel[a] + vel[b] + vel[c]));
    }
    let _ = model;
    rate / 6.0
}

/// The right-hand side with the two pressures held at `pressures` = [abdominal, pleural].
pub fn rhs_frozen(
    model: &Model,
    data: &mut Data,
    act: &Activations,
    y: &[f64],
    dy: &mut [f64],
    pressures: [f64; 2],
) {
    let layout = &model.layout;
    kinematics::positions_and_velocities(model, data, layout, y);
    forces::accumulate_frozen(model, data, act, pressures);
    super::accelerations::compute_local(model, &model.preload, &model.mass, data, layout, y, dy);
}

/// dV/dy of the volume enclosed by `tris` at state `y` into `out`: analytic for free
/// vertices, central differences for the rib angles and the sternum pose; zero for
/// velocities. `grad` and `ytmp` are scratch.
#[allow(clippy::too_many_arguments)]
fn volume_gradient(
    model: &Model,
    data: &mut Data,
    l: &Layout,
    y: &[f64],
    tris: &[[u32; 3]],
    grad: &mut [Vector3<f64>],
    ytmp: &mut [f64],
    out: &mut [f64],
) {
    out.fill(0.0);
    kinematics::positions_and_velocities(model, data, l, y);
    grad.iter_mut().for_each(|g| *g = Vector3::zeros());
    for t in tris {
        let [a, b, c] = t.map(|i| i as usize);
        let (pa, pb, pc): (Point3<f64>, Point3<f64>, Point3<f64>) =
            (data.pos[a], data.pos[b], data.pos[c]);
        grad[a] += pb.coords.cross(&pc.coords) / 6.0;
        grad[b] += pc.coords.cross(&pa.coords) / 6.0;
        grad[c] += pa.coords.cross(&pb.coords) / 6.0;
    }
    for (j, &a) in model.vertex_anchor.iter().enumerate() {
        let g = grad[a as usize];
        out[l.vertex_x + 3 * j..l.vertex_x + 3 * j + 3].copy_from_slice(g.as_slice());
    }
    // bodies: central differences of the volume over their pose coordinates
    ytmp.copy_from_slice(y);
    let body_cols = (l.theta..l.theta + RIBS).chain(l.sternum_x..l.sternum_x + 7);
    for i in body_cols {
        let d = 1e-6 * y[i].abs().max(1.0);
        ytmp[i] = y[i] + d;
        kinematics::positions_and_velocities(model, data, l, ytmp);
        let vp = volume(&data.pos, tris);
        ytmp[i] = y[i] - d;
        kinematics::positions_and_velocities(model, data, l, ytmp);
        let vm = volume(&data.pos, tris);
        ytmp[i] = y[i];
        out[i] = (vp - vm) / (2.0 * d);
    }
}
