//! The stiff method: ROS34PW2, a linearly implicit Rosenbrock-W method of order 3 with an
//! embedded method of order 2, four stages, stiffly accurate and L-stable (J. Rang &
//! L. Angermann, "New Rosenbrock W-methods of order 3 for partial differential algebraic
//! equations of index 1", BIT 45 (2005) 761-787, Table "ROS34PW2"). Being a W-method it keeps
//! its order with any matrix in place of the Jacobian, so the Jacobian is evaluated rarely
//! and a factorisation is reused while the step size changes little.
//!
//! Each stage solves (I/(hγ) - J) u_i = f(t + α_i h, y + Σ a_ij u_j) + Σ c_ij u_j / h +
//! γ_i h f_t in the transformed variables of Hairer & Wanner, *Solving ODEs II*, Sec. IV.7
//! (eq. 7.4'): a = α Γ^{-1}, c = diag(1/γ) - Γ^{-1}, m = b Γ^{-1}; y1 = y + Σ m_i u_i.
//! The Jacobian comes from the problem ([`StiffOde`]: sparse part plus low-rank part) or, for
//! a plain [`Ode`], from dense finite differences. The time derivative f_t is a forward
//! difference. Step control is the PI controller of the explicit integrator on the
//! difference of the two solutions; dense output is the cubic Hermite interpolant of
//! (y0, f0) and (y1, f1), f1 being the next step's first stage.

// Index loops mirror the formulas (stage and row indices) in this numerical kernel.
#![allow(clippy::needless_range_loop)]

use serde::{Deserialize, Serialize};

use super::control::{Chain, Controller, ERR_OLD_MIN};
use super::norm;
use super::sparse::{Jacobian, Pattern, ShiftedSolver};
use super::{Ode, Options, SolverError, Stats, StiffOde};

/// Diagonal γ of ROS34PW2.
const GAMMA: f64 = 4.358_665_215_084_59e-1;
/// α_ij (strictly lower triangular), Rang & Angermann (2005).
const ALPHA: [[f64; 4]; 4] = [
    [0.0; 4],
    [8.717_330_430_169_18e-1, 0.0, 0.0, 0.0],
    [
        8.445_706_001_536_942e-1,
        -1.129_906_423_648_418_5e-1,
        0.0,
        0.0,
    ],
    [0.0, 0.0, 1.0, 0.0],
];
/// γ_ij (lower triangular, diagonal γ).
const GAMMA_IJ: [[f64; 4]; 4] = [
    [GAMMA, 0.0, 0.0, 0.0],
    [-8.717_330_430_169_18e-1, GAMMA, 0.0, 0.0],
    [
        -9.033_805_701_304_408e-1,
        5.418_067_238_809_533e-2,
        GAMMA,
        0.0,
    ],
    [
        2.421_238_070_609_534_6e-1,
        -1.223_250_583_904_514_7,
        5.452_602_553_351_021e-1,
        GAMMA,
    ],
];
/// Weights of the third-order solution.
const B: [f64; 4] = [
    2.421_238_070_609_534_6e-1,
    -1.223_250_583_904_514_7,
    1.545_260_255_335_102,
    GAMMA,
];
/// Weights of the embedded second-order solution.
const B_HAT: [f64; 4] = [
    3.781_090_314_581_937e-1,
    -9.604_229_221_242_318e-2,
    0.5,
    2.179_332_607_542_295e-1,
];

/// Safety factor of the step-size controller.
const SAFETY: f64 = 0.9;
/// Step-size ratio limits.
const FAC_MIN: f64 = 0.2;
const FAC_MAX: f64 = 6.0;
/// PI exponents for an error estimate of order 3 (Gustafsson 1991: 0.7/k, 0.4/k).
const PI_ALPHA: f64 = 0.7 / 3.0;
const PI_BETA: f64 = 0.4 / 3.0;
/// A factorisation is reused while h / h_factored stays in this band (a W-method tolerates
/// the implied scaling of the Jacobian).
const REUSE_BAND: (f64, f64) = (0.8, 1.25);
/// A proposed step increase below this ratio is not taken, so that the factorisation
/// can be reused.
const HOLD_RATIO: f64 = 1.2;
/// The Jacobian is re-evaluated after this many accepted steps.
const JACOBIAN_MAX_AGE: u32 = 40;
/// A rejection re-evaluates the Jacobian when it is at least this many accepted steps old,
/// or on the second rejection in a row (a W-method keeps its order with a stale matrix; a
/// rejection of a step with a young one is most likely the step size's, which the controller
/// corrects).
const JACOBIAN_STALE_AGE: u32 = 3;

/// Transformed coefficients (Hairer & Wanner IV.7): a, c, m, m - m̂, α_i, γ_i.
#[derive(Clone, Copy, Debug)]
struct Coefficients {
    a: [[f64; 4]; 4],
    c: [[f64; 4]; 4],
    m: [f64; 4],
    e: [f64; 4],
    alpha: [f64; 4],
    gamma: [f64; 4],
}

/// Inverse of a lower triangular 4 x 4 matrix.
fn lower_inverse(g: &[[f64; 4]; 4]) -> [[f64; 4]; 4] {
    let mut inv = [[0.0; 4]; 4];
    for j in 0..4 {
        inv[j][j] = 1.0 / g[j][j];
        for i in j + 1..4 {
            let s: f64 = (j..i).map(|k| g[i][k] * inv[k][j]).sum();
            inv[i][j] = -s / g[i][i];
        }
    }
    inv
}

fn coefficients() -> Coefficients {
    let gi = lower_inverse(&GAMMA_IJ);
    let mut k = Coefficients {
        a: [[0.0; 4]; 4],
        c: [[0.0; 4]; 4],
        m: [0.0; 4],
        e: [0.0; 4],
        alpha: [0.0; 4],
        gamma: [0.0; 4],
    };
    for i in 0..4 {
        for j in 0..4 {
            k.a[i][j] = (0..4).map(|l| ALPHA[i][l] * gi[l][j]).sum();
            k.c[i][j] = if i == j { 0.0 } else { -gi[i][j] };
        }
        k.alpha[i] = ALPHA[i].iter().sum();
        k.gamma[i] = GAMMA_IJ[i].iter().sum();
        k.m[i] = (0..4).map(|l| B[l] * gi[l][i]).sum();
        let m_hat: f64 = (0..4).map(|l| B_HAT[l] * gi[l][i]).sum();
        k.e[i] = k.m[i] - m_hat;
    }
    k
}

/// Working memory and the Jacobian cache (rebuilt on first use; not serialised: after a
/// restore the Jacobian is evaluated afresh at the restored state).
#[derive(Clone, Debug, Default)]
struct Work {
    ready: bool,
    jac: Jacobian,
    groups: Vec<u32>,
    solver: ShiftedSolver,
    has_jac: bool,
    /// The Jacobian was evaluated at the current point and no step was taken since.
    jac_fresh: bool,
    jac_age: u32,
    /// Stage increments u_0..u_3, n each.
    u: Vec<f64>,
    ytmp: Vec<f64>,
    ynew: Vec<f64>,
    fstage: Vec<f64>,
    ft: Vec<f64>,
    f1: Vec<f64>,
    yout: Vec<f64>,
    yold: Vec<f64>,
    fold: Vec<f64>,
    floor: Vec<f64>,
    fd_y: Vec<f64>,
    fd_f: Vec<f64>,
}

/// The Rosenbrock-W integrator's memory (serialisable: step size, controller memory, first
/// stage f(t, y) at the current point, statistics).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub(super) struct Rosenbrock {
    pub(super) options: Options,
    dim: usize,
    pub(super) h_next: f64,
    err_old: f64,
    f0_valid: bool,
    f0_t: f64,
    f0_y: Vec<f64>,
    f0: Vec<f64>,
    pub(super) stats: Stats,
    /// Size of the last step attempted (that of the last accepted one once `run` returns).
    #[serde(skip)]
    last_h: f64,
    #[serde(skip)]
    work: Work,
}

enum Attempt {
    Error(f64),
    NonFinite,
    Singular,
}

impl Rosenbrock {
    pub(super) fn new(options: Options, dim: usize) -> Rosenbrock {
        Rosenbrock {
            options,
            dim,
            h_next: 0.0,
            err_old: ERR_OLD_MIN,
            f0_valid: false,
            f0_t: 0.0,
            f0_y: vec![0.0; dim],
            f0: vec![0.0; dim],
            stats: Stats::default(),
            last_h: 0.0,
            work: Work::default(),
        }
    }

    /// A copy of the memory a snapshot keeps, without the workspace (Jacobian, factors).
    pub(super) fn memory(&self) -> Rosenbrock {
        Rosenbrock {
            options: self.options,
            dim: self.dim,
            h_next: self.h_next,
            err_old: self.err_old,
            f0_valid: self.f0_valid,
            f0_t: self.f0_t,
            f0_y: self.f0_y.clone(),
            f0: self.f0.clone(),
            stats: self.stats,
            last_h: 0.0,
            work: Work::default(),
        }
    }

    /// Takes over the memory of `src` and drops the Jacobian and its factors, as a restore
    /// from a snapshot does (the next step evaluates them afresh).
    pub(super) fn copy_memory_from(&mut self, src: &Rosenbrock) {
        if self.dim != src.dim {
            *self = src.memory();
            return;
        }
        self.options = src.options;
        self.h_next = src.h_next;
        self.err_old = src.err_old;
        self.f0_valid = src.f0_valid;
        self.f0_t = src.f0_t;
        self.f0_y.clone_from(&src.f0_y);
        self.f0.clone_from(&src.f0);
        self.stats = src.stats;
        self.work = Work::default();
    }

    /// The last accepted step of [`Rosenbrock::run`]: its size, start state and slopes
    /// f(t0, y0), f(t0 + h, y1) (y1 is the state `run` ended with), for [`hermite`].
    pub(super) fn last_step(&self) -> (f64, &[f64], &[f64], &[f64]) {
        (self.last_h, &self.work.yold, &self.work.fold, &self.f0)
    }

    pub(super) fn invalidate(&mut self) {
        self.f0_valid = false;
        self.work.jac_fresh = false;
    }

    pub(super) fn reset(&mut self) {
        self.h_next = 0.0;
        self.err_old = ERR_OLD_MIN;
        self.f0_valid = false;
        self.stats = Stats::default();
        self.work.has_jac = false;
        self.work.solver.clear();
    }

    fn ensure_workspace<O: Ode + ?Sized>(&mut self, ode: &mut O) {
        if self.work.ready {
            return;
        }
        let n = self.dim;
        let (pattern, groups, rank) = match ode.as_stiff() {
            Some(s) => {
                let st = s.jacobian_structure();
                (st.pattern, st.groups, st.rank)
            }
            None => (Pattern::dense(n), vec![0; n], 0),
        };
        let w = &mut self.work;
        w.solver = ShiftedSolver::new(&pattern, &groups);
        w.jac = Jacobian::zeros(pattern, rank);
        w.groups = groups;
        for buf in [
            &mut w.ytmp,
            &mut w.ynew,
            &mut w.fstage,
            &mut w.ft,
            &mut w.f1,
            &mut w.yout,
            &mut w.yold,
            &mut w.fold,
            &mut w.fd_y,
            &mut w.fd_f,
        ] {
            *buf = vec![0.0; n];
        }
        w.floor = vec![1e-3; n];
        w.u = vec![0.0; 4 * n];
        w.has_jac = false;
        w.ready = true;
    }

    fn ensure_f0<O: Ode + ?Sized>(&mut self, ode: &mut O, t: f64, y: &[f64]) -> bool {
        if self.f0_valid && self.f0_t == t && self.f0_y.as_slice() == y {
            return true;
        }
        ode.rhs(t, y, &mut self.f0);
        self.stats.rhs_evaluations += 1;
        if self.f0.iter().any(|v| !v.is_finite()) {
            self.f0.fill(0.0);
            self.f0_valid = false;
            return false;
        }
        self.f0_t = t;
        self.f0_y.copy_from_slice(y);
        self.f0_valid = true;
        true
    }

    /// Evaluates the Jacobian at (t, y) (f0 = f(t, y) valid).
    fn evaluate_jacobian<O: Ode + ?Sized>(&mut self, ode: &mut O, t: f64, y: &[f64]) {
        let w = &mut self.work;
        let evals = match ode.as_stiff() {
            Some(s) => s.jacobian(t, y, &self.f0, &mut w.jac),
            None => dense_differences(ode, t, y, &self.f0, w),
        };
        self.stats.rhs_evaluations += evals;
        self.stats.jacobian_evaluations += 1;
        w.has_jac = true;
        w.jac_fresh = true;
        w.jac_age = 0;
        w.solver.clear();
    }

    /// Accepted steps from `(t, y)` to `t_end`: the last one shortened to land on it, or,
    /// with `past`, not shortened (the integration ends at the first step end at or past
    /// `t_end`, whose step [`Rosenbrock::last_step`] gives for the dense output).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn run<O: Ode + ?Sized>(
        &mut self,
        ode: &mut O,
        t: &mut f64,
        y: &mut [f64],
        t_end: f64,
        past: bool,
        output_times: &[f64],
        callback: &mut dyn FnMut(f64, &[f64]),
    ) -> Result<(), SolverError> {
        if t_end == *t {
            return Ok(());
        }
        self.ensure_workspace(ode);
        if !self.ensure_f0(ode, *t, y) {
            return Err(SolverError::NonFinite { t: *t });
        }
        let mut next_out = output_times.partition_point(|&v| v <= *t);
        let opts = self.options;
        if self.h_next <= 0.0 || !self.h_next.is_finite() {
            self.h_next = match opts.h_init {
                Some(h) => h,
                None => self.initial_step(*t, y, t_end, ode.error_weights()),
            };
        }
        let k = coefficients();
        let ctl = Controller {
            safety: SAFETY,
            fac_min: FAC_MIN,
            fac_max: FAC_MAX,
            alpha: PI_ALPHA,
            beta: PI_BETA,
            hold_ratio: HOLD_RATIO,
        };
        let mut chain = Chain::new(self.h_next);
        let mut rejections_in_row = 0u32;
        while *t < t_end {
            let horizon = if past { f64::INFINITY } else { t_end };
            let p = chain.plan(&mut self.h_next, *t, horizon, &opts)?;
            let h = p.h;
            self.last_h = h;
            if !self.work.has_jac || self.work.jac_age >= JACOBIAN_MAX_AGE {
                self.evaluate_jacobian(ode, *t, y);
            }
            match self.attempt(ode, &k, *t, y, h) {
                Attempt::Error(err) if err <= 1.0 => {
                    let t_new = if p.clipped { t_end } else { *t + h };
                    // f(t_new, y1): the next step's first stage and the dense output's slope
                    let w = &mut self.work;
                    ode.rhs(t_new, &w.ynew, &mut w.f1);
                    self.stats.rhs_evaluations += 1;
                    if w.f1.iter().any(|v| !v.is_finite()) {
                        return Err(chain.fail_non_finite(&mut self.h_next, *t));
                    }
                    w.yold.copy_from_slice(y);
                    w.fold.copy_from_slice(&self.f0);
                    while next_out < output_times.len() && output_times[next_out] <= t_new {
                        let tau = output_times[next_out];
                        if tau >= t_new {
                            callback(tau, &w.ynew);
                        } else {
                            hermite(
                                &mut w.yout,
                                &w.yold,
                                &w.ynew,
                                &w.fold,
                                &w.f1,
                                h,
                                (tau - *t) / h,
                            );
                            callback(tau, &w.yout);
                        }
                        next_out += 1;
                    }
                    self.h_next = chain.accept(&ctl, err, &mut self.err_old, p);
                    self.stats.steps += 1;
                    y.copy_from_slice(&w.ynew);
                    self.f0.copy_from_slice(&w.f1);
                    self.f0_y.copy_from_slice(y);
                    self.f0_t = t_new;
                    self.f0_valid = true;
                    *t = t_new;
                    w.jac_fresh = false;
                    w.jac_age += 1;
                    rejections_in_row = 0;
                }
                outcome => {
                    self.stats.rejected += 1;
                    rejections_in_row += 1;
                    let err = match outcome {
                        Attempt::Error(err) => Some(err),
                        Attempt::NonFinite | Attempt::Singular => None,
                    };
                    chain.reject(&ctl, err, h, *t, &mut self.h_next, &opts)?;
                    // a stale Jacobian may be the cause: evaluate it afresh when it is old,
                    // when the step failed outright, or when a shorter step failed again
                    let stale = self.work.jac_age >= JACOBIAN_STALE_AGE
                        || rejections_in_row >= 2
                        || err.is_none();
                    if !self.work.jac_fresh && stale {
                        self.evaluate_jacobian(ode, *t, y);
                    }
                }
            }
        }
        Ok(())
    }

    /// Fixed steps without error control (for order studies).
    pub(super) fn run_fixed<O: Ode + ?Sized>(
        &mut self,
        ode: &mut O,
        t: &mut f64,
        y: &mut [f64],
        t_end: f64,
        n: u64,
    ) -> Result<(), SolverError> {
        self.ensure_workspace(ode);
        let k = coefficients();
        let t0 = *t;
        let hs = (t_end - t0) / n as f64;
        for i in 1..=n {
            if !self.ensure_f0(ode, *t, y) {
                return Err(SolverError::NonFinite { t: *t });
            }
            let tn = if i == n { t_end } else { t0 + i as f64 * hs };
            self.evaluate_jacobian(ode, *t, y);
            match self.attempt(ode, &k, *t, y, tn - *t) {
                Attempt::Error(_) => {}
                _ => return Err(SolverError::NonFinite { t: *t }),
            }
            self.stats.steps += 1;
            y.copy_from_slice(&self.work.ynew);
            *t = tn;
        }
        Ok(())
    }

    /// One step of size h from (t, y): stages, candidate y1 in `work.ynew`, error norm.
    fn attempt<O: Ode + ?Sized>(
        &mut self,
        ode: &mut O,
        k: &Coefficients,
        t: f64,
        y: &[f64],
        h: f64,
    ) -> Attempt {
        let n = self.dim;
        let c = h * GAMMA;
        let w = &mut self.work;
        let shift = w.solver.shift();
        let ratio = c / shift;
        if shift == 0.0 || !(REUSE_BAND.0..=REUSE_BAND.1).contains(&ratio) {
            self.stats.factorizations += 1;
            if w.solver.factor(&w.jac, c).is_err() {
                return Attempt::Singular;
            }
        }
        // the factorisation is of I - c' J with c' = shift: it is I - c T with T = (c'/c) J
        let c_used = w.solver.shift();
        // time derivative by a forward difference
        let dt = f64::EPSILON.sqrt() * t.abs().max(h).max(1e-3);
        ode.rhs(t + dt, y, &mut w.ft);
        self.stats.rhs_evaluations += 1;
        for (ft, &f0) in w.ft.iter_mut().zip(&self.f0) {
            *ft = (*ft - f0) / dt;
        }
        for i in 0..4 {
            // stage argument
            if i == 0 {
                w.fstage.copy_from_slice(&self.f0);
            } else {
                for (l, yt) in w.ytmp.iter_mut().enumerate() {
                    let mut s = 0.0;
                    for j in 0..i {
                        s += k.a[i][j] * w.u[j * n + l];
                    }
                    *yt = y[l] + s;
                }
                ode.rhs(t + k.alpha[i] * h, &w.ytmp, &mut w.fstage);
                self.stats.rhs_evaluations += 1;
            }
            // right-hand side of the stage system, scaled by c_used so that
            // (I - c_used J) u_i = c_used (f + Σ c_ij u_j / h + γ_i h f_t)
            let (done, rest) = w.u.split_at_mut(i * n);
            let ui = &mut rest[..n];
            for l in 0..n {
                let mut s = w.fstage[l] + k.gamma[i] * h * w.ft[l];
                for j in 0..i {
                    s += k.c[i][j] / h * done[j * n + l];
                }
                ui[l] = c_used * s;
            }
            w.solver.solve(ui);
            // the method's matrix is I/(hγ) - T: scale from c_used to c
            if c_used != c {
                let r = c / c_used;
                ui.iter_mut().for_each(|v| *v *= r);
            }
            if ui.iter().any(|v| !v.is_finite()) {
                return Attempt::NonFinite;
            }
        }
        let (atol, rtol) = (self.options.atol, self.options.rtol);
        for l in 0..n {
            let (mut y1, mut e) = (0.0, 0.0);
            for j in 0..4 {
                y1 += k.m[j] * w.u[j * n + l];
                e += k.e[j] * w.u[j * n + l];
            }
            w.ynew[l] = y[l] + y1;
            w.ytmp[l] = e;
        }
        // the error norm of the explicit pairs, with the problem's error weights
        let err = norm::rms(&w.ytmp[..n], y, &w.ynew, atol, rtol, ode.error_weights());
        if err.is_finite() && w.ynew.iter().all(|v| v.is_finite()) {
            Attempt::Error(err)
        } else {
            Attempt::NonFinite
        }
    }

    /// First step: 0.01 ‖y‖/‖f‖ in the weighted norm (Hairer's first guess; the problem's
    /// error weights as in the step's error norm), capped by the
    /// span and h_max; the controller grows it quickly.
    fn initial_step(
        &self,
        t: f64,
        y: &[f64],
        t_end: f64,
        weights: Option<super::ErrorWeights>,
    ) -> f64 {
        let n = self.dim;
        let (atol, rtol) = (self.options.atol, self.options.rtol);
        let sc = |i: usize| {
            let (r, w) = match &weights {
                Some(ew) => (ew.reference[i] as usize, ew.weight[i]),
                None => (i, 1.0),
            };
            (w * atol + rtol * y[r].abs()).max(f64::MIN_POSITIVE)
        };
        let d0 = ((0..n).map(|i| (y[i] / sc(i)).powi(2)).sum::<f64>() / n as f64).sqrt();
        let d1 = ((0..n).map(|i| (self.f0[i] / sc(i)).powi(2)).sum::<f64>() / n as f64).sqrt();
        let h = if d0 < 1e-5 || d1 < 1e-5 {
            1e-6
        } else {
            0.01 * d0 / d1
        };
        h.min(self.options.h_max)
            .min(t_end - t)
            .max(self.options.h_min)
    }
}

/// Dense forward-difference Jacobian of a plain [`Ode`] (pattern: dense).
fn dense_differences<O: Ode + ?Sized>(
    ode: &mut O,
    t: f64,
    y: &[f64],
    f0: &[f64],
    w: &mut Work,
) -> u64 {
    let n = y.len();
    let eps = f64::EPSILON.sqrt();
    w.fd_y.copy_from_slice(y);
    for j in 0..n {
        let d = eps * y[j].abs().max(w.floor[j]);
        w.fd_y[j] = y[j] + d;
        let d = w.fd_y[j] - y[j];
        ode.rhs(t, &w.fd_y, &mut w.fd_f);
        for i in 0..n {
            w.jac.values[i * n + j] = (w.fd_f[i] - f0[i]) / d;
        }
        w.fd_y[j] = y[j];
    }
    n as u64
}

/// Cubic Hermite interpolant at θ of (y0, f0) and (y1, f1) over a step h.
pub(super) fn hermite(
    out: &mut [f64],
    y0: &[f64],
    y1: &[f64],
    f0: &[f64],
    f1: &[f64],
    h: f64,
    th: f64,
) {
    let h00 = (1.0 + 2.0 * th) * (1.0 - th) * (1.0 - th);
    let h10 = th * (1.0 - th) * (1.0 - th);
    let h01 = th * th * (3.0 - 2.0 * th);
    let h11 = th * th * (th - 1.0);
    for i in 0..out.len() {
        out[i] = h00 * y0[i] + h * h10 * f0[i] + h01 * y1[i] + h * h11 * f1[i];
    }
}

/// Structure of a problem's Jacobian, asked once by the stiff integrator.
#[derive(Clone, Debug, Default)]
pub struct JacobianStructure {
    /// Pattern of the sparse part S.
    pub pattern: Pattern,
    /// Block id of each unknown for the sparse LU (e.g. the unknowns of one body or mesh
    /// vertex); unknowns with equal ids are eliminated together.
    pub groups: Vec<u32>,
    /// Rank of the low-rank part U V^T.
    pub rank: usize,
}

/// Compile-time check that the trait stays object safe.
#[allow(dead_code)]
fn _object_safe(_: &mut dyn StiffOde) {}
