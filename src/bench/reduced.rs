//! A reduced basis for the quasi-static mechanics, measured (docs/dynamics.md, "Quasi-static
//! mechanics"): can the positions of ribs, sternum and abdominal vertices be solved on a few
//! tens of modes instead of all 1,287 unknowns (level of detail 1), how accurate are they, and
//! what does a solve then cost?
//!
//! The modes are the leading left singular vectors (proper orthogonal decomposition) of
//! equilibria taken from a run with another drive than the one tested on: the training run
//! breathes with the forced drive, the test with the quiet one, so a basis that only
//! reproduces its own snapshots is not mistaken for one that spans the drive's range.
//! Rotations are scaled by the statics' lever (0.2 m) so that every coordinate of a mode is
//! a displacement. On the modes, z = z_ref + Phi c, each solve is Newton's method on the
//! Galerkin-projected bordered system
//!
//! ```text
//! [ Phi^T J Phi   Phi^T u_T ] [dc]   [ -Phi^T R ]
//! [ u_T^T Phi     0         ] [dP] = [ -c_V     ],
//! ```
//!
//! the reduced Jacobian by forward differences along the modes (one residual per mode),
//! kept while the iterations contract (modified Newton), warm-started from the last frame.
//! The residual is still the full one (no hyper-reduction), so the figures bound what the
//! modes alone buy; the full solver ([`Statics`]) on the same frames gives the reference
//! positions and pleural pressures and its own cost, in the same run.

use crate::dynamics::statics::{LEVER, Statics, apply, pressures_and_residual, volume_of};
use crate::dynamics::{Activations, Data, Layout, Model, RIBS, kinematics};
use crate::model::{Config, Drive, Torso};
use crate::solver::Method;
use crate::{Error, Result};
use nalgebra::{DMatrix, DVector, Quaternion, UnitQuaternion, Vector3};
use serde::Serialize;
use std::time::Instant;

/// One frame of a quasi-static run: its time, activations and solved state.
struct Frame {
    time: f64,
    act: Activations,
    state: Vec<f64>,
}

/// Accuracy and cost of the reduced solves with one number of modes.
#[derive(Clone, Debug, Serialize)]
pub struct ReducedRow {
    /// Modes kept.
    pub modes: usize,
    /// Share of the training snapshots' energy (squared singular values) the modes hold.
    pub energy: f64,
    /// Largest distance between an anchor (rib, sternum or wall point) of the reduced and of
    /// the full equilibrium over the test frames [mm].
    pub max_position_error_mm: f64,
    /// The same, the best the modes can do: the full equilibrium projected on them [mm].
    pub max_projection_error_mm: f64,
    /// Largest pleural-pressure difference from the full solve [Pa].
    pub max_pleural_error_pa: f64,
    /// That difference as an airflow error, over the airway resistance [L/s].
    pub max_flow_error_l_s: f64,
    /// Largest full residual left at the reduced equilibrium, as a force on one unknown [N
    /// or N m].
    pub max_full_residual: f64,
    /// Reduced solves that did not converge (kept at their last iterate).
    pub failures: usize,
    /// Newton iterations per solve.
    pub iterations_per_solve: f64,
    /// Full residual evaluations per solve (iterations and reduced Jacobians).
    pub residuals_per_solve: f64,
    /// Wall time per reduced solve [us].
    pub us_per_solve: f64,
}

/// The measurement: the full solver's cost on the same frames and one row per mode count.
#[derive(Clone, Debug, Serialize)]
pub struct ReducedReport {
    /// Level of detail.
    pub lod: u32,
    /// Unknowns of the full static problem.
    pub unknowns: usize,
    /// Training snapshots (forced drive).
    pub snapshots: usize,
    /// Test frames (quiet drive).
    pub frames: usize,
    /// Wall time per full solve on the test frames, warm-started from the frame before [us].
    pub full_us_per_solve: f64,
    /// Newton iterations per full solve.
    pub full_iterations_per_solve: f64,
    /// Wall time of one full residual evaluation (median of the reduced runs' mean) [us].
    pub us_per_residual: f64,
    /// One row per mode count.
    pub rows: Vec<ReducedRow>,
}

/// `frames` frames at `rate` Hz of a quasi-static run of `drive` at level `lod`, every
/// `stride`-th kept.
fn run(lod: u32, drive: Drive, frames: usize, stride: usize, rate: f64) -> Result<Vec<Frame>> {
    let mut config = Config::default();
    config.scene.level_of_detail = lod;
    config.solver.method = Method::QuasiStatic;
    config.drive = drive;
    let mut torso = Torso::new(config)?;
    let mut out = Vec::new();
    for k in 1..=frames {
        let t = k as f64 / rate;
        torso.advance_to(t)?;
        if k % stride == 0 {
            let state = torso.current_state().to_vec();
            out.push(Frame {
                time: t,
                act: torso.applied(t),
                state,
            });
        }
    }
    Ok(out)
}

/// The increment dz that takes `reference` to `y` ([`apply`]'s inverse), rotations scaled by
/// `scale` (1 for unknowns, [`LEVER`] for displacements).
fn difference(l: &Layout, y: &[f64], reference: &[f64], scale: f64, dz: &mut [f64]) {
    for r in 0..RIBS {
        dz[r] = (y[l.theta + r] - reference[l.theta + r]) * scale;
    }
    for k in 0..3 {
        dz[RIBS + k] = y[l.sternum_x + k] - reference[l.sternum_x + k];
    }
    let quat = |v: &[f64]| {
        UnitQuaternion::from_quaternion(Quaternion::new(
            v[l.sternum_q],
            v[l.sternum_q + 1],
            v[l.sternum_q + 2],
            v[l.sternum_q + 3],
        ))
    };
    let phi: Vector3<f64> = (quat(y) * quat(reference).inverse()).scaled_axis();
    for k in 0..3 {
        dz[RIBS + 3 + k] = phi[k] * scale;
    }
    let n = 3 * l.vertices;
    for i in 0..n {
        dz[RIBS + 6 + i] = y[l.vertex_x + i] - reference[l.vertex_x + i];
    }
}

/// Unscales rotations of a displacement-scaled increment in place.
fn unscale(dz: &mut [f64]) {
    for v in dz[..RIBS].iter_mut() {
        *v /= LEVER;
    }
    for v in dz[RIBS + 3..RIBS + 6].iter_mut() {
        *v /= LEVER;
    }
}

/// Anchor positions of state `y` (flattened) into `out`.
fn anchors(model: &Model, data: &mut Data, l: &Layout, y: &[f64], out: &mut Vec<[f64; 3]>) {
    kinematics::positions_and_velocities(model, data, l, y);
    out.clear();
    out.extend(data.pos.iter().map(|p| [p.x, p.y, p.z]));
}

fn largest_distance(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(p, q)| {
            ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt()
        })
        .fold(0.0, f64::max)
}

/// The reduced problem: modes (in unknowns, rotations unscaled) about a reference state.
struct Reduced<'a> {
    model: &'a Model,
    l: Layout,
    reference: Vec<f64>,
    /// n x m, columns the modes in unknowns.
    phi: DMatrix<f64>,
    data: Data,
    y: Vec<f64>,
    dy: Vec<f64>,
    residuals: usize,
}

impl Reduced<'_> {
    /// y = reference + Phi c.
    fn state(&mut self, c: &DVector<f64>) {
        let dz = &self.phi * c;
        self.y.copy_from_slice(&self.reference);
        apply(&self.l, &mut self.y, dz.as_slice());
    }

    /// The full residual at c with pleural pressure p (into `out`); returns V_T.
    fn residual(
        &mut self,
        c: &DVector<f64>,
        act: &Activations,
        p: f64,
        out: &mut DVector<f64>,
    ) -> f64 {
        self.state(c);
        let (_, vt) = pressures_and_residual(
            self.model,
            &mut self.data,
            &self.l,
            act,
            &self.y,
            None,
            p,
            &mut self.dy,
        );
        self.residuals += 1;
        out.copy_from_slice(&self.dy[self.l.theta_dot..]);
        vt
    }
}

/// Solves the reduced equilibrium at `act` holding thoracic volume `target` from (c, p);
/// `kept` is the factored reduced bordered matrix, refreshed when the iterations contract
/// slowly. Returns the iterations, or None when they did not converge.
#[allow(clippy::too_many_arguments)]
fn reduced_solve(
    r: &mut Reduced,
    act: &Activations,
    target: f64,
    tol: f64,
    c: &mut DVector<f64>,
    p: &mut f64,
    kept: &mut Option<nalgebra::LU<f64, nalgebra::Dyn, nalgebra::Dyn>>,
) -> Option<usize> {
    let m = r.phi.ncols();
    let n = r.phi.nrows();
    let mut res = DVector::zeros(n);
    let mut res2 = DVector::zeros(n);
    let mut prev = f64::INFINITY;
    let mut fresh = false;
    for it in 1..=16 {
        let vt = r.residual(c, act, *p, &mut res);
        if kept.is_none() {
            // reduced Jacobian along the modes, u_T from a unit pleural pressure
            let mut a = DMatrix::zeros(m + 1, m + 1);
            r.residual(c, act, *p + 1.0, &mut res2);
            let ut = &res2 - &res;
            let ur = r.phi.transpose() * &ut;
            for k in 0..m {
                let eps = 1e-7 * (1.0 + c[k].abs());
                let mut ck = c.clone();
                ck[k] += eps;
                r.residual(&ck, act, *p, &mut res2);
                let col = r.phi.transpose() * ((&res2 - &res) / eps);
                a.view_mut((0, k), (m, 1)).copy_from(&col);
            }
            a.view_mut((0, m), (m, 1)).copy_from(&ur);
            a.view_mut((m, 0), (1, m)).copy_from(&ur.transpose());
            *kept = Some(a.lu());
            fresh = true;
        }
        let mut rhs = DVector::zeros(m + 1);
        rhs.rows_mut(0, m).copy_from(&(-(r.phi.transpose() * &res)));
        rhs[m] = -(vt - target);
        let step = kept.as_ref().and_then(|lu| lu.solve(&rhs))?;
        let dc = step.rows(0, m).into_owned();
        let mut dz = (&r.phi * &dc).data.as_vec().clone();
        // convergence on the largest displacement (rotations times the lever)
        for i in (0..RIBS).chain(RIBS + 3..RIBS + 6) {
            dz[i] *= LEVER;
        }
        let size = dz.iter().fold(0.0f64, |s, v| s.max(v.abs()));
        *c += &dc;
        *p += step[m];
        let theta = size / prev;
        if size <= tol || (prev.is_finite() && theta < 1.0 && theta / (1.0 - theta) * size <= tol) {
            return Some(it);
        }
        if prev.is_finite() && theta > 0.5 && !fresh {
            *kept = None;
            prev = f64::INFINITY;
            continue;
        }
        prev = size;
    }
    None
}

/// Trains on `train_frames` frames of the forced drive (every `stride`-th a snapshot), tests
/// on `test_frames` frames of the quiet drive at 56 Hz, at level `lod`, for each number of
/// `modes`, with the displacement tolerance `tol` [m].
pub fn measure(
    lod: u32,
    training: Drive,
    modes: &[usize],
    train_frames: usize,
    stride: usize,
    test_frames: usize,
    tol: f64,
) -> Result<ReducedReport> {
    const RATE: f64 = 56.0;
    let train = run(lod, training, train_frames, stride, RATE)?;
    let test = run(lod, Drive::quiet(), test_frames, 1, RATE)?;
    let mut config = Config::default();
    config.scene.level_of_detail = lod;
    config.drive = Drive::quiet();
    let torso = Torso::new(config)?;
    let model = &torso.compiled().model;
    let l = model.layout;
    let n = RIBS + 6 + 3 * l.vertices;
    let reference = test
        .first()
        .ok_or_else(|| Error::State("no test frames".into()))?
        .state
        .clone();

    // snapshots in displacements, their singular vectors
    let mut x = DMatrix::zeros(n, train.len());
    let mut dz = vec![0.0; n];
    for (j, f) in train.iter().enumerate() {
        difference(&l, &f.state, &reference, LEVER, &mut dz);
        x.column_mut(j).copy_from_slice(&dz);
    }
    let svd = x.svd(true, false);
    let u = svd
        .u
        .ok_or_else(|| Error::State("no singular vectors".into()))?;
    let mut order: Vec<usize> = (0..svd.singular_values.len()).collect();
    order.sort_by(|&a, &b| svd.singular_values[b].total_cmp(&svd.singular_values[a]));
    let total: f64 = svd.singular_values.iter().map(|s| s * s).sum();

    // the full solver on the test frames: reference solutions and its cost
    let mut data = Data::new(model);
    let first = &test[0];
    let mut statics = Statics::new(model, &first.state, &first.act);
    // the first frame is where both solvers start (its pleural pressure unknown to them)
    let test = &test[1..];
    let mut full = Vec::with_capacity(test.len());
    let before = statics.stats;
    let clock = Instant::now();
    for f in test {
        let target = volume_of(model, &f.state);
        let p = statics
            .solve(model, &mut data, f.time, &f.act, target, tol)
            .map_err(|e| Error::State(format!("full solve at {} s: {e}", f.time)))?;
        full.push((statics.state().to_vec(), p, target));
    }
    let full_seconds = clock.elapsed().as_secs_f64();
    let after = statics.stats;
    let solves = test.len() as f64;

    let mut full_anchors = Vec::with_capacity(test.len());
    for (y, _, _) in &full {
        let mut a = Vec::new();
        anchors(model, &mut data, &l, y, &mut a);
        full_anchors.push(a);
    }

    let mut rows = Vec::new();
    let mut per_residual = Vec::new();
    for &m in modes {
        let m = m.min(order.len());
        let mut phi = DMatrix::zeros(n, m);
        for (k, &j) in order.iter().take(m).enumerate() {
            let mut col: Vec<f64> = u.column(j).iter().copied().collect();
            unscale(&mut col);
            phi.column_mut(k).copy_from_slice(&col);
        }
        let energy = order
            .iter()
            .take(m)
            .map(|&j| svd.singular_values[j].powi(2))
            .sum::<f64>()
            / total;
        let mut r = Reduced {
            model,
            l,
            reference: reference.clone(),
            phi,
            data: Data::new(model),
            y: reference.clone(),
            dy: vec![0.0; l.len],
            residuals: 0,
        };
        // best approximation: the full solution projected on the (scaled) modes
        let mut projection = 0.0f64;
        let mut scaled = DMatrix::zeros(n, m);
        for (k, &j) in order.iter().take(m).enumerate() {
            scaled.column_mut(k).copy_from(&u.column(j));
        }
        let mut pa = Vec::new();
        for ((y, _, _), fa) in full.iter().zip(&full_anchors) {
            difference(&l, y, &reference, LEVER, &mut dz);
            let coeff = scaled.transpose() * DVector::from_column_slice(&dz);
            let mut best = (&scaled * coeff).data.as_vec().clone();
            unscale(&mut best);
            let mut yb = reference.clone();
            apply(&l, &mut yb, &best);
            anchors(model, &mut data, &l, &yb, &mut pa);
            projection = projection.max(largest_distance(&pa, fa));
        }
        // from the first frame (c = 0), pleural pressure unknown; then each frame from the
        // last two extrapolated linearly
        let mut c = DVector::zeros(m);
        let mut p = 0.0;
        let mut last: Option<(DVector<f64>, f64)> = None;
        let mut kept = None;
        let (mut iterations, mut failures) = (0usize, 0usize);
        let (mut pos_err, mut p_err, mut res_max) = (0.0f64, 0.0f64, 0.0f64);
        let mut res = DVector::zeros(n);
        let mut elapsed = 0.0;
        let mut ra = Vec::new();
        for (f, ((_, pf, target), fa)) in test.iter().zip(full.iter().zip(&full_anchors)) {
            let clock = Instant::now();
            let now = (c.clone(), p);
            if let Some((c0, p0)) = &last {
                c = &c * 2.0 - c0;
                p = 2.0 * p - p0;
            }
            last = Some(now);
            match reduced_solve(&mut r, &f.act, *target, tol, &mut c, &mut p, &mut kept) {
                Some(k) => iterations += k,
                None => {
                    failures += 1;
                    kept = None;
                }
            }
            elapsed += clock.elapsed().as_secs_f64();
            let counted = r.residuals;
            r.residual(&c, &f.act, p, &mut res);
            r.residuals = counted;
            res_max = res_max.max(res.amax());
            r.state(&c);
            let y = r.y.clone();
            anchors(model, &mut data, &l, &y, &mut ra);
            pos_err = pos_err.max(largest_distance(&ra, fa));
            p_err = p_err.max((p - pf).abs());
        }
        let frames = test.len() as f64;
        // time per residual: a separate timed batch at the last state
        let clock = Instant::now();
        let batch = 50;
        let counted = r.residuals;
        for _ in 0..batch {
            r.residual(&c, &test[test.len() - 1].act, p, &mut res);
        }
        per_residual.push(clock.elapsed().as_secs_f64() / batch as f64 * 1e6);
        r.residuals = counted;
        rows.push(ReducedRow {
            modes: m,
            energy,
            max_position_error_mm: pos_err * 1e3,
            max_projection_error_mm: projection * 1e3,
            max_pleural_error_pa: p_err,
            max_flow_error_l_s: p_err / model.airway_resistance * 1e3,
            max_full_residual: res_max,
            failures,
            iterations_per_solve: iterations as f64 / frames,
            residuals_per_solve: r.residuals as f64 / frames,
            us_per_solve: elapsed / frames * 1e6,
        });
    }
    Ok(ReducedReport {
        lod,
        unknowns: n,
        snapshots: train.len(),
        frames: test.len(),
        full_us_per_solve: full_seconds / solves * 1e6,
        full_iterations_per_solve: (after.iterations - before.iterations) as f64 / solves,
        us_per_residual: crate::bench::median(&per_residual),
        rows,
    })
}
