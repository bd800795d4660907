//! Stage 2: forces on anchors.
//!
//! - Muscle and membrane elements (thesis eq. 2.2): f = c e + gamma e', e = |r| - l(t), with
//!   l(t) = l0 r(t) (eq. 2.3) and r = 1 - beta_max a g s for muscles (a the side's activation
//!   of the group, g the element's regional gain, s the tissue's rest length over the path's:
//!   the smooth dome's arcs over the chords for a diaphragm fibre, else 1). Muscles only pull (Zajac 1989, thesis 2.1),
//!   and so do the membrane edges of the diaphragm's dome ([`super::PASSIVE_SLACK`]), and
//!   those of the abdominal wall under [`super::Params::abdominal_wall_tension_only`]: a
//!   membrane wrinkles rather than carry compression (tension-field theory: Stein &
//!   Hedgepeth 1961, NASA TN D-813; Mansfield 1969, Proc R Soc A 311:1). The tension of
//!   either is the softplus eps ln(1 + exp(f / eps)) of f, a smooth toe of width eps
//!   ([`super::Params::tension_toe`]) in place of max(0, f), so that the right-hand side is
//!   smooth where an element goes slack. A two-point element also damps its ends' relative
//!   velocity across it, alpha gamma (v_b - v_a)_perp with alpha
//!   [`super::Params::transverse_fraction`] (the tilted element of `dynamics::inertia`).
//! - Under the passive-and-active muscle law ([`super::muscle::MuscleLaw::Hill`], an option
//!   of [`super::Params::muscle_law`]), a muscle's spring force is replaced by
//!   F_max (f_PE + a f_A) ([`super::muscle::force`]) with the same damper and the same
//!   softplus tension.
//! - Zero-length vector springs (cartilage ball joints, wall foundation): F = k d + c d'; the
//!   wall foundation's c adds the wall's tissue resistance
//!   ([`super::Params::abdominal_wall_resistance`]) to the stiffness-proportional part.
//! - Abdominal pressure (eq. 2.5): P = K (V0/V - 1) - mu dV/dt; each triangle pushes each of
//!   its corners with P A n / 3 (eq. 2.6), which on a closed surface is exactly P dV/dx. The
//!   viscous term mu (`Structure::abdomen_viscosity`) damps the cavity's volume mode.
//! - The abdominal contents' hydrostatic pressure rho g . (x - x_c) under
//!   [`super::GravityLoads::Acting`] (`hydrostatic_pressure`), on top of the mean pressure.
//! - Pleural pressure: P_pl = P_ao - P_L(V_th) - R dV_th/dt on the thoracic surface: the
//!   pressure at the airway opening (`Activations::airway_opening`, 0 breathing air) less the
//!   lungs' recoil and the pressure drop of the airflow through the airway resistance R
//!   (`Structure::airway_resistance`); dV/dt is the sum over the triangles of A n . (v_a + v_b +
//!   v_c) / 3, exact on a closed surface. With the airway occluded (`Activations::occlusion`)
//!   no gas flows and P_ao - R dV/dt is replaced by the alveolar pressure of Boyle's law on
//!   the lungs' gas (`super::airway`). All relative to rest, where the chest wall's rest
//!   forces balance the lungs' recoil at FRC.

use super::structure::{PASSIVE, Structure, VIA, via_segment_length};
use super::{Activations, Data};
use nalgebra::{Point3, Vector3};

/// Computes `data.force` for every anchor.
pub fn accumulate(model: &Structure, data: &mut Data, act: &Activations) {
    local_forces(model, data, act);
    abdominal_pressure(model, data);
    pleural_pressure(model, data, act);
}

/// As [`accumulate`], but with the abdominal and pleural pressures held at the given values
/// `[abdominal, pleural]` [Pa] instead of computed from the volumes: the local part of the
/// forces, whose Jacobian is sparse (used by `dynamics::jacobian`). `data`'s volumes and
/// pressures are left as they were.
pub fn accumulate_frozen(
    model: &Structure,
    data: &mut Data,
    act: &Activations,
    pressures: [f64; 2],
) {
    local_forces(model, data, act);
    let (na, nt) = (model.abdomen_triangles.len(), model.thorax_triangles.len());
    let (abdomen, thorax) = data.face.split_at_mut(na);
    face_vectors(&data.pos, &model.abdomen_triangles, abdomen);
    face_vectors(&data.pos, &model.thorax_triangles, &mut thorax[..nt]);
    let Data { face, force, .. } = data;
    let (abdomen, thorax) = face.split_at(na);
    let tris = &model.abdomen_triangles;
    apply_pressure(tris, &model.abdomen_moving, abdomen, pressures[0], force);
    let tris = &model.thorax_triangles;
    apply_pressure(tris, &model.thorax_moving, thorax, pressures[1], force);
}

/// The abdominal contents' hydrostatic pressure p = rho g . (x - x_c)
/// ([`Structure::contents_density`], [`Structure::contents_centre`]) on the moving triangles
/// of the abdominal surface, on top of the cavity's mean pressure. A pressure linear over a
/// flat triangle loads corner i with A n (2 p_i + p_j + p_k) / 12 (its integral against the
/// corner's hat function), which is exactly minus the derivative of the contents' potential
/// ([`super::energy::hydrostatic_energy`]) with respect to the corner (Reynolds transport:
/// moving a corner moves the surface by its hat function). Over the whole closed surface the
/// loads add up to the contents' weight, rho g V; the fixed triangles' share is carried by
/// the skeleton.
fn hydrostatic_pressure(model: &Structure, data: &mut Data) {
    let (rho, g) = (model.contents_density, model.gravity);
    if rho == 0.0 || g == Vector3::zeros() {
        return;
    }
    let c = model.contents_centre;
    let Data { pos, force, .. } = data;
    for (t, &moving) in model.abdomen_triangles.iter().zip(&model.abdomen_moving) {
        if !moving {
            continue;
        }
        let [a, b, d] = t.map(|i| pos[i as usize]);
        // (b - a) x (d - a) = 2 A n
        let face = (b - a).cross(&(d - a));
        let p = [a, b, d].map(|x| rho * g.dot(&(x - c)));
        let sum = p[0] + p[1] + p[2];
        for k in 0..3 {
            force[t[k] as usize] += face * ((p[k] + sum) / 24.0);
        }
    }
}

/// Element and vector-spring forces, and the abdominal contents' hydrostatic pressure
/// (everything but the cavities' mean pressures).
fn local_forces(model: &Structure, data: &mut Data, act: &Activations) {
    data.force.fill(Vector3::zeros());
    elements(model, data, act);
    vector_springs(model, data);
    hydrostatic_pressure(model, data);
}

/// Muscle and membrane elements. An element along a path p_0 .. p_m has length
/// L = sum s_k, s_k = sqrt(|d_k|^2 + c^2) with d_k = p_{k+1} - p_k and c the band's core
/// ([`super::PATH_CORE`]; c = 0 for two-point elements), and rate
/// L' = sum (v_{k+1} - v_k) . n_k with n_k = d_k / s_k; its tension f acts on each via point
/// along n_k - n_{k-1}, on the origin along n_0 and on the insertion along -n_{m-1}
/// (f = -dE/dx of the element's energy).
///
/// Runs of [`LANES`] consecutive two-point elements are computed together, one array per
/// coordinate (structure of arrays), so that the lengths, square roots, divisions and
/// spring-damper laws compile to vector instructions; on x86-64 CPUs with AVX2 (detected at
/// run time) the loop is compiled for 4-wide vectors, elsewhere for the baseline (SSE2 on
/// x86-64, NEON on aarch64). Each lane does the operations of [`Pass::single`] in the same
/// order, with no fused multiply-add, and the forces are added to the anchors element by
/// element in the elements' order: the result is bit for bit the same on every path.
fn elements(model: &Structure, data: &mut Data, act: &Activations) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU has AVX2, checked just above.
        unsafe { elements_avx2(model, data, act) };
        return;
    }
    elements_in_batches::<false>(model, data, act);
}

/// [`elements_in_batches`] compiled for AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn elements_avx2(model: &Structure, data: &mut Data, act: &Activations) {
    elements_in_batches::<true>(model, data, act);
}

/// Elements computed per batch of [`LANES`] two-point elements (4 doubles fill an AVX2
/// register).
const LANES: usize = 4;

/// The element loop behind [`elements`], inlined into each instruction-set variant; `AVX2`
/// says that the caller runs with AVX2 enabled, so that the batches use its intrinsics.
#[inline(always)]
fn elements_in_batches<const AVX2: bool>(model: &Structure, data: &mut Data, act: &Activations) {
    let level = act.table();
    let n = model.elements.len();
    let m = data.pos.len();
    let pass = Pass::new(model, &data.pos[..m], &data.vel[..m], &level);
    let force = &mut data.force[..m];
    let mut e = 0;
    while e < n {
        if e + LANES <= n && pass.ends[e..e + LANES].iter().all(|p| p[0] != VIA) {
            pass.batch::<AVX2>(e, force);
            e += LANES;
        } else {
            pass.single(e, force);
            e += 1;
        }
    }
}

/// What the element loop reads: the elements' arrays, the activation table and the anchors'
/// positions and velocities.
struct Pass<'a> {
    start: &'a [u32],
    path: &'a [u32],
    ends: &'a [[u32; 2]],
    rest_length: &'a [f64],
    stiffness: &'a [f64],
    damping: &'a [f64],
    slot: &'a [u8],
    gain: &'a [f64],
    max_force: &'a [f64],
    optimal_length: &'a [f64],
    slack_length: &'a [f64],
    drive: &'a [f64],
    /// The active stiffness k_A of the passive-and-active law ([`super::muscle`]).
    active_stiffness: f64,
    /// Whether the model's muscles follow the passive-and-active law (else no element reads
    /// `max_force` and the rest: the thesis's law pays nothing for the other).
    hill: bool,
    level: &'a [f64; 256],
    toe: f64,
    transverse: f64,
    pos: &'a [Point3<f64>],
    vel: &'a [Vector3<f64>],
}

impl<'a> Pass<'a> {
    /// The pass over `model`'s elements at anchor positions `pos` and velocities `vel` (of
    /// one length) under the activation table `level` ([`Activations::table`]).
    fn new(
        model: &'a Structure,
        pos: &'a [Point3<f64>],
        vel: &'a [Vector3<f64>],
        level: &'a [f64; 256],
    ) -> Pass<'a> {
        let el = &model.elements;
        let n = el.len();
        Pass {
            start: &el.start[..n + 1],
            path: &el.path[..],
            ends: &el.ends[..n],
            rest_length: &el.rest_length[..n],
            stiffness: &el.stiffness[..n],
            damping: &el.damping[..n],
            slot: &el.slot[..n],
            gain: &el.gain[..n],
            max_force: &el.max_force[..n],
            optimal_length: &el.optimal_length[..n],
            slack_length: &el.slack_length[..n],
            drive: &el.drive[..n],
            active_stiffness: super::muscle::active_stiffness(),
            hill: model.params.muscle_law == super::muscle::MuscleLaw::Hill,
            level,
            toe: model.params.tension_toe,
            transverse: model.params.transverse_fraction,
            pos,
            vel: &vel[..pos.len()],
        }
    }

    /// The rest length of element `e` under its activation: l0 (1 - a g); a membrane
    /// element's slot reads 0 and its gain is 0, so its rest length is l0 exactly.
    #[inline(always)]
    fn rest(&self, e: usize) -> f64 {
        self.rest_length[e] * (1.0 - self.level[self.slot[e] as usize] * self.gain[e])
    }

    /// The force of element `e` of length `len` and rate `rate` when it is a muscle under
    /// the passive-and-active law ([`super::muscle::force`] plus its damper), else `linear`,
    /// the linear spring-damper's.
    #[inline(always)]
    fn hill_or(&self, e: usize, len: f64, rate: f64, linear: f64) -> f64 {
        if !self.hill {
            return linear;
        }
        let f_max = self.max_force[e];
        if f_max == 0.0 {
            return linear;
        }
        let a = self.level[self.slot[e] as usize] * self.drive[e];
        let (o, s) = (self.optimal_length[e], self.slack_length[e]);
        super::muscle::force(len, o, s, f_max, a, self.active_stiffness) + self.damping[e] * rate
    }

    /// The two-point elements `e .. e + LANES`, lane by lane in arrays of coordinates (the
    /// arithmetic on whole arrays, [`add`], [`sub`], [`mul`], [`div`], so that it compiles to
    /// vector instructions); the forces are added to the anchors in the elements' order.
    #[inline(always)]
    fn batch<const AVX2: bool>(&self, e: usize, force: &mut [Vector3<f64>]) {
        let (pos, vel) = (self.pos, self.vel);
        let mut d = [[0.0; LANES]; 3];
        let mut dv = [[0.0; LANES]; 3];
        let mut ends = [[0usize; 2]; LANES];
        let mut rest = [0.0; LANES];
        for l in 0..LANES {
            let [a, b] = self.ends[e + l];
            let (a, b) = (a as usize, b as usize);
            ends[l] = [a, b];
            let (x, v) = (pos[b] - pos[a], vel[b] - vel[a]);
            for k in 0..3 {
                d[k][l] = x[k];
                dv[k][l] = v[k];
            }
            rest[l] = self.rest(e + l);
        }
        let (stiffness, damping) = (lanes(self.stiffness, e), lanes(self.damping, e));
        let cross = mul([self.transverse; LANES], damping);
        #[cfg(target_arch = "x86_64")]
        let (len, n, rate, mut f) = if AVX2 {
            // SAFETY: `AVX2` is true only in `elements_avx2`, reached after the CPU was found
            // to have AVX2.
            unsafe { spring_damper_avx2(&d, &dv, &stiffness, &damping, &rest) }
        } else {
            spring_damper(&d, &dv, &stiffness, &damping, &rest)
        };
        #[cfg(not(target_arch = "x86_64"))]
        let (len, n, rate, mut f) = spring_damper(&d, &dv, &stiffness, &damping, &rest);
        for (l, f) in f.iter_mut().enumerate() {
            if self.slot[e + l] != PASSIVE {
                *f = tension(self.hill_or(e + l, len[l], rate[l], *f), self.toe);
            }
        }
        let fv: [[f64; LANES]; 3] =
            std::array::from_fn(|k| add(mul(n[k], f), mul(sub(dv[k], mul(n[k], rate)), cross)));
        for l in 0..LANES {
            if len[l] < 1e-12 {
                continue;
            }
            let [a, b] = ends[l];
            let v = Vector3::new(fv[0][l], fv[1][l], fv[2][l]);
            force[a] += v;
            force[b] -= v;
        }
    }

    /// Element `e` alone (a two-point element, or one along a path with via points).
    #[inline(always)]
    fn single(&self, e: usize, force: &mut [Vector3<f64>]) {
        let (pos, vel) = (self.pos, self.vel);
        let rest = self.rest(e);
        let muscle = self.slot[e] != PASSIVE;
        let (stiffness, damping) = (self.stiffness[e], self.damping[e]);
        let [a, b] = self.ends[e];
        if a != VIA {
            let (a, b) = (a as usize, b as usize);
            let d = pos[b] - pos[a];
            let len = d.norm();
            if len < 1e-12 {
                return;
            }
            let n = d / len;
            let rate = (vel[b] - vel[a]).dot(&n);
            let mut f = stiffness * (len - rest) + damping * rate;
            if muscle {
                f = tension(self.hill_or(e, len, rate, f), self.toe);
            }
            // the transverse damper (`Params::transverse_fraction`): the ends' relative
            // velocity across the element
            let dv = vel[b] - vel[a];
            let fv = n * f + (dv - n * rate) * (self.transverse * damping);
            force[a] += fv;
            force[b] -= fv;
            return;
        }
        let path = &self.path[self.start[e] as usize..self.start[e + 1] as usize];
        let (mut len, mut rate) = (0.0, 0.0);
        for w in path.windows(2) {
            let (a, b) = (w[0] as usize, w[1] as usize);
            let d = pos[b] - pos[a];
            let l = via_segment_length(&d);
            len += l;
            rate += (vel[b] - vel[a]).dot(&d) / l;
        }
        let mut f = stiffness * (len - rest) + damping * rate;
        if muscle {
            f = tension(self.hill_or(e, len, rate, f), self.toe);
        }
        if f == 0.0 {
            return;
        }
        for w in path.windows(2) {
            let (a, b) = (w[0] as usize, w[1] as usize);
            let d = pos[b] - pos[a];
            let fv = d * (f / via_segment_length(&d));
            force[a] += fv;
            force[b] -= fv;
        }
    }
}

/// Length |d|, direction n = d / |d|, rate dv . n and spring-damper force
/// c (|d| - l) + gamma rate of [`LANES`] two-point elements whose end-to-end vectors are `d`
/// and relative velocities `dv` (coordinate, lane), with nalgebra's orders of operations:
/// |d| = sqrt((x x + y y) + z z), dot products (x + y) + z.
#[allow(clippy::type_complexity)]
#[inline(always)]
fn spring_damper(
    d: &[[f64; LANES]; 3],
    dv: &[[f64; LANES]; 3],
    stiffness: &[f64; LANES],
    damping: &[f64; LANES],
    rest: &[f64; LANES],
) -> ([f64; LANES], [[f64; LANES]; 3], [f64; LANES], [f64; LANES]) {
    let len = add(add(mul(d[0], d[0]), mul(d[1], d[1])), mul(d[2], d[2])).map(f64::sqrt);
    let n = d.map(|x| div(x, len));
    let rate = add(add(mul(dv[0], n[0]), mul(dv[1], n[1])), mul(dv[2], n[2]));
    let f = add(mul(*stiffness, sub(len, *rest)), mul(*damping, rate));
    (len, n, rate, f)
}

/// [`spring_damper`] with AVX2 intrinsics: four lanes per instruction, each lane's
/// operations those of the scalar path (IEEE square root and division, no fused
/// multiply-add), so bit for bit its result.
#[cfg(target_arch = "x86_64")]
#[allow(clippy::type_complexity)]
#[target_feature(enable = "avx2")]
fn spring_damper_avx2(
    d: &[[f64; LANES]; 3],
    dv: &[[f64; LANES]; 3],
    stiffness: &[f64; LANES],
    damping: &[f64; LANES],
    rest: &[f64; LANES],
) -> ([f64; LANES], [[f64; LANES]; 3], [f64; LANES], [f64; LANES]) {
    use std::arch::x86_64::{
        __m256d, _mm256_add_pd, _mm256_div_pd, _mm256_loadu_pd, _mm256_mul_pd, _mm256_sqrt_pd,
        _mm256_storeu_pd, _mm256_sub_pd,
    };
    #[inline]
    #[target_feature(enable = "avx2")]
    fn load(x: &[f64; LANES]) -> __m256d {
        // SAFETY: 4 doubles read from a `[f64; 4]`.
        unsafe { _mm256_loadu_pd(x.as_ptr()) }
    }
    #[inline]
    #[target_feature(enable = "avx2")]
    fn store(x: __m256d) -> [f64; LANES] {
        let mut out = [0.0; LANES];
        // SAFETY: 4 doubles written to a `[f64; 4]`.
        unsafe { _mm256_storeu_pd(out.as_mut_ptr(), x) };
        out
    }
    let (dx, dy, dz) = (load(&d[0]), load(&d[1]), load(&d[2]));
    let len2 = _mm256_add_pd(
        _mm256_add_pd(_mm256_mul_pd(dx, dx), _mm256_mul_pd(dy, dy)),
        _mm256_mul_pd(dz, dz),
    );
    let len = _mm256_sqrt_pd(len2);
    let (nx, ny, nz) = (
        _mm256_div_pd(dx, len),
        _mm256_div_pd(dy, len),
        _mm256_div_pd(dz, len),
    );
    let rate = _mm256_add_pd(
        _mm256_add_pd(
            _mm256_mul_pd(load(&dv[0]), nx),
            _mm256_mul_pd(load(&dv[1]), ny),
        ),
        _mm256_mul_pd(load(&dv[2]), nz),
    );
    let f = _mm256_add_pd(
        _mm256_mul_pd(load(stiffness), _mm256_sub_pd(len, load(rest))),
        _mm256_mul_pd(load(damping), rate),
    );
    (
        store(len),
        [store(nx), store(ny), store(nz)],
        store(rate),
        store(f),
    )
}

/// `LANES` consecutive values of `values` from `e`.
#[inline(always)]
fn lanes(values: &[f64], e: usize) -> [f64; LANES] {
    let mut out = [0.0; LANES];
    out.copy_from_slice(&values[e..e + LANES]);
    out
}

/// Lane-wise a + b.
#[inline(always)]
fn add(a: [f64; LANES], b: [f64; LANES]) -> [f64; LANES] {
    std::array::from_fn(|l| a[l] + b[l])
}

/// Lane-wise a - b.
#[inline(always)]
fn sub(a: [f64; LANES], b: [f64; LANES]) -> [f64; LANES] {
    std::array::from_fn(|l| a[l] - b[l])
}

/// Lane-wise a b.
#[inline(always)]
fn mul(a: [f64; LANES], b: [f64; LANES]) -> [f64; LANES] {
    std::array::from_fn(|l| a[l] * b[l])
}

/// Lane-wise a / b.
#[inline(always)]
fn div(a: [f64; LANES], b: [f64; LANES]) -> [f64; LANES] {
    std::array::from_fn(|l| a[l] / b[l])
}

/// Tension of a muscle element whose linear spring-damper force is `f`: the softplus
/// eps ln(1 + exp(f / eps)) with eps = `toe`, written as max(f, 0) + eps ln(1 + exp(-|f| /
/// eps)) so that it cannot overflow; beyond 40 eps from slack the correction is below
/// 4e-18 eps, under the rounding of f, and is not computed.
#[inline]
pub fn tension(f: f64, toe: f64) -> f64 {
    let x = f.abs() / toe;
    if x > 40.0 {
        f.max(0.0)
    } else {
        f.max(0.0) + toe * (-x).exp().ln_1p()
    }
}

/// The outward normal force [N] of a wall foundation spring of stiffness `k` [N/m] and
/// unloading length `lambda` [m] at an outward displacement `u` [m] from its rest
/// (`Params::abdominal_wall_unloading`): -k u outwards, k lambda (1 - exp(u / lambda)) inwards,
/// which is the load k lambda the vertex carried at rest given up along an exponential. Its
/// slope is -k at rest on both sides.
#[inline]
pub fn unloading_force(k: f64, lambda: f64, u: f64) -> f64 {
    if u >= 0.0 {
        -k * u
    } else {
        -k * lambda * (u / lambda).exp_m1()
    }
}

/// The energy [J] of [`unloading_force`]: k u^2 / 2 outwards, k lambda^2 (exp(x) - 1 - x) with
/// x = u / lambda inwards.
#[inline]
pub fn unloading_energy(k: f64, lambda: f64, u: f64) -> f64 {
    if u >= 0.0 {
        0.5 * k * u * u
    } else {
        let x = u / lambda;
        k * lambda * lambda * (x.exp_m1() - x)
    }
}

/// Cartilage joints and wall foundation.
fn vector_springs(model: &Structure, data: &mut Data) {
    let s = &model.springs;
    let n = s.a.len();
    let (ia, ib, horizontal) = (&s.a[..n], &s.b[..n], &s.horizontal[..n]);
    let (stiffness, damping) = (&s.stiffness[..n], &s.damping[..n]);
    let m = data.pos.len();
    let (pos, vel, force) = (&data.pos[..], &data.vel[..m], &mut data.force[..m]);
    for i in 0..n {
        let (a, b) = (ia[i] as usize, ib[i] as usize);
        let d = pos[b] - pos[a];
        let mut f = d * stiffness[i] + (vel[b] - vel[a]) * damping[i];
        if horizontal[i] {
            f.y = 0.0;
        }
        let lambda = s.unloading[i];
        if lambda > 0.0 {
            // the normal part, for the wall vertex's outward displacement u
            let n = s.normal[i];
            let u = -d.dot(&n);
            if u < 0.0 {
                let k = stiffness[i];
                f += n * (k * u + unloading_force(k, lambda, u));
            }
        }
        force[a] += f;
        force[b] -= f;
    }
}

/// Signed volume enclosed by `tris` (the same sum, in the same order, as
/// [`volume`](super::volume)), storing each triangle's volume term a . (b x c) in `term` and its
/// doubled area vector (b - a) x (c - a) in `face` for [`apply_pressure`]: the corners are
/// gathered once for both. Returns the sum of the terms, started at `sum`.
fn volume_and_faces(
    pos: &[Point3<f64>],
    tris: &[[u32; 3]],
    face: &mut [Vector3<f64>],
    term: &mut [f64],
    mut sum: f64,
) -> f64 {
    for ((t, f), v) in tris.iter().zip(face.iter_mut()).zip(term.iter_mut()) {
        let (a, b, c) = (
            &pos[t[0] as usize].coords,
            &pos[t[1] as usize].coords,
            &pos[t[2] as usize].coords,
        );
        *v = a.dot(&b.cross(c));
        sum += *v;
        *f = (b - a).cross(&(c - a));
    }
    sum
}

/// The volume sum of [`volume_and_faces`] and the rate sum of dV/dt in one pass over `tris`:
/// each moving triangle's corners are gathered once for its volume term, its face vector and
/// face . (v_a + v_b + v_c) (the volume's gradient at a corner of a closed surface is the sum of
/// face / 6 over its triangles, so dV/dt is the rate sum / 6). A triangle fixed to the ground
/// (`moving` false) keeps the term and face vector [`rest_terms`] stored in `Data::new`: its
/// corners never leave their rest positions, so recomputing them would give the same bits, and
/// it adds nothing to the rate. Both sums run in triangle order, started at `sums`, as the
/// separate volume and rate passes did, so that the results are bit-identical to theirs.
/// Returns `(volume sum, rate sum)`.
fn volume_faces_and_rate(
    pos: &[Point3<f64>],
    vel: &[Vector3<f64>],
    tris: &[[u32; 3]],
    moving: &[bool],
    face: &mut [Vector3<f64>],
    term: &mut [f64],
    sums: (f64, f64),
) -> (f64, f64) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU has AVX2, checked just above.
        return unsafe { volume_faces_and_rate_avx2(pos, vel, tris, moving, face, term, sums) };
    }
    volume_faces_and_rate_in_batches(pos, vel, tris, moving, face, term, sums)
}

/// [`volume_faces_and_rate_in_batches`] compiled for AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn volume_faces_and_rate_avx2(
    pos: &[Point3<f64>],
    vel: &[Vector3<f64>],
    tris: &[[u32; 3]],
    moving: &[bool],
    face: &mut [Vector3<f64>],
    term: &mut [f64],
    sums: (f64, f64),
) -> (f64, f64) {
    volume_faces_and_rate_in_batches(pos, vel, tris, moving, face, term, sums)
}

/// The pass behind [`volume_faces_and_rate`], inlined into each instruction-set variant: runs
/// of [`LANES`] moving triangles are computed together in arrays of coordinates (the
/// products of a . (b x c), (b - a) x (c - a) and its dot product with the corners' velocity
/// sum as nalgebra's `cross` and `dot` order them, no fused multiply-add), then added to the
/// two sums triangle by triangle in order: bit for bit the per-triangle loop.
#[inline(always)]
fn volume_faces_and_rate_in_batches(
    pos: &[Point3<f64>],
    vel: &[Vector3<f64>],
    tris: &[[u32; 3]],
    moving: &[bool],
    face: &mut [Vector3<f64>],
    term: &mut [f64],
    sums: (f64, f64),
) -> (f64, f64) {
    let (mut sum, mut rate) = sums;
    let n = tris.len();
    let (moving, face, term) = (&moving[..n], &mut face[..n], &mut term[..n]);
    let mut i = 0;
    while i < n {
        if i + LANES <= n && moving[i..i + LANES].iter().all(|&m| m) {
            // corner, coordinate, lane
            let mut p = [[[0.0; LANES]; 3]; 3];
            let mut w = [[0.0; LANES]; 3];
            for l in 0..LANES {
                let [a, b, c] = tris[i + l].map(|i| i as usize);
                let s = vel[a] + vel[b] + vel[c];
                for k in 0..3 {
                    p[0][k][l] = pos[a][k];
                    p[1][k][l] = pos[b][k];
                    p[2][k][l] = pos[c][k];
                    w[k][l] = s[k];
                }
            }
            let [a, b, c] = p;
            let (mut v, mut r) = ([0.0; LANES], [0.0; LANES]);
            let mut f = [[0.0; LANES]; 3];
            for l in 0..LANES {
                let bc = [
                    b[1][l] * c[2][l] - b[2][l] * c[1][l],
                    b[2][l] * c[0][l] - b[0][l] * c[2][l],
                    b[0][l] * c[1][l] - b[1][l] * c[0][l],
                ];
                v[l] = a[0][l] * bc[0] + a[1][l] * bc[1] + a[2][l] * bc[2];
                let u = [b[0][l] - a[0][l], b[1][l] - a[1][l], b[2][l] - a[2][l]];
                let q = [c[0][l] - a[0][l], c[1][l] - a[1][l], c[2][l] - a[2][l]];
                f[0][l] = u[1] * q[2] - u[2] * q[1];
                f[1][l] = u[2] * q[0] - u[0] * q[2];
                f[2][l] = u[0] * q[1] - u[1] * q[0];
                r[l] = f[0][l] * w[0][l] + f[1][l] * w[1][l] + f[2][l] * w[2][l];
            }
            for l in 0..LANES {
                term[i + l] = v[l];
                sum += v[l];
                face[i + l] = Vector3::new(f[0][l], f[1][l], f[2][l]);
                rate += r[l];
            }
            i += LANES;
            continue;
        }
        if moving[i] {
            let [ia, ib, ic] = tris[i].map(|i| i as usize);
            let (a, b, c) = (&pos[ia].coords, &pos[ib].coords, &pos[ic].coords);
            term[i] = a.dot(&b.cross(c));
            face[i] = (b - a).cross(&(c - a));
            rate += face[i].dot(&(vel[ia] + vel[ib] + vel[ic]));
        }
        sum += term[i];
        i += 1;
    }
    (sum, rate)
}

/// Fills `face` and `term` (laid out as `Data::face` and `Data::term`: abdominal triangles,
/// then thoracic ones) with every triangle's doubled area vector and volume term at `model`'s
/// rest positions: the entries of the triangles fixed to the ground, which the pressure pass
/// reads and never rewrites.
pub(super) fn rest_terms(model: &Structure, face: &mut [Vector3<f64>], term: &mut [f64]) {
    let na = model.abdomen_triangles.len();
    let (abdomen_face, thorax_face) = face.split_at_mut(na);
    let (abdomen_term, thorax_term) = term.split_at_mut(na);
    let rest = &model.rest;
    volume_and_faces(
        rest,
        &model.abdomen_triangles,
        abdomen_face,
        abdomen_term,
        0.0,
    );
    volume_and_faces(rest, &model.thorax_triangles, thorax_face, thorax_term, 0.0);
}

/// Each triangle's doubled area vector (b - a) x (c - a) into `face`.
fn face_vectors(pos: &[Point3<f64>], tris: &[[u32; 3]], face: &mut [Vector3<f64>]) {
    for (t, f) in tris.iter().zip(face.iter_mut()) {
        let (a, b, c) = (pos[t[0] as usize], pos[t[1] as usize], pos[t[2] as usize]);
        *f = (b - a).cross(&(c - a));
    }
}

/// Pushes `pressure` on a closed surface whose face vectors are `face`: each corner
/// receives P/6 (b - a) x (c - a). Triangles that do not move are skipped.
fn apply_pressure(
    tris: &[[u32; 3]],
    moving: &[bool],
    face: &[Vector3<f64>],
    pressure: f64,
    force: &mut [Vector3<f64>],
) {
    if pressure == 0.0 {
        return;
    }
    let scale = pressure / 6.0;
    for ((t, face), &moving) in tris.iter().zip(face).zip(moving) {
        if !moving {
            continue;
        }
        let f = face * scale;
        force[t[0] as usize] += f;
        force[t[1] as usize] += f;
        force[t[2] as usize] += f;
    }
}

/// Abdominal pressure from the current cavity volume (eq. 2.5-2.6).
fn abdominal_pressure(model: &Structure, data: &mut Data) {
    let tris = &model.abdomen_triangles;
    let n = tris.len();
    let Data {
        pos,
        vel,
        face,
        term,
        force,
        ..
    } = data;
    let (face, term) = (&mut face[..n], &mut term[..n]);
    let moving = &model.abdomen_moving;
    let (sum, rate) = volume_faces_and_rate(pos, vel, tris, moving, face, term, (-0.0, 0.0));
    let (v, rate) = (sum / 6.0, rate / 6.0);
    let p = model.params.bulk_modulus * (model.abdomen_rest_volume / v - 1.0)
        - model.abdomen_viscosity * rate;
    apply_pressure(tris, &model.abdomen_moving, face, p, force);
    data.abdomen_volume = v;
    data.abdomen_pressure = p;
}

/// Pleural pressure from the thoracic volume: the pressure at the airway opening less the
/// lungs' elastic recoil, the pressure-volume law of [`super::pleural::PleuralLaw`] (linear
/// with the lung elastance about rest, with inverse barriers at the residual volume and total
/// lung capacity), and less the pressure drop R dV/dt of the airflow through the airway
/// resistance; with the airway occluded, the alveolar pressure of Boyle's law on the lungs'
/// gas instead ([`Structure::alveolar`]). The dome's
/// triangles, reversed copies of abdominal ones, take the abdominal pass's face vectors and
/// volume terms negated (exactly what recomputing them would give).
fn pleural_pressure(model: &Structure, data: &mut Data, act: &Activations) {
    let tris = &model.thorax_triangles;
    let (na, nt) = (model.abdomen_triangles.len(), tris.len());
    let Data {
        pos,
        vel,
        face,
        term,
        force,
        ..
    } = data;
    let (abdomen_face, thorax_face) = face.split_at_mut(na);
    let (abdomen_term, thorax_term) = term.split_at_mut(na);
    let (thorax_face, thorax_term) = (&mut thorax_face[..nt], &mut thorax_term[..nt]);
    let source = &model.thorax_dome_source;
    let moving = &model.thorax_moving[..nt];
    let (sum, rate) = if source.is_empty() {
        volume_faces_and_rate(
            pos,
            vel,
            tris,
            moving,
            thorax_face,
            thorax_term,
            (-0.0, 0.0),
        )
    } else {
        let lining = model.lining_count;
        let (lining_face, dome_face) = thorax_face.split_at_mut(lining);
        let (lining_tris, dome_tris) = tris.split_at(lining);
        let (lining_moving, dome_moving) = moving.split_at(lining);
        let (mut sum, mut rate) = volume_faces_and_rate(
            pos,
            vel,
            lining_tris,
            lining_moving,
            lining_face,
            thorax_term,
            (-0.0, 0.0),
        );
        for ((&i, f), (t, &moving)) in source
            .iter()
            .zip(dome_face.iter_mut())
            .zip(dome_tris.iter().zip(dome_moving))
        {
            let i = i as usize;
            sum += -abdomen_term[i];
            *f = -abdomen_face[i];
            if moving {
                let [a, b, c] = t.map(|i| i as usize);
                rate += f.dot(&(vel[a] + vel[b] + vel[c]));
            }
        }
        (sum, rate)
    };
    let (v, rate) = (sum / 6.0, rate / 6.0);
    let p = model.alveolar(act, v, rate).pressure - model.pleural.recoil(v);
    apply_pressure(tris, &model.thorax_moving, thorax_face, p, force);
    data.thorax_volume = v;
    data.pleural_pressure = p;
}

#[cfg(test)]
mod tests {
    use super::super::{Activations, Data, Model, Params, rest_state, rhs, volume};
    #[cfg(target_arch = "x86_64")]
    use super::elements_avx2;
    use super::{Pass, elements_in_batches, local_forces};
    use crate::anatomy::{Anatomy, Subject};
    use nalgebra::Vector3;

    /// A state away from rest: ribs turned, sternum moved, every free vertex displaced
    /// by a different amount, with velocities.
    fn deformed(model: &Model) -> Vec<f64> {
        let l = model.layout;
        let mut y = rest_state(model);
        for r in 0..super::super::RIBS {
            y[l.theta + r] = 0.02 * ((r as f64) * 0.7).sin();
            y[l.theta_dot + r] = 0.1 * ((r as f64) * 1.3).cos();
        }
        y[l.sternum_x + 1] += 0.003;
        y[l.sternum_v] = 0.01;
        for i in 0..3 * l.vertices {
            y[l.vertex_x + i] += 0.004 * ((i as f64) * 0.37).sin();
            y[l.vertex_v + i] = 0.02 * ((i as f64) * 0.11).cos();
        }
        y
    }

    /// The wall's unloading law: minus its energy's derivative (central differences), linear
    /// outwards, with the slope -k on both sides of the rest, and inwards never pulling more
    /// than the load k lambda the vertex carried at rest.
    #[test]
    fn the_unloading_law_is_its_energys_derivative_and_bounded() {
        use super::{unloading_energy, unloading_force};
        let (k, lambda) = (2.0e3, 5.0e-3);
        for i in 0..=60 {
            let u = -0.05 + 0.001 * i as f64;
            let h = 1e-7;
            let de = (unloading_energy(k, lambda, u + h) - unloading_energy(k, lambda, u - h))
                / (2.0 * h);
            let f = unloading_force(k, lambda, u);
            assert!(
                (f + de).abs() < 1e-6 * k * lambda,
                "u {u}: {f} against {}",
                -de
            );
            assert!(f < k * lambda, "u {u}: {f}");
        }
        let h = 1e-9;
        let slope = |u: f64| {
            (unloading_force(k, lambda, u + h) - unloading_force(k, lambda, u - h)) / (2.0 * h)
        };
        assert!((slope(-2.0 * h) / -k - 1.0).abs() < 1e-5);
        assert!((slope(2.0 * h) / -k - 1.0).abs() < 1e-5);
        assert!((unloading_force(k, lambda, -1.0) / (k * lambda) - 1.0).abs() < 1e-12);
    }

    /// Under the hill law every wall vertex has an unloading length, its rest load over the
    /// foundation's stiffness per area, and the load falls with height by the contents'
    /// hydrostatic gradient (Loring et al. 1994): the lengths are linear in height, with slope
    /// rho g / kappa, wherever they are above the floor. Under the thesis law there are none.
    #[test]
    fn the_walls_unloading_lengths_follow_its_rest_load() {
        use crate::anatomy::Posture;
        use crate::dynamics::Structure;
        use crate::dynamics::muscle::MuscleLaw;
        use crate::dynamics::params::{ABDOMINAL_CONTENTS_DENSITY, WALL_LOAD_FLOOR};
        let anatomy = Anatomy::build(&Subject::default(), 0).unwrap();
        let thesis = Structure::compile(&anatomy, Params::for_posture(Posture::Standing));
        assert!(thesis.springs.unloading.iter().all(|&l| l == 0.0));
        let params = Params::for_posture_and_law(Posture::Standing, MuscleLaw::Hill);
        let s = Structure::compile(&anatomy, params.clone());
        let wall: Vec<usize> = (0..s.springs.a.len())
            .filter(|&i| s.springs.unloading[i] > 0.0)
            .collect();
        assert!(wall.len() > 10, "{} wall springs", wall.len());
        // kappa from the lowest vertex's load (the cited bottom load)
        let height = |i: usize| -s.gravity.dot(&s.rest[s.springs.a[i] as usize].coords);
        let low = *wall
            .iter()
            .min_by(|&&i, &&j| height(i).total_cmp(&height(j)))
            .unwrap();
        let bottom =
            crate::dynamics::params::wall_load_at_lowest(Posture::Standing, params.gravity);
        let kappa = bottom / s.springs.unloading[low];
        let mut checked = 0;
        for &i in &wall {
            let load = bottom - ABDOMINAL_CONTENTS_DENSITY * (height(i) - height(low));
            let expected = load.max(WALL_LOAD_FLOOR) / kappa;
            assert!(
                (s.springs.unloading[i] / expected - 1.0).abs() < 1e-9,
                "spring {i}: {} against {expected} m",
                s.springs.unloading[i]
            );
            checked += usize::from(load > WALL_LOAD_FLOOR);
        }
        assert!(checked > 10, "{checked} above the floor");
        // kappa is the foundation's stiffness per area, A_wall / C_wall, and each spring's
        // stiffness kappa A_v: their sum over kappa^2 is the wall's compliance
        let sum: f64 = wall.iter().map(|&i| s.springs.stiffness[i]).sum();
        let compliance = sum / (kappa * kappa);
        assert!(
            (compliance / params.abdominal_wall_compliance - 1.0).abs() < 1e-9,
            "{compliance} against {} m^3/Pa",
            params.abdominal_wall_compliance
        );
    }

    /// Under the hill law the first rib's cartilage joint, a synchondrosis, keeps the passive
    /// wall's stiffness while the others take the compartments' factor; under the thesis law
    /// all are alike; a negative first-cartilage stiffness is refused by name.
    #[test]
    fn the_first_cartilage_keeps_the_passive_walls_stiffness() {
        use crate::anatomy::Posture;
        use crate::dynamics::muscle::MuscleLaw;
        use crate::dynamics::{HILL_CARTILAGE_FACTOR, Structure};
        let anatomy = Anatomy::build(&Subject::default(), 0).unwrap();
        let hill = Params::for_posture_and_law(Posture::Standing, MuscleLaw::Hill);
        let before = Params::before_compartments(Posture::Standing, MuscleLaw::Hill);
        for (params, first, rest) in [
            (Params::for_posture(Posture::Standing), 1.0e4, 1.0e4),
            (
                hill.clone(),
                before.cartilage_stiffness,
                before.cartilage_stiffness * HILL_CARTILAGE_FACTOR,
            ),
        ] {
            let s = Structure::compile(&anatomy, params);
            assert_eq!(anatomy.joints.len(), 20);
            for (j, k) in anatomy.joints.iter().zip(&s.springs.stiffness) {
                let expected = if j.level == 1 { first } else { rest };
                assert!((k / expected - 1.0).abs() < 1e-12, "level {}: {k}", j.level);
            }
        }
        let mut bad = hill;
        bad.first_cartilage_stiffness = -1.0;
        let err = bad.validate().unwrap_err().to_string();
        assert!(err.contains("first_cartilage_stiffness"), "{err}");
    }

    /// The contents' hydrostatic loads are minus the gradient of their potential
    /// ([`crate::dynamics::energy::hydrostatic_energy`]) at every free vertex of a deformed
    /// abdomen (central differences), standing and supine, and that potential changes by
    /// -rho g . d V when the whole cavity moves by d: the loads add up to the contents' weight.
    #[test]
    fn hydrostatic_loads_are_the_contents_weight() {
        use crate::anatomy::Posture;
        use crate::dynamics::energy::hydrostatic_energy;
        use crate::dynamics::{GravityLoads, Structure, kinematics};
        let anatomy = Anatomy::build(&Subject::default(), 0).unwrap();
        for posture in [Posture::Standing, Posture::Supine] {
            let mut params = Params::for_posture(Posture::Standing);
            params.gravity_loads = GravityLoads::Acting;
            let mut structure = Structure::compile(&anatomy, params);
            structure.turn_gravity(posture);
            let model = Model::new(structure);
            // the same compiled structure (its tissues' rest lengths included) without the
            // contents' weight
            let mut without: Structure = (*model).clone();
            without.contents_density = 0.0;
            let y = deformed(&model);
            let (mut data, mut bare) = (Data::new(&model), Data::new(&without));
            let l = model.layout;
            let act = Activations::default();
            kinematics::positions_and_velocities(&model, &mut data, &l, &y);
            kinematics::positions_and_velocities(&without, &mut bare, &l, &y);
            local_forces(&model, &mut data, &act);
            local_forces(&without, &mut bare, &act);
            let scale = model.contents_density * model.gravity.norm() * 0.1 * 0.01;
            let mut checked = 0;
            for &a in model.vertex_anchor.iter().step_by(7) {
                let a = a as usize;
                let load = data.force[a] - bare.force[a];
                for k in 0..3 {
                    let h = 1e-6;
                    let mut pos = data.pos.clone();
                    pos[a][k] += h;
                    let up = hydrostatic_energy(&model, &pos);
                    pos[a][k] -= 2.0 * h;
                    let down = hydrostatic_energy(&model, &pos);
                    let gradient = (up - down) / (2.0 * h);
                    assert!(
                        (load[k] + gradient).abs() < 1e-6 * scale,
                        "{posture:?}, anchor {a}, axis {k}: load {} against -dE/dx {}",
                        load[k],
                        -gradient
                    );
                }
                checked += 1;
            }
            assert!(checked > 10);
            let d = Vector3::new(0.01, -0.02, 0.005);
            let moved: Vec<_> = data.pos.iter().map(|p| p + d).collect();
            let v = volume(&data.pos, &model.abdomen_triangles);
            let de = hydrostatic_energy(&model, &moved) - hydrostatic_energy(&model, &data.pos);
            let expected = -model.contents_density * model.gravity.dot(&d) * v;
            assert!(
                (de - expected).abs() < 1e-9 * expected.abs().max(1.0),
                "{posture:?}: {de} J against -rho g . d V = {expected} J"
            );
        }
    }

    /// The element loop in batches of four two-point elements (the baseline arrays, and the
    /// AVX2 intrinsics when the CPU has them) gives bit for bit the forces of the elements
    /// computed one at a time, muscles near slack (softplus toe) and via paths included.
    #[test]
    fn batched_elements_match_one_element_at_a_time() {
        for lod in [0, 1] {
            let anatomy = Anatomy::build(&Subject::default(), lod).unwrap();
            let model = Model::compile(&anatomy, Params::for_posture(anatomy.subject.posture));
            let y = deformed(&model);
            let mut dy = vec![0.0; y.len()];
            let mut data = Data::new(&model);
            let act = Activations::new(&[0.3; crate::anatomy::MuscleGroup::COUNT], 1.0, 0.8);
            rhs(&model, &mut data, &act, &y, &mut dy);
            let level = act.table();
            let zero = vec![Vector3::zeros(); data.pos.len()];
            let mut reference = zero.clone();
            let pass = Pass::new(&model, &data.pos, &data.vel, &level);
            for e in 0..model.elements.len() {
                pass.single(e, &mut reference);
            }
            let mut batched = vec![data.clone()];
            batched[0].force.clone_from(&zero);
            elements_in_batches::<false>(&model, &mut batched[0], &act);
            #[cfg(target_arch = "x86_64")]
            if std::arch::is_x86_feature_detected!("avx2") {
                let mut fast = data.clone();
                fast.force.clone_from(&zero);
                // SAFETY: the CPU has AVX2, checked just above.
                unsafe { elements_avx2(&model, &mut fast, &act) };
                batched.push(fast);
            }
            for (variant, b) in batched.iter().enumerate() {
                for (i, (f, r)) in b.force.iter().zip(&reference).enumerate() {
                    for k in 0..3 {
                        assert_eq!(
                            f[k].to_bits(),
                            r[k].to_bits(),
                            "lod {lod}, variant {variant}, anchor {i}, axis {k}: {f:?} vs {r:?}"
                        );
                    }
                }
            }
            assert!(reference.iter().any(|f| f.norm() > 0.0));
        }
    }

    /// A diaphragm element's tissue length differs from its path's rest length (their ratio
    /// s: above 1 where chords cut the dome's curve, below 1 where short segments through via
    /// points carry the path's core); its contraction beta a g s and its stiffness
    /// F / (beta l0 s) still give its maximal force F when fully activated at its rest length
    /// (isometric, thesis eq. 2.2-2.3 with the force at full activation the element's F), and
    /// no force at rest unactivated; the model's rest length times s is the tissue length,
    /// via points' core included. Levels of detail 0 (two-point elements) and 2 (elements
    /// wrapping two edges through a via point).
    #[test]
    fn diaphragm_elements_with_longer_tissue_give_their_force() {
        use crate::anatomy::MuscleGroup;
        for lod in [0, 2] {
            let anatomy = Anatomy::build(&Subject::default(), lod).unwrap();
            let mut params = Params::for_posture(anatomy.subject.posture);
            // a toe far below the forces, so that the tension is the spring's force
            params.tension_toe = 1e-9;
            let model = Model::compile(&anatomy, params);
            let pos: Vec<_> = anatomy.anchors.iter().map(|a| a.rest).collect();
            let vel = vec![Vector3::zeros(); pos.len()];
            let mut groups = [0.0; MuscleGroup::COUNT];
            groups[MuscleGroup::Diaphragm.index()] = 1.0;
            let full = Activations::new(&groups, 1.0, 1.0).table();
            let none = Activations::new(&[0.0; MuscleGroup::COUNT], 1.0, 1.0).table();
            let el = &model.elements;
            let (mut checked, mut via, mut away) = (0, 0, 0);
            for (e, m) in anatomy.muscles.iter().enumerate() {
                if m.group != MuscleGroup::Diaphragm {
                    continue;
                }
                let tissue = m
                    .tissue_length
                    .expect("a diaphragm element's tissue length");
                let l0 = el.rest_length[e];
                let s = tissue / l0;
                away += usize::from((s - 1.0).abs() > 1e-3);
                let beta = model.params.beta_for(m.group);
                assert!(
                    (el.gain[e] - beta * m.gain * s).abs() < 1e-12,
                    "lod {lod}, element {e}: gain {} against beta g s {}",
                    el.gain[e],
                    beta * m.gain * s
                );
                // the tension along the element: its pull on its first anchor, over the
                // share of the first segment's length along it
                let tension = |level: &[f64; 256]| {
                    let mut force = vec![Vector3::zeros(); pos.len()];
                    Pass::new(&model, &pos, &vel, level).single(e, &mut force);
                    let (a, b) = (m.path[0] as usize, m.path[1] as usize);
                    let d = pos[b] - pos[a];
                    let along = if m.path.len() == 2 {
                        1.0
                    } else {
                        d.norm() / super::via_segment_length(&d)
                    };
                    force[a].norm() / along
                };
                let f_full = tension(&full);
                assert!(
                    (f_full - m.max_force * m.gain).abs() < 1e-9 * m.max_force,
                    "lod {lod}, element {e} (s = {s}): {f_full} N at full activation, F = {} N",
                    m.max_force
                );
                let f_rest = tension(&none);
                assert!(
                    f_rest < 1e-8,
                    "lod {lod}, element {e}: {f_rest} N at rest unactivated"
                );
                checked += 1;
                via += usize::from(m.path.len() > 2);
            }
            assert!(checked > 0, "lod {lod}: no diaphragm elements");
            assert!(
                away > 0,
                "lod {lod}: no diaphragm element with s away from 1"
            );
            if lod == 2 {
                assert!(via > 0, "level 2 has diaphragm elements through via points");
            }
        }
    }

    /// The pressure pass (fused volume and face vectors, thoracic dome reused from the
    /// abdomen, triangles fixed to the ground skipped) gives exactly the volumes of
    /// `dynamics::volume` and the forces of the plain per-triangle formula on every anchor
    /// that moves.
    #[test]
    fn pressure_pass_matches_the_plain_formulas() {
        for lod in [0, 1] {
            let anatomy = Anatomy::build(&Subject::default(), lod).unwrap();
            let model = Model::compile(&anatomy, Params::for_posture(anatomy.subject.posture));
            assert!(
                !model.thorax_dome_source.is_empty(),
                "the thoracic dome is laid out as the reversed abdominal dome"
            );
            let y = deformed(&model);
            let mut dy = vec![0.0; y.len()];
            let mut data = Data::new(&model);
            let act = Activations::new(&[0.3; crate::anatomy::MuscleGroup::COUNT], 1.0, 0.8);
            rhs(&model, &mut data, &act, &y, &mut dy);
            let va = volume(&data.pos, &model.abdomen_triangles);
            let vt = volume(&data.pos, &model.thorax_triangles);
            assert_eq!(data.abdomen_volume.to_bits(), va.to_bits());
            assert_eq!(data.thorax_volume.to_bits(), vt.to_bits());
            assert!(data.abdomen_pressure != 0.0 && data.pleural_pressure != 0.0);

            // forces without the pressures, then the pressures added triangle by triangle
            let mut plain = data.clone();
            local_forces(&model, &mut plain, &act);
            for (tris, p) in [
                (&model.abdomen_triangles, data.abdomen_pressure),
                (&model.thorax_triangles, data.pleural_pressure),
            ] {
                for t in tris.iter() {
                    let [a, b, c] = t.map(|i| plain.pos[i as usize]);
                    let f: Vector3<f64> = (b - a).cross(&(c - a)) * (p / 6.0);
                    for &i in t {
                        plain.force[i as usize] += f;
                    }
                }
            }
            let mut moving = 0;
            for (i, carrier) in model.carrier.iter().enumerate() {
                if *carrier == super::super::Carrier::Ground {
                    continue;
                }
                moving += 1;
                let (fast, reference) = (data.force[i], plain.force[i]);
                for k in 0..3 {
                    assert_eq!(
                        fast[k].to_bits(),
                        reference[k].to_bits(),
                        "lod {lod}, anchor {i}, axis {k}: {fast:?} vs {reference:?}"
                    );
                }
            }
            assert!(moving > 100);
        }
    }
}
