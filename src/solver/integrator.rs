//! The adaptive integrator: one embedded Runge-Kutta pair (see `tableau.rs`) driven by a
//! weighted RMS error norm, a PI step-size controller, FSAL reuse, dense output, Hairer's
//! automatic initial step and his stiffness test. All working memory is allocated when the
//! integrator is created (or first used after deserialisation); the step loop never
//! allocates.
//!
//! Sources: Hairer, Norsett & Wanner, *Solving Ordinary Differential Equations I* (2nd ed.,
//! 1993), Sec. II.4 (error norm, initial step `hinit`, step control) and the `dopri5` /
//! `dop853` codes; K. Gustafsson, "Control theoretic techniques for stepsize selection in
//! explicit Runge-Kutta methods", ACM TOMS 17 (1991) 533-554 (PI control); Hairer & Wanner,
//! *Solving ODEs II* (1996), Sec. IV.2 (stiffness detection).

use serde::{Deserialize, Serialize};

use super::control::{Chain, Controller, ERR_OLD_MIN};
use super::norm;
use super::rosenbrock::Rosenbrock;
use super::tableau::{DOPRI5, Tableau};
use super::{ErrorWeights, Method, Ode, Options, SolverError, Stats};

/// Safety factor of the step-size controller.
const SAFETY: f64 = 0.9;
/// Smallest step-size ratio h_new / h.
const FAC_MIN: f64 = 0.2;
/// Largest step-size ratio h_new / h.
const FAC_MAX: f64 = 10.0;
/// The stiffness flag is raised after this many positive tests ...
const STIFF_HITS: u32 = 15;
/// ... without this many consecutive negative ones in between (Hairer's `dopri5`).
const NONSTIFF_RESET: u32 = 6;

/// Scratch memory of the stepper; rebuilt (once) when missing, e.g. after deserialisation.
#[derive(Clone, Debug, Default)]
struct Work {
    /// Stages 1.. of the pair, then its extra dense stages, `n` values each (stage 0 is
    /// the FSAL vector kept in [`Integrator::fsal_k`]).
    k: Vec<f64>,
    /// Argument of the stage being evaluated; then the error estimate Σ e_j k_j.
    ytmp: Vec<f64>,
    /// Candidate solution y1.
    ynew: Vec<f64>,
    /// State of the stage used by the stiffness test.
    ystiff: Vec<f64>,
    /// Dense-output vectors r1, r2, ... of the last accepted step.
    dense: Vec<f64>,
    /// Interpolated state handed to the output callback (also the second error estimate
    /// of DOP853 while a step is being assessed).
    yout: Vec<f64>,
}

/// The integration ahead of the caller ([`Integrator::integrate_ahead`]): the internal
/// point, which may lie past the time the caller was last given, and the last accepted
/// step's continuous extension, from which the caller's states are read.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
struct Ahead {
    /// Whether the fields below belong to the integration the caller is on: cleared by
    /// [`Integrator::invalidate`], [`Integrator::reset`] and any other way of integrating.
    valid: bool,
    /// The time and state the caller was last given: a call resumes the integration ahead
    /// only from exactly these.
    out_t: f64,
    out_y: Vec<f64>,
    /// The internal time and state (the end of the last accepted step).
    t: f64,
    y: Vec<f64>,
    /// Whether `t0`, `h`, `y0` and `dense` hold a step.
    have_step: bool,
    /// Start and size of the last accepted step, and its start state.
    t0: f64,
    h: f64,
    y0: Vec<f64>,
    /// Dense-output vectors of that step.
    dense: Vec<f64>,
}

impl Ahead {
    /// Starts a call of [`Integrator::integrate_ahead`] at (`t`, `y`): sizes the buffers
    /// (state length `n`, dense output `dense_len`), and returns whether the call resumes the
    /// integration ahead (the caller is exactly where the last call left it); otherwise the
    /// internal state restarts from (`t`, `y`) with no step. Either way the memory is marked
    /// invalid until the call succeeds.
    fn begin(&mut self, n: usize, dense_len: usize, t: f64, y: &[f64]) -> bool {
        for (buf, len) in [
            (&mut self.y, n),
            (&mut self.y0, n),
            (&mut self.out_y, n),
            (&mut self.dense, dense_len),
        ] {
            if buf.len() != len {
                buf.clear();
                buf.resize(len, 0.0);
                self.valid = false;
            }
        }
        let resume = self.valid
            && self.out_t == t
            && self.t >= t
            && self.have_step
            && self.out_y.as_slice() == y;
        if !resume {
            self.t = t;
            self.y.copy_from_slice(y);
            self.have_step = false;
        }
        self.valid = false;
        resume
    }
}

/// Adaptive embedded Runge-Kutta integrator with memory across calls.
///
/// Holds the method, its options, the step size to try next, the PI-controller memory,
/// the FSAL stage f(t, y) at the current point, preallocated stage buffers and cumulative
/// [`Stats`]. Serialising it and restoring it later continues the integration bit for bit.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Integrator {
    method: Method,
    options: Options,
    dim: usize,
    /// Step size to try next; 0 until chosen.
    h_next: f64,
    /// PI controller memory: the error norm of the last accepted step (floored).
    err_old: f64,
    /// Whether the FSAL vector is f(fsal_t, fsal_y).
    fsal_valid: bool,
    fsal_t: f64,
    fsal_y: Vec<f64>,
    fsal_k: Vec<f64>,
    stats: Stats,
    stiff_hits: u32,
    nonstiff_run: u32,
    /// Memory of the stiff method when it is the method in use.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    stiff: Option<Box<Rosenbrock>>,
    /// Stepping past the communication points.
    #[serde(default)]
    ahead: Ahead,
    #[serde(skip)]
    work: Work,
}

/// Result of one step attempt.
enum Attempt {
    /// Finite error norm (accepted if <= 1).
    Error(f64),
    /// A stage or the candidate state was not finite.
    NonFinite,
}

impl Integrator {
    /// Creates an integrator for systems of dimension `dim` (> 0).
    pub fn new(method: Method, options: Options, dim: usize) -> Result<Self, SolverError> {
        options.validate()?;
        if dim == 0 {
            return Err(SolverError::InvalidArgument(
                "system dimension is 0; it must be at least 1".into(),
            ));
        }
        let mut it = Integrator {
            method,
            options,
            dim,
            h_next: 0.0,
            err_old: ERR_OLD_MIN,
            fsal_valid: false,
            fsal_t: 0.0,
            fsal_y: vec![0.0; dim],
            fsal_k: vec![0.0; dim],
            stats: Stats::default(),
            stiff_hits: 0,
            nonstiff_run: 0,
            stiff: (method == Method::Rosenbrock).then(|| Box::new(Rosenbrock::new(options, dim))),
            ahead: Ahead::default(),
            work: Work::default(),
        };
        if it.stiff.is_none() {
            it.ensure_workspace();
        }
        Ok(it)
    }

    /// The method in use.
    pub fn method(&self) -> Method {
        self.method
    }

    /// The options in use.
    pub fn options(&self) -> &Options {
        &self.options
    }

    /// Replaces the options (validated first; the step size and FSAL stage are kept).
    pub fn set_options(&mut self, options: Options) -> Result<(), SolverError> {
        options.validate()?;
        self.options = options;
        if let Some(r) = &mut self.stiff {
            r.options = options;
        }
        Ok(())
    }

    /// Dimension of the system.
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// Cumulative statistics since creation or the last [`Integrator::reset`].
    pub fn stats(&self) -> Stats {
        match &self.stiff {
            Some(r) => r.stats,
            None => self.stats,
        }
    }

    /// The step size the next step will try (0 before the first step).
    pub fn step_size(&self) -> f64 {
        match &self.stiff {
            Some(r) => r.h_next,
            None => self.h_next,
        }
    }

    /// Whether Hairer's stiffness test currently considers the problem stiff: it fired on
    /// 15 accepted steps without 6 consecutive negative tests in between.
    pub fn stiffness_detected(&self) -> bool {
        self.stiff_hits >= STIFF_HITS
    }

    /// The right-hand side changed discontinuously (new inputs): forget the FSAL stage,
    /// keep the step size and controller memory.
    pub fn invalidate(&mut self) {
        self.fsal_valid = false;
        self.ahead.valid = false;
        if let Some(r) = &mut self.stiff {
            r.invalidate();
        }
    }

    /// A copy of the memory a snapshot keeps (method, options, step size, controller memory,
    /// FSAL stage, statistics, stiffness-test counters), without the scratch buffers.
    pub fn memory(&self) -> Integrator {
        Integrator {
            method: self.method,
            options: self.options,
            dim: self.dim,
            h_next: self.h_next,
            err_old: self.err_old,
            fsal_valid: self.fsal_valid,
            fsal_t: self.fsal_t,
            fsal_y: self.fsal_y.clone(),
            fsal_k: self.fsal_k.clone(),
            stats: self.stats,
            stiff_hits: self.stiff_hits,
            nonstiff_run: self.nonstiff_run,
            stiff: self.stiff.as_ref().map(|r| Box::new(r.memory())),
            ahead: self.ahead.clone(),
            work: Work::default(),
        }
    }

    /// Takes over the memory of `src` (see [`Integrator::memory`]), reusing this integrator's
    /// buffers: the integration then continues bit for bit as it would from `src`, exactly as
    /// after a round trip through serialisation, but without allocating when the two have
    /// the same method and dimension. A checkpoint taken before every communication step
    /// costs a copy of three state-length vectors.
    pub fn copy_memory_from(&mut self, src: &Integrator) {
        if self.dim != src.dim || self.method != src.method {
            *self = src.memory();
            return;
        }
        self.options = src.options;
        self.h_next = src.h_next;
        self.err_old = src.err_old;
        self.fsal_valid = src.fsal_valid;
        self.fsal_t = src.fsal_t;
        self.fsal_y.clone_from(&src.fsal_y);
        self.fsal_k.clone_from(&src.fsal_k);
        self.stats = src.stats;
        self.stiff_hits = src.stiff_hits;
        self.nonstiff_run = src.nonstiff_run;
        let (dst, a) = (&mut self.ahead, &src.ahead);
        dst.valid = a.valid;
        dst.out_t = a.out_t;
        dst.out_y.clone_from(&a.out_y);
        dst.t = a.t;
        dst.y.clone_from(&a.y);
        dst.have_step = a.have_step;
        dst.t0 = a.t0;
        dst.h = a.h;
        dst.y0.clone_from(&a.y0);
        dst.dense.clone_from(&a.dense);
        match (&mut self.stiff, &src.stiff) {
            (Some(dst), Some(r)) => dst.copy_memory_from(r),
            (dst, r) => *dst = r.as_ref().map(|r| Box::new(r.memory())),
        }
    }

    /// Forgets everything: step size, controller memory, FSAL stage, statistics.
    pub fn reset(&mut self) {
        self.ahead.valid = false;
        self.h_next = 0.0;
        self.err_old = ERR_OLD_MIN;
        self.fsal_valid = false;
        self.stats = Stats::default();
        self.stiff_hits = 0;
        self.nonstiff_run = 0;
        if let Some(r) = &mut self.stiff {
            r.reset();
        }
    }

    /// Advances `(t, y)` exactly to `t_end` (>= t) with adaptive steps; the last step is
    /// shortened to land on `t_end`, and the natural step size is remembered for the next
    /// call. On error, `*t` and `y` hold the last accepted step.
    pub fn integrate<O: Ode + ?Sized>(
        &mut self,
        ode: &mut O,
        t: &mut f64,
        y: &mut [f64],
        t_end: f64,
    ) -> Result<(), SolverError> {
        self.ahead.valid = false;
        self.run(ode, t, y, t_end, &[], &mut |_: f64, _: &[f64]| {})
    }

    /// As [`Integrator::integrate`], but the steps do not end on `t_end`: the integration
    /// runs on to the first step end at or past `t_end` and gives the caller the state at
    /// `t_end` from that step's continuous extension (Dormand-Prince's, of order 4, Hairer,
    /// Norsett & Wanner II.6). The next call that starts where this one ended, with nothing
    /// invalidated in between ([`Integrator::invalidate`] when the right-hand side changes),
    /// continues from the internal point rather than from `y` (when `y` is still the state
    /// this call gave; any other state restarts), so communication points cost
    /// no step of their own and, while they fall inside one step, no evaluation at all. A
    /// call from any other point restarts from `(t, y)`. The stiff method runs past `t_end`
    /// likewise, its states read from the cubic Hermite interpolant of its last step, but a
    /// restart's steps end on `t_end` (the interpolant is not stiffly accurate, and a state
    /// read from it would start the next restart). On error, `*t` and `y` hold the last
    /// accepted step (or stay as given when none was accepted).
    pub fn integrate_ahead<O: Ode + ?Sized>(
        &mut self,
        ode: &mut O,
        t: &mut f64,
        y: &mut [f64],
        t_end: f64,
    ) -> Result<(), SolverError> {
        self.check_call(ode, *t, y, t_end)?;
        if t_end == *t {
            return Ok(());
        }
        if self.method == Method::Rosenbrock || self.stiff.is_some() {
            return self.stiff_ahead(ode, t, y, t_end);
        }
        self.ensure_workspace();
        let n = self.dim;
        let dense_len = self.work.dense.len();
        self.ahead.begin(n, dense_len, *t, y);
        let mut yint = std::mem::take(&mut self.ahead.y);
        let mut tint = self.ahead.t;
        let result = self.step_past(ode, &mut tint, &mut yint, t_end);
        self.ahead.y = yint;
        self.ahead.t = tint;
        if let Err(e) = result {
            if tint > *t {
                *t = tint;
                y.copy_from_slice(&self.ahead.y);
            }
            return Err(e);
        }
        let a = &mut self.ahead;
        if a.t == t_end {
            y.copy_from_slice(&a.y);
        } else {
            interpolate(&a.dense, &a.y0, (t_end - a.t0) / a.h, y);
        }
        *t = t_end;
        a.out_t = t_end;
        a.out_y.copy_from_slice(y);
        a.valid = true;
        Ok(())
    }

    /// [`Integrator::integrate_ahead`] for the stiff method: its steps run past `t_end` and
    /// the caller's state comes from the last step's cubic Hermite interpolant, except on a
    /// restart (the first call after [`Integrator::invalidate`], or from another state),
    /// whose steps end on `t_end` so that the state it gives is a step's own.
    fn stiff_ahead<O: Ode + ?Sized>(
        &mut self,
        ode: &mut O,
        t: &mut f64,
        y: &mut [f64],
        t_end: f64,
    ) -> Result<(), SolverError> {
        let n = self.dim;
        let r = self
            .stiff
            .get_or_insert_with(|| Box::new(Rosenbrock::new(self.options, n)));
        let a = &mut self.ahead;
        let resume = a.begin(n, 2 * n, *t, y);
        if a.t < t_end {
            let mut yint = std::mem::take(&mut a.y);
            let mut tint = a.t;
            // A restart's first run lands on t_end: the cubic Hermite interpolant is not
            // stiffly accurate (its error in a stiff component is about |h lambda| / 6 times
            // the step's error estimate), so a state read from it must not become the start
            // of the next restart when the inputs change on every call.
            let past = resume;
            let result = r.run(ode, &mut tint, &mut yint, t_end, past, &[], &mut |_, _| {});
            let a = &mut self.ahead;
            a.y = yint;
            if let Err(e) = result {
                if tint > *t {
                    *t = tint;
                    y.copy_from_slice(&a.y);
                }
                a.t = tint;
                return Err(e);
            }
            let (h, y0, f0, f1) = r.last_step();
            a.t0 = tint - h;
            a.h = h;
            a.t = tint;
            a.y0.copy_from_slice(y0);
            a.dense[..n].copy_from_slice(f0);
            a.dense[n..].copy_from_slice(f1);
            a.have_step = true;
        }
        let a = &mut self.ahead;
        if a.t == t_end {
            y.copy_from_slice(&a.y);
        } else {
            let (f0, f1) = a.dense.split_at(n);
            super::rosenbrock::hermite(y, &a.y0, &a.y, f0, f1, a.h, (t_end - a.t0) / a.h);
        }
        *t = t_end;
        a.out_t = t_end;
        a.out_y.copy_from_slice(y);
        a.valid = true;
        Ok(())
    }

    /// As [`Integrator::integrate`], calling `callback(τ, y(τ))` at every `output_times`
    /// entry τ in (t, t_end], in order, from the method's continuous extension (steps are
    /// not shortened to hit output times). `output_times` must be finite and
    /// non-decreasing; entries outside (t, t_end] are ignored.
    pub fn integrate_dense<O: Ode + ?Sized, F: FnMut(f64, &[f64])>(
        &mut self,
        ode: &mut O,
        t: &mut f64,
        y: &mut [f64],
        t_end: f64,
        output_times: &[f64],
        mut callback: F,
    ) -> Result<(), SolverError> {
        if output_times.iter().any(|v| !v.is_finite()) {
            return Err(SolverError::InvalidArgument(
                "output times must be finite".into(),
            ));
        }
        if let Some(i) = output_times.windows(2).position(|w| w[1] < w[0]) {
            return Err(SolverError::InvalidArgument(format!(
                "output times must be non-decreasing; entry {} ({}) is below entry {} ({})",
                i + 1,
                output_times[i + 1],
                i,
                output_times[i]
            )));
        }
        self.run(ode, t, y, t_end, output_times, &mut callback)
    }

    /// Fixed-step integration without error control (for convergence studies and
    /// reproducible runs): takes n = ⌈(t_end - t)/h⌉ equal steps of (t_end - t)/n
    /// (a relative slack of 1e-9 avoids an extra step from round-off). Does not touch the
    /// adaptive step size or controller memory; counts steps in the statistics.
    pub fn integrate_fixed<O: Ode + ?Sized>(
        &mut self,
        ode: &mut O,
        t: &mut f64,
        y: &mut [f64],
        t_end: f64,
        h: f64,
    ) -> Result<(), SolverError> {
        if !(h.is_finite() && h > 0.0) {
            return Err(SolverError::InvalidArgument(format!(
                "fixed step h = {h} must be finite and > 0"
            )));
        }
        self.check_call(ode, *t, y, t_end)?;
        if t_end == *t {
            return Ok(());
        }
        let t0 = *t;
        let span = t_end - t0;
        if self.method == Method::Rosenbrock && self.stiff.is_none() {
            // memory serialised without its stiff part: start it afresh
            self.stiff = Some(Box::new(Rosenbrock::new(self.options, self.dim)));
        }
        if let Some(r) = &mut self.stiff {
            let n = ((span / h) * (1.0 - 1e-9)).ceil().max(1.0);
            if n > self.options.max_steps as f64 {
                return Err(SolverError::TooManySteps {
                    t: *t,
                    steps: self.options.max_steps,
                });
            }
            return r.run_fixed(ode, t, y, t_end, n as u64);
        }
        self.ensure_workspace();
        self.ensure_fsal(ode, *t, y)?;
        let n = ((span / h) * (1.0 - 1e-9)).ceil().max(1.0);
        if n > self.options.max_steps as f64 {
            return Err(SolverError::TooManySteps {
                t: *t,
                steps: self.options.max_steps,
            });
        }
        let n = n as u64;
        let hs = span / n as f64;
        for i in 1..=n {
            let tn = if i == n { t_end } else { t0 + i as f64 * hs };
            let h_i = tn - *t;
            match self.attempt(ode, *t, y, h_i) {
                Attempt::NonFinite => return Err(SolverError::NonFinite { t: *t }),
                Attempt::Error(_) => {}
            }
            self.stats.steps += 1;
            self.commit(t, y, tn);
        }
        Ok(())
    }

    // -----------------------------------------------------------------------------------

    /// Accepted steps from the internal point `(t, y)` until `t` reaches `t_end` (the last one
    /// ending at or past it), keeping the last step's continuous extension in `self.ahead`.
    fn step_past<O: Ode + ?Sized>(
        &mut self,
        ode: &mut O,
        t: &mut f64,
        y: &mut [f64],
        t_end: f64,
    ) -> Result<(), SolverError> {
        if *t >= t_end {
            return Ok(());
        }
        self.ensure_fsal(ode, *t, y)?;
        let (opts, ctl) = self.start_explicit(ode, *t, y, t_end);
        let mut chain = Chain::new(self.h_next);
        while *t < t_end {
            let p = chain.plan(&mut self.h_next, *t, f64::INFINITY, &opts)?;
            let h = p.h;
            match self.attempt(ode, *t, y, h) {
                Attempt::Error(err) if err <= 1.0 => {
                    let t_new = *t + h;
                    if t_new >= t_end {
                        if !self.prepare_dense(ode, *t, y, h) {
                            return Err(chain.fail_non_finite(&mut self.h_next, *t));
                        }
                        let a = &mut self.ahead;
                        // the work buffer is rewritten whole by the next `prepare_dense`:
                        // trade the two buffers rather than copy the vectors
                        std::mem::swap(&mut a.dense, &mut self.work.dense);
                        a.y0.copy_from_slice(y);
                        a.t0 = *t;
                        a.h = h;
                        a.have_step = true;
                    }
                    if opts.stiffness_check {
                        self.stiffness_test(h, self.tableau());
                    }
                    self.h_next = chain.accept(&ctl, err, &mut self.err_old, p);
                    self.stats.steps += 1;
                    self.commit(t, y, t_new);
                }
                outcome => {
                    self.stats.rejected += 1;
                    let err = match outcome {
                        Attempt::Error(err) => Some(err),
                        Attempt::NonFinite => None,
                    };
                    chain.reject(&ctl, err, h, *t, &mut self.h_next, &opts)?;
                }
            }
        }
        Ok(())
    }

    /// The explicit pair in use (the stiff method never reaches the explicit paths).
    fn tableau(&self) -> &'static Tableau {
        self.method.tableau().unwrap_or(&DOPRI5)
    }

    fn check_call<O: Ode + ?Sized>(
        &self,
        ode: &O,
        t: f64,
        y: &[f64],
        t_end: f64,
    ) -> Result<(), SolverError> {
        self.options.validate()?;
        if self.dim == 0 || ode.dim() != self.dim || y.len() != self.dim {
            return Err(SolverError::InvalidArgument(format!(
                "dimension mismatch: integrator {}, system {}, state vector {}",
                self.dim,
                ode.dim(),
                y.len()
            )));
        }
        if !t.is_finite() || !t_end.is_finite() {
            return Err(SolverError::InvalidArgument(format!(
                "times must be finite (t = {t}, t_end = {t_end})"
            )));
        }
        if t_end < t {
            return Err(SolverError::InvalidArgument(format!(
                "t_end = {t_end} is before t = {t}; only forward integration is supported"
            )));
        }
        if y.iter().any(|v| !v.is_finite()) {
            return Err(SolverError::NonFinite { t });
        }
        Ok(())
    }

    /// Sizes the scratch memory (allocates only when it does not fit, i.e. once).
    fn ensure_workspace(&mut self) {
        let n = self.dim;
        let tab = self.tableau();
        let nk = (tab.stages - 1 + tab.dense.extra_c.len()) * n;
        let nd = (3 + tab.dense.d.len()) * n;
        let w = &mut self.work;
        for (buf, len) in [
            (&mut w.k, nk),
            (&mut w.ytmp, n),
            (&mut w.ynew, n),
            (&mut w.ystiff, n),
            (&mut w.dense, nd),
            (&mut w.yout, n),
        ] {
            if buf.len() != len {
                buf.clear();
                buf.resize(len, 0.0);
            }
        }
        if self.fsal_k.len() != n || self.fsal_y.len() != n {
            self.fsal_k.clear();
            self.fsal_k.resize(n, 0.0);
            self.fsal_y.clear();
            self.fsal_y.resize(n, 0.0);
            self.fsal_valid = false;
        }
    }

    /// Makes `fsal_k` = f(t, y), reusing it when it was computed at exactly this point.
    /// The set-up shared by the explicit stepping loops: a first step size when none is
    /// carried over (the options' or [`Integrator::initial_step`]'s), the options and the
    /// step-size controller of the method's tableau.
    fn start_explicit<O: Ode + ?Sized>(
        &mut self,
        ode: &mut O,
        t: f64,
        y: &[f64],
        t_end: f64,
    ) -> (Options, Controller) {
        if self.h_next <= 0.0 || !self.h_next.is_finite() {
            self.h_next = match self.options.h_init {
                Some(h) => h,
                None => self.initial_step(ode, t, y, t_end),
            };
        }
        let tab = self.tableau();
        let ctl = Controller {
            safety: SAFETY,
            fac_min: FAC_MIN,
            fac_max: FAC_MAX,
            alpha: tab.pi_alpha,
            beta: tab.pi_beta,
            hold_ratio: 1.0,
        };
        (self.options, ctl)
    }

    fn ensure_fsal<O: Ode + ?Sized>(
        &mut self,
        ode: &mut O,
        t: f64,
        y: &[f64],
    ) -> Result<(), SolverError> {
        if self.fsal_valid && self.fsal_t == t && self.fsal_y.as_slice() == y {
            return Ok(());
        }
        ode.rhs(t, y, &mut self.fsal_k);
        self.stats.rhs_evaluations += 1;
        if self.fsal_k.iter().any(|v| !v.is_finite()) {
            // keep the stored vector finite so that the integrator stays serialisable
            self.fsal_k.fill(0.0);
            self.fsal_valid = false;
            return Err(SolverError::NonFinite { t });
        }
        self.fsal_t = t;
        self.fsal_y.copy_from_slice(y);
        self.fsal_valid = true;
        Ok(())
    }

    /// The adaptive driver behind [`Integrator::integrate`] and
    /// [`Integrator::integrate_dense`].
    fn run<O: Ode + ?Sized>(
        &mut self,
        ode: &mut O,
        t: &mut f64,
        y: &mut [f64],
        t_end: f64,
        output_times: &[f64],
        callback: &mut dyn FnMut(f64, &[f64]),
    ) -> Result<(), SolverError> {
        self.ahead.valid = false;
        self.check_call(ode, *t, y, t_end)?;
        if t_end == *t {
            return Ok(());
        }
        if self.method == Method::Rosenbrock && self.stiff.is_none() {
            // memory serialised without its stiff part: start it afresh
            self.stiff = Some(Box::new(Rosenbrock::new(self.options, self.dim)));
        }
        if let Some(r) = &mut self.stiff {
            return r.run(ode, t, y, t_end, false, output_times, callback);
        }
        self.ensure_workspace();
        self.ensure_fsal(ode, *t, y)?;
        let mut next_out = output_times.partition_point(|&v| v <= *t);
        let (opts, ctl) = self.start_explicit(ode, *t, y, t_end);
        let mut chain = Chain::new(self.h_next);
        while *t < t_end {
            let p = chain.plan(&mut self.h_next, *t, t_end, &opts)?;
            let h = p.h;
            match self.attempt(ode, *t, y, h) {
                Attempt::Error(err) if err <= 1.0 => {
                    let t_new = if p.clipped { t_end } else { *t + h };
                    if next_out < output_times.len() && output_times[next_out] <= t_new {
                        if !self.prepare_dense(ode, *t, y, h) {
                            return Err(chain.fail_non_finite(&mut self.h_next, *t));
                        }
                        while next_out < output_times.len() && output_times[next_out] <= t_new {
                            let tau = output_times[next_out];
                            if tau >= t_new {
                                callback(tau, &self.work.ynew);
                            } else {
                                self.eval_dense(y, (tau - *t) / h);
                                callback(tau, &self.work.yout);
                            }
                            next_out += 1;
                        }
                    }
                    if opts.stiffness_check {
                        self.stiffness_test(h, self.tableau());
                    }
                    self.h_next = chain.accept(&ctl, err, &mut self.err_old, p);
                    self.stats.steps += 1;
                    self.commit(t, y, t_new);
                }
                outcome => {
                    self.stats.rejected += 1;
                    let err = match outcome {
                        Attempt::Error(err) => Some(err),
                        Attempt::NonFinite => None,
                    };
                    chain.reject(&ctl, err, h, *t, &mut self.h_next, &opts)?;
                }
            }
        }
        Ok(())
    }

    /// Accepts the step held in the work buffers: y ← y1, t ← t_new, FSAL ← f(t_new, y1).
    fn commit(&mut self, t: &mut f64, y: &mut [f64], t_new: f64) {
        let n = self.dim;
        let s = self.tableau().stages;
        y.copy_from_slice(&self.work.ynew);
        self.fsal_k
            .copy_from_slice(&self.work.k[(s - 2) * n..(s - 1) * n]);
        self.fsal_y.copy_from_slice(y);
        self.fsal_t = t_new;
        self.fsal_valid = true;
        *t = t_new;
    }

    /// Computes all stages of one step of size h from (t, y) into the work buffers and
    /// returns the weighted RMS error norm (or reports non-finite values).
    fn attempt<O: Ode + ?Sized>(&mut self, ode: &mut O, t: f64, y: &[f64], h: f64) -> Attempt {
        let n = self.dim;
        let tab = self.tableau();
        let s = tab.stages;
        let Work {
            k,
            ytmp,
            ynew,
            ystiff,
            ..
        } = &mut self.work;
        let k0 = &self.fsal_k;
        for i in 1..s {
            let dst: &mut [f64] = if i == s - 1 {
                &mut ynew[..]
            } else {
                &mut ytmp[..]
            };
            combine(dst, y, h, tab.a[i], k0, k, n);
            if self.options.stiffness_check && tab.stiff_stage == Some(i) {
                ystiff.copy_from_slice(dst);
            }
            let ki = &mut k[(i - 1) * n..i * n];
            ode.rhs(t + tab.c[i] * h, dst, ki);
        }
        self.stats.rhs_evaluations += (s - 1) as u64;
        let k_last = &k[(s - 2) * n..(s - 1) * n];
        if !(all_finite(ynew) && all_finite(k_last)) {
            return Attempt::NonFinite;
        }
        let err = self.error_norm(y, h, ode.error_weights());
        if err.is_finite() {
            Attempt::Error(err)
        } else {
            Attempt::NonFinite
        }
    }

    /// Weighted RMS norm ([`super::norm`]) of the local error estimate h Σ e_j k_j.
    /// DOP853 combines its two estimators as err5² / sqrt(err5² + 0.01 err3²).
    fn error_norm(&mut self, y: &[f64], h: f64, weights: Option<ErrorWeights>) -> f64 {
        let n = self.dim;
        let tab = self.tableau();
        let (atol, rtol) = (self.options.atol, self.options.rtol);
        // the stage arguments are no longer needed: reuse their buffers for Σ e_j k_j
        let Work {
            k,
            ytmp: e5,
            yout: e3,
            ynew,
            ..
        } = &mut self.work;
        stage_sum(e5, tab.e, &self.fsal_k, k, n);
        let (y, ynew) = (&y[..n], &ynew[..n]);
        match tab.e_low {
            None => h * norm::rms(&e5[..n], y, ynew, atol, rtol, weights),
            Some(el) => {
                let sum = norm::square_sum(&e5[..n], y, ynew, atol, rtol, weights);
                stage_sum(e3, el, &self.fsal_k, k, n);
                let sum_low = norm::square_sum(&e3[..n], y, ynew, atol, rtol, weights);
                if sum == 0.0 && sum_low == 0.0 {
                    return 0.0;
                }
                h * sum / ((sum + 0.01 * sum_low) * n as f64).sqrt()
            }
        }
    }

    /// Hairer's stiffness test on an accepted step: |hλ| ≈ h ‖k_last - k_s‖ / ‖y1 - Y_s‖
    /// against the method's boundary. Only counts; never aborts.
    fn stiffness_test(&mut self, h: f64, tab: &Tableau) {
        let Some(stage) = tab.stiff_stage else {
            return;
        };
        let n = self.dim;
        let s = tab.stages;
        let ks = &self.work.k[(stage - 1) * n..stage * n];
        let kl = &self.work.k[(s - 2) * n..(s - 1) * n];
        let mut num = 0.0;
        let mut den = 0.0;
        for i in 0..n {
            let dk = kl[i] - ks[i];
            let dy = self.work.ynew[i] - self.work.ystiff[i];
            num += dk * dk;
            den += dy * dy;
        }
        if den > 0.0 && h * (num / den).sqrt() > tab.stiff_boundary {
            self.stats.stiff_steps += 1;
            self.nonstiff_run = 0;
            self.stiff_hits = self.stiff_hits.saturating_add(1);
        } else {
            self.nonstiff_run += 1;
            if self.nonstiff_run >= NONSTIFF_RESET {
                self.stiff_hits = 0;
            }
        }
    }

    /// Builds the dense-output vectors of the step just computed (evaluating the extra
    /// stages if the method has any). Returns false if an extra stage was not finite.
    fn prepare_dense<O: Ode + ?Sized>(&mut self, ode: &mut O, t: f64, y: &[f64], h: f64) -> bool {
        let n = self.dim;
        let tab = self.tableau();
        let s = tab.stages;
        let dense = &tab.dense;
        let Work {
            k,
            ytmp,
            ynew,
            dense: r,
            ..
        } = &mut self.work;
        let k0 = &self.fsal_k;
        for (m, (&c, a)) in dense.extra_c.iter().zip(dense.extra_a).enumerate() {
            combine(ytmp, y, h, a, k0, k, n);
            let idx = s - 1 + m;
            let km = &mut k[idx * n..(idx + 1) * n];
            ode.rhs(t + c * h, ytmp, km);
            self.stats.rhs_evaluations += 1;
            if km.iter().any(|v| !v.is_finite()) {
                return false;
            }
        }
        let k_last = &k[(s - 2) * n..(s - 1) * n];
        for i in 0..n {
            let dy = ynew[i] - y[i];
            let bspl = h * k0[i] - dy;
            r[i] = dy;
            r[n + i] = bspl;
            r[2 * n + i] = dy - h * k_last[i] - bspl;
        }
        for (m, row) in dense.d.iter().enumerate() {
            let rm = &mut r[(3 + m) * n..(4 + m) * n];
            stage_sum(rm, row, k0, k, n);
            rm.iter_mut().for_each(|v| *v *= h);
        }
        true
    }

    /// Evaluates the continuous extension at θ ∈ [0, 1] into `work.yout`.
    fn eval_dense(&mut self, y: &[f64], theta: f64) {
        let Work { dense: r, yout, .. } = &mut self.work;
        interpolate(r, y, theta, yout);
    }

    /// Hairer's automatic initial step (`hinit` of `dopri5`), with RMS norms: a first
    /// guess from ‖y‖/‖f‖, one explicit Euler step to estimate the second derivative,
    /// then h = min(100 h0, (0.01 / max(‖f'‖, ‖f‖))^(1/p), h_max).
    fn initial_step<O: Ode + ?Sized>(&mut self, ode: &mut O, t: f64, y: &[f64], t_end: f64) -> f64 {
        let n = self.dim;
        let (atol, rtol) = (self.options.atol, self.options.rtol);
        let f0 = &self.fsal_k;
        let sc = |i: usize| (atol + rtol * y[i].abs()).max(f64::MIN_POSITIVE);
        let rms =
            |g: &dyn Fn(usize) -> f64| ((0..n).map(|i| g(i) * g(i)).sum::<f64>() / n as f64).sqrt();
        let d0 = rms(&|i| y[i] / sc(i));
        let d1 = rms(&|i| f0[i] / sc(i));
        let mut h0 = if d0 < 1e-5 || d1 < 1e-5 {
            1e-6
        } else {
            0.01 * d0 / d1
        };
        h0 = h0.min(self.options.h_max).min(t_end - t);
        let Work { ytmp, k, .. } = &mut self.work;
        let f1 = &mut k[..n];
        for i in 0..n {
            ytmp[i] = y[i] + h0 * f0[i];
        }
        ode.rhs(t + h0, ytmp, f1);
        self.stats.rhs_evaluations += 1;
        let d2 = rms(&|i| (f1[i] - f0[i]) / sc(i)) / h0;
        let p = self.tableau().error_order as f64;
        let h1 = if !d2.is_finite() {
            h0 * 1e-3
        } else {
            let der12 = d2.max(d1);
            if der12 <= 1e-15 {
                (h0 * 1e-3).max(1e-6)
            } else {
                (0.01 / der12).powf(1.0 / p)
            }
        };
        (100.0 * h0)
            .min(h1)
            .min(self.options.h_max)
            .max(self.options.h_min)
    }
}

/// The continuous extension of a step with dense-output vectors `r` (see
/// `Integrator::prepare_dense`) from `y0`, at theta in [0, 1], into `out`.
/// The innermost term comes first and the factors alternate θ (odd r index) and 1-θ; the
/// sum is accumulated in `out` one vector r_j at a time (contiguous, so that it vectorises),
/// with per component the same operations in the same order as a per-component Horner loop.
fn interpolate(r: &[f64], y0: &[f64], theta: f64, out: &mut [f64]) {
    let n = y0.len();
    let m = r.len() / n;
    let th1 = 1.0 - theta;
    let out = &mut out[..n];
    out.fill(0.0);
    for j in (0..m).rev() {
        let f = if j % 2 == 0 { theta } else { th1 };
        for (acc, &rj) in out.iter_mut().zip(&r[j * n..(j + 1) * n]) {
            *acc = (rj + *acc) * f;
        }
    }
    for (acc, &y) in out.iter_mut().zip(y0) {
        *acc += y;
    }
}

/// Most nonzero weights a stage sum can have on the fused path (DOP853's dense-output rows
/// span its 12 stages and 3 extra stages); longer sums take the general loop.
const MAX_TERMS: usize = 16;

/// dst = y + h Σ_j a_j k_j, with k_0 = `k0` and k_j (j ≥ 1) at `k[(j-1)n..jn]`.
/// The increments are summed first and added to y last, as in Hairer's codes, so that
/// round-off does not accumulate in large components of y.
fn combine(dst: &mut [f64], y: &[f64], h: f64, a: &[f64], k0: &[f64], k: &[f64], n: usize) {
    weighted_sum(dst, y, a, k0, k, n, |yi, acc| yi + h * acc);
}

/// dst = Σ_j w_j k_j over the stages (zero weights skipped).
fn stage_sum(dst: &mut [f64], w: &[f64], k0: &[f64], k: &[f64], n: usize) {
    weighted_sum(dst, k0, w, k0, k, n, |_, acc| acc);
}

/// dst_i = finish(y_i, Σ_j w_j k_j,i) over the stages with nonzero weights, in stage order
/// (acc = 0, then acc += w_j k_j,i). The stages with nonzero weights are picked once; one
/// loop over the state then reads each of them and writes dst once ([`fused_sum`]).
fn weighted_sum(
    dst: &mut [f64],
    y: &[f64],
    w: &[f64],
    k0: &[f64],
    k: &[f64],
    n: usize,
    finish: impl Fn(f64, f64) -> f64,
) {
    let mut ws = [0.0; MAX_TERMS];
    let mut ks: [&[f64]; MAX_TERMS] = [&[]; MAX_TERMS];
    let mut m = 0;
    for (j, &wj) in w.iter().enumerate() {
        if wj == 0.0 {
            continue;
        }
        if m == MAX_TERMS {
            return general_sum(dst, y, w, k0, k, n, finish);
        }
        ws[m] = wj;
        ks[m] = if j == 0 {
            &k0[..n]
        } else {
            &k[(j - 1) * n..j * n]
        };
        m += 1;
    }
    let (dst, y) = (&mut dst[..n], &y[..n]);
    macro_rules! fused {
        ($($m:literal)*) => {
            match m {
                $($m => fused_sum::<$m>(
                    dst,
                    y,
                    &ws[..$m].try_into().expect("length checked"),
                    &ks[..$m].try_into().expect("length checked"),
                    finish,
                ),)*
                _ => general_sum(dst, y, w, k0, k, n, finish),
            }
        };
    }
    fused!(0 1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16);
}

/// The fused loop of [`weighted_sum`] for exactly `M` stages: the sum over the stages is
/// unrolled, and the loop over the state has no bounds checks (every slice has length n).
#[inline(always)]
fn fused_sum<const M: usize>(
    dst: &mut [f64],
    y: &[f64],
    w: &[f64; M],
    ks: &[&[f64]; M],
    finish: impl Fn(f64, f64) -> f64,
) {
    let n = dst.len();
    let y = &y[..n];
    let ks: [&[f64]; M] = ks.map(|s| &s[..n]);
    for i in 0..n {
        let mut acc = 0.0;
        for j in 0..M {
            acc += w[j] * ks[j][i];
        }
        dst[i] = finish(y[i], acc);
    }
}

/// [`weighted_sum`] for any number of stages, one stage at a time.
fn general_sum(
    dst: &mut [f64],
    y: &[f64],
    w: &[f64],
    k0: &[f64],
    k: &[f64],
    n: usize,
    finish: impl Fn(f64, f64) -> f64,
) {
    let dst = &mut dst[..n];
    dst.fill(0.0);
    for (j, &wj) in w.iter().enumerate() {
        if wj == 0.0 {
            continue;
        }
        let src = if j == 0 {
            &k0[..n]
        } else {
            &k[(j - 1) * n..j * n]
        };
        for (d, &kv) in dst.iter_mut().zip(src) {
            *d += wj * kv;
        }
    }
    for (d, &yi) in dst.iter_mut().zip(&y[..n]) {
        *d = finish(yi, *d);
    }
}

/// Whether every entry is finite: 0 v is ±0 for a finite entry and NaN for an infinite or
/// NaN one, and a sum with a NaN term is NaN (a branch-free, vectorisable form of
/// `iter().all(is_finite)`; four partial sums so that the additions do not wait on each other).
fn all_finite(v: &[f64]) -> bool {
    let mut acc = [0.0; 4];
    let chunks = v.chunks_exact(4);
    let mut rest = 0.0;
    for &x in chunks.remainder() {
        rest += x * 0.0;
    }
    for c in chunks {
        for j in 0..4 {
            acc[j] += c[j] * 0.0;
        }
    }
    acc[0] + acc[1] + acc[2] + acc[3] + rest == 0.0
}
