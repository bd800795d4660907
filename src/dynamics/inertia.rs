//! Selective mass scaling: the mass matrix the dynamics integrates with.
//!
//! Breathing is quasi-static. The respiratory system's inertance (0.01-0.02 cmH2O s^2/L, Mead
//! 1956) makes its inertial pressure about 0.3 % of the elastic recoil at 0.25 Hz, and the
//! whole system is overdamped (resistance 2-3 cmH2O s/L against an elastance of about
//! 10 cmH2O/L). The true masses of a floating rib, the sternum or an 18 g dome vertex held by
//! thousands of N/m of fibres only add vibration modes at 80-130 Hz, which no breath excites
//! but which bound the step of an explicit integrator. This module adds inertia to the stiff
//! deformation modes alone, as selective mass scaling does in explicit finite-element codes
//! (Olovsson, Simonsson & Unosson 2005, Int J Numer Meth Eng 63:1436): the added mass matrix
//! is the local stiffness over the square of half the inertia frequency, omega_b = omega_i / 2
//! = pi f_i ([`super::Params::inertia_frequency`], 25 Hz: ten times the fastest drive the
//! model supports),
//!
//! M = M_true + blocks(K_local) / omega_b^2 + I_A g_A g_A^T + I_T g_T g_T^T.
//!
//! Each block alone then vibrates at omega_b at most; blocks moving against their neighbours
//! (a vertex against the next, a rib against the sternum) stretch the elements between them
//! from both ends and reach about twice that, omega_i. The damping of every element, spring
//! and joint is stiffness-proportional (`Structure::compile`: c = 2 zeta k / omega_i), so these
//! fastest modes are damped with the ratio zeta (1 by default: critically).
//!
//! - K_local is the stiffness of the elements, vector springs and rib joints at rest
//!   (sum of k G G^T over each element's length gradient G in the generalised coordinates:
//!   rib angles, the sternum's translation and small rotation, vertex positions). Its block
//!   over the rigid bodies (24 ribs and the sternum, 30 coordinates, kept whole so that the
//!   stiff costal cartilages add inertia to the ribs' motion relative to the sternum and none
//!   to the rib cage's breathing motion as a whole) and its 3 x 3 block of each vertex are
//!   kept. A mode that stretches stiff elements then has as much added mass as stiffness
//!   over omega_b^2, and a frequency between omega_b and omega_i; a mode that does not (the rib cage turning as a
//!   whole, the wall moving on its soft foundation) keeps its true inertia and its own, lower,
//!   frequency.
//! - Elements tilt. A two-point element's block gives inertia along its rest direction only;
//!   when the cavities deform and the element turns by theta, sin^2 theta of its stiffness and
//!   damping act across that direction, where only the true mass is. At the dome's
//!   central-tendon pole (stiff tendon edges between light vertices) that alone bounded the
//!   step at level of detail 1 (real roots near -1,000 /s). Each two-point element therefore
//!   also adds `transverse_fraction` (alpha, [`super::Params::transverse_fraction`], 0.1 =
//!   sin^2 18 degrees) of its k / omega_b^2 across its rest direction, and damps its ends'
//!   relative velocity across it with alpha of its axial damping coefficient
//!   (`dynamics::forces`), so that the transverse directions are a tilted element's, damped
//!   with the same ratio zeta. The damper acts on relative velocities only: it resists the
//!   cavities' shearing, not their motion.
//! - A vector spring's damping beyond the stiffness-proportional part (the abdominal wall's
//!   tissue resistance) adds c / omega_i to its vertex's mass in every direction, so that the
//!   damper alone relaxes the vertex no faster than omega_i.
//! - The cavities' volumes: g_A and g_T are the gradients of the abdomen's and the thorax's
//!   volumes at rest. I_T is the inertance of the gas in the airways, 0.015 cmH2O s^2/L (Mead
//!   1956, the mid-point of the 0.01-0.02 of the reference); it is raised, if needed, so that
//!   neither the lungs' elastance nor the airway resistance puts the thoracic volume mode
//!   above omega_i (E_L / I_T <= omega_b^2, R / I_T <= omega_i). The abdomen, incompressible
//!   (its bulk modulus K), gets I_A = (K / V_A) / omega_b^2.
//!
//! M is constant (built at rest). The accelerations solve M a = f with the block inverses and
//! Woodbury's identity for the rank-two part: a = b - Z S U^T b, b = B^-1 f, Z = B^-1 U,
//! S = (W^-1 + U^T Z)^-1, U = [g_A g_T], W = diag(I_A, I_T). The kinetic energy is
//! q'^T M q' / 2. Gravity keeps acting on the true masses.

use super::structure::{Carrier, RIBS, Structure, via_segment_length};
use nalgebra::{DMatrix, Matrix2, Matrix3, Vector2, Vector3};

/// Number of generalised coordinates of the rigid bodies: the ribs' angles, then the
/// sternum's translation and rotation (world axes).
pub const RIGID: usize = RIBS + 6;

/// 1 cmH2O in Pa.
const CMH2O: f64 = 98.0665;

/// Inertance of the gas in the airways [Pa s^2/m^3]: 0.015 cmH2O s^2/L (Mead 1956, J Appl
/// Physiol 9:208; 0.01-0.02 cmH2O s^2/L in healthy adults).
pub const AIRWAY_INERTANCE: f64 = 0.015 * CMH2O * 1e3;

/// The mass matrix of one model (module doc) and how it was built.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MassMatrix {
    /// Inverse of the rigid bodies' 30 x 30 block, row-major.
    rigid_inverse: Vec<f64>,
    /// Inverse of each rib's diagonal entry and of the sternum's 6 x 6 diagonal block of the
    /// rigid block (row-major), for [`MassMatrix::solve_local`].
    rib_local: Vec<f64>,
    sternum_local: Vec<f64>,
    /// Inverse of each free vertex's 3 x 3 block.
    vertex_inverse: Vec<Matrix3<f64>>,
    /// The rigid block itself, row-major (for the kinetic energy).
    rigid: Vec<f64>,
    /// Each free vertex's block (for the kinetic energy).
    vertex: Vec<Matrix3<f64>>,
    /// U = [g_A g_T], column-major (2 columns of the generalised dimension).
    u: Vec<f64>,
    /// Z = B^-1 U, column-major.
    z: Vec<f64>,
    /// S = (W^-1 + U^T Z)^-1.
    s: Matrix2<f64>,
    /// W = diag(I_A, I_T) [Pa s^2/m^3].
    pub inertance: [f64; 2],
    /// Ratio of the trace of each rigid body's scaled block to its true one (ribs, then the
    /// sternum's translation and rotation).
    pub rigid_ratio: Vec<f64>,
    /// Ratio of the trace of each free vertex's scaled block to its true one.
    pub vertex_ratio: Vec<f64>,
}

/// Generalised-coordinate gradients of an anchor's position: (coordinate, dp/dq).
fn anchor_jacobian(model: &Structure, a: u32, out: &mut Vec<(usize, Vector3<f64>)>) {
    let p = model.rest[a as usize];
    match model.carrier[a as usize] {
        Carrier::Ground => {}
        Carrier::Rib(r) => {
            let r = r as usize;
            out.push((r, model.rib_axis[r].cross(&(p - model.rib_head[r]))));
        }
        Carrier::Sternum => {
            let arm = p - model.sternum_com;
            for k in 0..3 {
                let mut e = Vector3::zeros();
                e[k] = 1.0;
                out.push((RIBS + k, e));
                out.push((RIBS + 3 + k, e.cross(&arm)));
            }
        }
        Carrier::Vertex(j) => {
            for k in 0..3 {
                let mut e = Vector3::zeros();
                e[k] = 1.0;
                out.push((RIGID + 3 * j as usize + k, e));
            }
        }
    }
}

/// Gradient of a scalar over the generalised coordinates, collected point by point.
#[derive(Default)]
struct Gradient {
    entries: Vec<(usize, f64)>,
    jac: Vec<(usize, Vector3<f64>)>,
}

impl Gradient {
    /// Adds the scalar's gradient `g` with respect to anchor `a`'s position.
    fn point(&mut self, model: &Structure, a: u32, g: &Vector3<f64>) {
        self.jac.clear();
        anchor_jacobian(model, a, &mut self.jac);
        for (dof, dp) in &self.jac {
            self.entries.push((*dof, dp.dot(g)));
        }
    }

    /// The entries merged by coordinate; the gradient is emptied.
    fn take(&mut self) -> Vec<(usize, f64)> {
        self.entries.sort_unstable_by_key(|(i, _)| *i);
        let mut merged: Vec<(usize, f64)> = Vec::with_capacity(self.entries.len());
        for &(i, v) in &self.entries {
            match merged.last_mut() {
                Some((j, w)) if *j == i => *w += v,
                _ => merged.push((i, v)),
            }
        }
        self.entries.clear();
        merged
    }
}

/// The blocks of the local stiffness at rest: the rigid bodies' 30 x 30 (row-major) and each
/// free vertex's 3 x 3.
fn local_stiffness(model: &Structure) -> (Vec<f64>, Vec<Matrix3<f64>>) {
    let mut rigid = vec![0.0; RIGID * RIGID];
    let mut vertex = vec![Matrix3::zeros(); model.free_vertices()];
    let mut add = |gamma: f64, g: &[(usize, f64)]| {
        for &(i, a) in g {
            for &(j, b) in g {
                if i < RIGID && j < RIGID {
                    rigid[i * RIGID + j] += gamma * a * b;
                } else if i >= RIGID && j >= RIGID && (i - RIGID) / 3 == (j - RIGID) / 3 {
                    vertex[(i - RIGID) / 3][((i - RIGID) % 3, (j - RIGID) % 3)] += gamma * a * b;
                }
            }
        }
    };
    let mut grad = Gradient::default();
    let pos = &model.rest;
    let el = &model.elements;
    let transverse = model.params.transverse_fraction;
    for e in 0..el.len() {
        let path = el.path_of(e);
        for w in path.windows(2) {
            let d = pos[w[1] as usize] - pos[w[0] as usize];
            let len = if path.len() == 2 {
                d.norm()
            } else {
                via_segment_length(&d)
            };
            if len < 1e-12 {
                continue;
            }
            let n = d / len;
            grad.point(model, w[0], &-n);
            grad.point(model, w[1], &n);
        }
        add(el.stiffness[e], &grad.take());
        // a two-point element's transverse directions carry the fraction `transverse` of
        // its stiffness (the tilt it may take, module doc)
        if path.len() == 2 && transverse > 0.0 {
            let d = pos[path[1] as usize] - pos[path[0] as usize];
            if d.norm() < 1e-12 {
                continue;
            }
            let n = d.normalize();
            let t1 = n
                .cross(&Vector3::x())
                .try_normalize(1e-6)
                .unwrap_or_else(|| n.cross(&Vector3::y()).normalize());
            let t2 = n.cross(&t1);
            for t in [t1, t2] {
                grad.point(model, path[0], &-t);
                grad.point(model, path[1], &t);
                add(transverse * el.stiffness[e], &grad.take());
            }
        }
    }
    let s = &model.springs;
    for i in 0..s.a.len() {
        for k in 0..3 {
            if s.horizontal[i] && k == 1 {
                continue;
            }
            let mut e = Vector3::zeros();
            e[k] = 1.0;
            grad.point(model, s.a[i], &-e);
            grad.point(model, s.b[i], &e);
            add(s.stiffness[i], &grad.take());
        }
    }
    for r in 0..RIBS {
        rigid[r * RIGID + r] += model.rib_stiffness[r];
    }
    (rigid, vertex)
}

/// The inertia each free vertex gains from the vector springs' damping beyond the
/// stiffness-proportional part (the abdominal wall's tissue resistance): c / omega_i, so that
/// the damper alone relaxes a vertex no faster than omega_i [kg, isotropic].
fn viscous_vertex_mass(model: &Structure, omega: f64) -> Vec<f64> {
    let rayleigh = 2.0 * model.params.damping_ratio / omega;
    let mut mass = vec![0.0; model.free_vertices()];
    let s = &model.springs;
    for i in 0..s.a.len() {
        let extra = s.damping[i] - rayleigh * s.stiffness[i];
        if extra <= 1e-12 * s.damping[i].abs() {
            continue;
        }
        for a in [s.a[i], s.b[i]] {
            if let Carrier::Vertex(j) = model.carrier[a as usize] {
                mass[j as usize] += extra / omega;
            }
        }
    }
    mass
}

/// The generalised gradient dV/dq of the volume enclosed by `tris` at rest (dV/dp of a
/// corner is the sum of face / 6 over its triangles, exact on a closed surface).
pub fn volume_gradient(model: &Structure, tris: &[[u32; 3]]) -> Vec<f64> {
    let pos = &model.rest;
    let mut grad = vec![Vector3::zeros(); pos.len()];
    for t in tris {
        let [a, b, c] = t.map(|i| pos[i as usize]);
        let f = (b - a).cross(&(c - a)) / 6.0;
        for &i in t {
            grad[i as usize] += f;
        }
    }
    let mut out = vec![0.0; RIGID + 3 * model.free_vertices()];
    let mut jac = Vec::new();
    for (a, g) in grad.iter().enumerate() {
        jac.clear();
        anchor_jacobian(model, a as u32, &mut jac);
        for (dof, dp) in &jac {
            out[*dof] += dp.dot(g);
        }
    }
    out
}

impl MassMatrix {
    /// The mass matrix of a model of structure `model` (whose masses are the true ones) for the inertia frequency
    /// `frequency` [Hz] (module doc); `slopes` are the pressure slopes dP/dV at rest `[abdomen, thorax]`
    /// [Pa/m^3] and `resistance` the airway resistance [Pa s/m^3].
    pub fn new(model: &Structure, frequency: f64, slopes: [f64; 2], resistance: f64) -> MassMatrix {
        let omega = 2.0 * std::f64::consts::PI * frequency;
        // the blocks' own frequency: half the inertia frequency, since the blocks' coupling
        // (a vertex and its neighbours moving in opposition) can double it
        let w2 = 0.25 * omega * omega;
        let (k_rigid, k_vertex) = local_stiffness(model);
        // the rigid block: true inertias plus stiffness / omega^2
        let mut rigid = DMatrix::<f64>::zeros(RIGID, RIGID);
        for r in 0..RIBS {
            rigid[(r, r)] = model.rib_inertia[r];
        }
        for k in 0..3 {
            rigid[(RIBS + k, RIBS + k)] = model.sternum_mass;
            for l in 0..3 {
                rigid[(RIBS + 3 + k, RIBS + 3 + l)] = model.sternum_inertia[(k, l)];
            }
        }
        let true_diagonal: Vec<f64> = (0..RIGID).map(|i| rigid[(i, i)]).collect();
        for i in 0..RIGID {
            for j in 0..RIGID {
                rigid[(i, j)] += k_rigid[i * RIGID + j] / w2;
            }
        }
        let rigid_ratio = (0..RIGID)
            .map(|i| rigid[(i, i)] / true_diagonal[i])
            .collect();
        let rigid_inverse = rigid
            .clone()
            .cholesky()
            .expect("the rigid bodies' mass block is positive definite")
            .inverse();
        let vertex: Vec<Matrix3<f64>> = k_vertex
            .iter()
            .zip(&model.vertex_mass)
            .zip(viscous_vertex_mass(model, omega))
            .map(|((k, m), c)| Matrix3::identity() * (*m + c) + k / w2)
            .collect();
        let vertex_ratio = vertex
            .iter()
            .zip(&model.vertex_mass)
            .map(|(b, m)| b.trace() / (3.0 * m))
            .collect();
        let vertex_inverse = vertex
            .iter()
            .map(|b| {
                b.cholesky()
                    .expect("a vertex's mass block is positive definite")
                    .inverse()
            })
            .collect();
        let inertance = [
            slopes[0] / w2,
            AIRWAY_INERTANCE.max(slopes[1] / w2).max(resistance / omega),
        ];
        let rib_local = (0..RIBS).map(|r| 1.0 / rigid[(r, r)]).collect();
        let sternum_local = rigid
            .view((RIBS, RIBS), (6, 6))
            .into_owned()
            .cholesky()
            .expect("the sternum's mass block is positive definite")
            .inverse()
            .transpose()
            .as_slice()
            .to_vec();
        let mut m = MassMatrix {
            rib_local,
            sternum_local,
            rigid_inverse: rigid_inverse.transpose().as_slice().to_vec(),
            rigid: rigid.transpose().as_slice().to_vec(),
            vertex_inverse,
            vertex,
            u: Vec::new(),
            z: Vec::new(),
            s: Matrix2::identity(),
            inertance,
            rigid_ratio,
            vertex_ratio,
        };
        let ga = volume_gradient(model, &model.abdomen_triangles);
        let gt = volume_gradient(model, &model.thorax_triangles);
        let n = ga.len();
        let mut z = [ga.clone(), gt.clone()];
        for col in &mut z {
            m.solve_blocks(col);
        }
        let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
        m.s = if inertance[0] > 0.0 {
            let gram = Matrix2::new(
                1.0 / inertance[0] + dot(&ga, &z[0]),
                dot(&ga, &z[1]),
                dot(&gt, &z[0]),
                1.0 / inertance[1] + dot(&gt, &z[1]),
            );
            gram.try_inverse()
                .expect("the volume coupling is invertible")
        } else {
            // true masses (frequency infinite): no inertance added to the abdomen's volume,
            // only the airways' gas inertance on the thorax's
            Matrix2::new(0.0, 0.0, 0.0, 1.0 / (1.0 / inertance[1] + dot(&gt, &z[1])))
        };
        m.u = [ga, gt].concat();
        m.z = [z[0].clone(), z[1].clone()].concat();
        debug_assert_eq!(m.u.len(), 2 * n);
        m
    }

    /// b <- B^-1 b, the block-diagonal part.
    fn solve_blocks(&self, b: &mut [f64]) {
        let mut rigid = [0.0; RIGID];
        for (i, out) in rigid.iter_mut().enumerate() {
            let row = &self.rigid_inverse[i * RIGID..(i + 1) * RIGID];
            *out = row.iter().zip(&b[..RIGID]).map(|(a, x)| a * x).sum();
        }
        b[..RIGID].copy_from_slice(&rigid);
        for (inv, v) in self
            .vertex_inverse
            .iter()
            .zip(b[RIGID..].chunks_exact_mut(3))
        {
            let x = inv * Vector3::new(v[0], v[1], v[2]);
            v.copy_from_slice(x.as_slice());
        }
    }

    /// f <- M^-1 f: generalised forces (rib torques, sternum force and torque, vertex
    /// forces) to accelerations.
    pub fn solve(&self, f: &mut [f64]) {
        self.solve_blocks(f);
        let n = f.len();
        let (u, z) = (&self.u, &self.z);
        let ub = Vector2::new(
            u[..n].iter().zip(&*f).map(|(a, b)| a * b).sum(),
            u[n..].iter().zip(&*f).map(|(a, b)| a * b).sum(),
        );
        let c = self.s * ub;
        for ((x, za), zt) in f.iter_mut().zip(&z[..n]).zip(&z[n..]) {
            *x -= za * c[0] + zt * c[1];
        }
    }

    /// f <- M_b^-1 f with M_b the mass matrix's blocks of each body alone (each rib's
    /// diagonal entry, the sternum's 6 x 6 block, each vertex's 3 x 3 block; the coupling of
    /// the rigid bodies and the volume inertances left out): an approximation of
    /// [`MassMatrix::solve`] whose Jacobian keeps the sparsity of the forces': the
    /// equilibrium's residual, and the stiff method's Jacobian before
    /// [`MassMatrix::local_to_full`] maps it to the whole mass matrix's.
    pub fn solve_local(&self, f: &mut [f64]) {
        for (x, inv) in f[..RIBS].iter_mut().zip(&self.rib_local) {
            *x *= inv;
        }
        let mut s = [0.0; 6];
        for (i, out) in s.iter_mut().enumerate() {
            let row = &self.sternum_local[i * 6..(i + 1) * 6];
            *out = row.iter().zip(&f[RIBS..RIGID]).map(|(a, x)| a * x).sum();
        }
        f[RIBS..RIGID].copy_from_slice(&s);
        for (inv, v) in self
            .vertex_inverse
            .iter()
            .zip(f[RIGID..].chunks_exact_mut(3))
        {
            let x = inv * Vector3::new(v[0], v[1], v[2]);
            v.copy_from_slice(x.as_slice());
        }
    }

    /// The map L = M^-1 M_b from the local accelerations of [`MassMatrix::solve_local`] to
    /// the true ones of [`MassMatrix::solve`], as L = I + Σ_k a_k b_k^T (returned as the
    /// column pairs `(a_k, b_k)`, generalised dimension each). With B the blocks of
    /// [`MassMatrix::solve`] (the rigid bodies' whole 30 x 30 block, each vertex's 3 x 3),
    /// M^-1 = B^-1 - Z S U^T B^-1 (Woodbury), so L = B^-1 M_b - Z S (M_b Z)^T; B^-1 M_b
    /// differs from the identity on the rigid bodies only, by R - I = B_r^-1 M_b,r - I
    /// (30 pairs: the columns of R - I with the unit vectors), and the volume inertances add
    /// two pairs (-Z S's columns with M_b Z's). The stiff method's Jacobian is the local
    /// one's image under L, which keeps its sparse part and adds these 32 to its low rank.
    pub fn local_to_full(&self) -> Vec<(Vec<f64>, Vec<f64>)> {
        let n = self.u.len() / 2;
        let mut pairs = Vec::with_capacity(RIGID + 2);
        // M_b's rigid part: each rib's diagonal entry, the sternum's 6 x 6 block
        let local = |i: usize, j: usize| -> f64 {
            if (i < RIBS || j < RIBS) && i != j {
                0.0
            } else {
                self.rigid[i * RIGID + j]
            }
        };
        for j in 0..RIGID {
            let mut a = vec![0.0; n];
            for (i, ai) in a[..RIGID].iter_mut().enumerate() {
                let r: f64 = (0..RIGID)
                    .map(|k| self.rigid_inverse[i * RIGID + k] * local(k, j))
                    .sum();
                *ai = r - f64::from(u8::from(i == j));
            }
            let mut b = vec![0.0; n];
            b[j] = 1.0;
            pairs.push((a, b));
        }
        // M_b Z
        let mut mz = [self.z[..n].to_vec(), self.z[n..].to_vec()];
        for col in &mut mz {
            let mut rigid = [0.0; RIGID];
            for (i, out) in rigid.iter_mut().enumerate() {
                *out = (0..RIGID).map(|k| local(i, k) * col[k]).sum();
            }
            col[..RIGID].copy_from_slice(&rigid);
            for (b, v) in self.vertex.iter().zip(col[RIGID..].chunks_exact_mut(3)) {
                let x = b * Vector3::new(v[0], v[1], v[2]);
                v.copy_from_slice(x.as_slice());
            }
        }
        for (k, yk) in mz.into_iter().enumerate() {
            // column k of -Z S
            let a: Vec<f64> = (0..n)
                .map(|i| -(self.z[i] * self.s[(0, k)] + self.z[n + i] * self.s[(1, k)]))
                .collect();
            pairs.push((a, yk));
        }
        pairs
    }

    /// Kinetic energy q'^T M q' / 2 of the generalised velocities `v`.
    pub fn kinetic_energy(&self, v: &[f64]) -> f64 {
        let mut e = 0.0;
        for i in 0..RIGID {
            let row = &self.rigid[i * RIGID..(i + 1) * RIGID];
            e += v[i] * row.iter().zip(&v[..RIGID]).map(|(a, x)| a * x).sum::<f64>();
        }
        for (b, x) in self.vertex.iter().zip(v[RIGID..].chunks_exact(3)) {
            let x = Vector3::new(x[0], x[1], x[2]);
            e += x.dot(&(b * x));
        }
        let n = v.len();
        for k in 0..2 {
            let rate: f64 = self.u[k * n..(k + 1) * n]
                .iter()
                .zip(v)
                .map(|(a, b)| a * b)
                .sum();
            e += self.inertance[k] * rate * rate;
        }
        0.5 * e
    }
}
