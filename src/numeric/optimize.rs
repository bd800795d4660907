//! Derivative-free minimisers over a box: bounded Nelder-Mead with adaptive coefficients,
//! multi-start Nelder-Mead and CMA-ES. They work in the unit cube (each parameter scaled to
//! its range) and keep every trial point inside the box by projection.
//!
//! Nelder-Mead (Nelder & Mead 1965, the thesis's optimiser, section 3.4) in the form of
//! Lagarias, Reeds, Wright & Wright 1998 (SIAM J. Optim. 9(1)), with the dimension-adaptive
//! coefficients of Gao & Han 2012 (Comput. Optim. Appl. 51, eq. 4.1): reflection 1,
//! expansion 1 + 2/n, contraction 3/4 - 1/(2n), shrink 1 - 1/n. Bounds by projection: each
//! trial point is clamped to the box before it is evaluated (the simplex keeps the clamped
//! point, so it never leaves the feasible set).
//!
//! CMA-ES: (mu/mu_w, lambda) with cumulative step-size adaptation, rank-one and rank-mu
//! covariance updates and the default strategy parameters of Hansen 2016 ("The CMA
//! evolution strategy: a tutorial", arXiv:1604.00772, table 1); bounds by projection of the
//! evaluated point plus a quadratic penalty on the distance the sample lay outside
//! (Hansen's boundary handling, simplified), so the distribution is pulled back inside.

use super::rng::Pcg64;
use crate::{Error, Result};
use nalgebra::{DMatrix, DVector};

/// A box: lower and upper bound per parameter.
#[derive(Clone, Debug, PartialEq)]
pub struct Bounds {
    /// Lower bounds.
    pub lo: Vec<f64>,
    /// Upper bounds (each > the lower bound).
    pub hi: Vec<f64>,
}

impl Bounds {
    /// A box from (lo, hi) pairs; errors when a pair is empty or not finite.
    pub fn new(pairs: &[(f64, f64)]) -> Result<Bounds> {
        for (i, &(lo, hi)) in pairs.iter().enumerate() {
            if !(lo.is_finite() && hi.is_finite() && hi > lo) {
                return Err(Error::invalid(
                    format!("bounds of parameter {}", i + 1),
                    format!("[{lo}, {hi}]"),
                    "finite lo < hi",
                ));
            }
        }
        Ok(Bounds {
            lo: pairs.iter().map(|p| p.0).collect(),
            hi: pairs.iter().map(|p| p.1).collect(),
        })
    }

    /// Number of parameters.
    pub fn dim(&self) -> usize {
        self.lo.len()
    }

    fn to_unit(&self, x: &[f64]) -> Vec<f64> {
        x.iter()
            .enumerate()
            .map(|(i, v)| ((v - self.lo[i]) / (self.hi[i] - self.lo[i])).clamp(0.0, 1.0))
            .collect()
    }

    fn unit_to_box(&self, u: &[f64]) -> Vec<f64> {
        u.iter()
            .enumerate()
            .map(|(i, v)| self.lo[i] + v.clamp(0.0, 1.0) * (self.hi[i] - self.lo[i]))
            .collect()
    }
}

/// Settings of [`nelder_mead`].
#[derive(Clone, Debug, PartialEq)]
pub struct NelderMeadOptions {
    /// Largest number of objective evaluations.
    pub max_evals: usize,
    /// Initial simplex edge as a fraction of each parameter's range.
    pub initial_step: f64,
    /// Stop when the simplex's largest vertex distance from the best, in range fractions
    /// (infinity norm), is below this...
    pub x_tol: f64,
    /// ...and its objective values differ from the best by at most
    /// `f_tol + f_rel_tol * |best|`.
    pub f_tol: f64,
    /// Relative part of the objective tolerance.
    pub f_rel_tol: f64,
}

impl Default for NelderMeadOptions {
    fn default() -> Self {
        NelderMeadOptions {
            max_evals: 120,
            initial_step: 0.15,
            x_tol: 2e-3,
            f_tol: 1e-9,
            f_rel_tol: 0.0,
        }
    }
}

/// Result of a minimisation.
#[derive(Clone, Debug, PartialEq)]
pub struct Minimum {
    /// Best parameters found.
    pub x: Vec<f64>,
    /// Objective there.
    pub f: f64,
    /// Objective evaluations used.
    pub evaluations: usize,
    /// Whether the convergence tolerances were met (false: stopped on the budget).
    pub converged: bool,
    /// Objective of the starting point (first evaluation).
    pub f_start: f64,
    /// Evaluations made ahead on a spare objective that the search did not use (not in
    /// `evaluations`; zero without a spare).
    pub unused_ahead: usize,
}

/// An objective evaluated through the box: counts evaluations, remembers the best point and
/// reports progress.
struct Counted<'a> {
    f: &'a mut dyn FnMut(&[f64]) -> Result<f64>,
    bounds: &'a Bounds,
    evaluations: usize,
    best: (Vec<f64>, f64),
    progress: &'a mut dyn FnMut(usize, f64),
    /// A second instance of the same objective, evaluated on another thread (see
    /// [`Spare`]).
    spare: Option<&'a mut Spare<'a>>,
    /// A point evaluated ahead by the spare objective, with its value.
    ahead: Option<(Vec<f64>, f64)>,
    /// Evaluations made ahead that the search did not ask for.
    wasted: usize,
}

/// A second instance of an objective, giving bit for bit the same values as the first,
/// which [`nelder_mead_parallel`] evaluates on another thread, ahead of the search: the
/// point the search is likely to need next, alongside the one it asks for.
pub type Spare<'a> = dyn FnMut(&[f64]) -> Result<f64> + Send + 'a;

impl Counted<'_> {
    fn eval_unit(&mut self, u: &[f64]) -> Result<f64> {
        let x = self.bounds.unit_to_box(u);
        let v = match self.ahead.take() {
            Some((p, v)) if p.as_slice() == u => v,
            other => {
                if other.is_some() {
                    self.wasted += 1;
                }
                (self.f)(&x)?
            }
        };
        self.count(x, v)
    }

    fn count(&mut self, x: Vec<f64>, v: f64) -> Result<f64> {
        let v = if v.is_nan() { f64::INFINITY } else { v };
        self.evaluations += 1;
        if v < self.best.1 {
            self.best = (x, v);
        }
        (self.progress)(self.evaluations, self.best.1);
        Ok(v)
    }

    /// Evaluates `u` as [`Counted::eval_unit`]; with a spare objective, also evaluates
    /// `next` on another thread at the same time and keeps its value for the search's next
    /// request (counted only if it comes).
    fn eval_ahead(&mut self, u: &[f64], next: Option<&[f64]>) -> Result<f64> {
        let (Some(spare), Some(next)) = (self.spare.as_deref_mut(), next) else {
            return self.eval_unit(u);
        };
        if self.ahead.take().is_some() {
            self.wasted += 1;
        }
        let (x, y) = (self.bounds.unit_to_box(u), self.bounds.unit_to_box(next));
        let f = &mut *self.f;
        let (v, w) = std::thread::scope(|scope| {
            let other = scope.spawn(|| spare(&y));
            let v = f(&x);
            let w = other
                .join()
                .unwrap_or_else(|_| Err(Error::State("the spare objective panicked".into())));
            (v, w)
        });
        let v = self.count(x, v?)?;
        self.ahead = Some((next.to_vec(), w?));
        Ok(v)
    }
}

fn project(u: &mut [f64]) {
    for v in u {
        *v = v.clamp(0.0, 1.0);
    }
}

/// Affine combination a + s (b - a), projected onto the unit box.
fn along(a: &[f64], b: &[f64], s: f64) -> Vec<f64> {
    let mut p: Vec<f64> = a.iter().zip(b).map(|(a, b)| a + s * (b - a)).collect();
    project(&mut p);
    p
}

/// Bounded Nelder-Mead from `x0` (see the module doc). `progress(evaluations, best)` is
/// called after each evaluation. An objective error stops the search and is returned.
pub fn nelder_mead(
    f: &mut dyn FnMut(&[f64]) -> Result<f64>,
    x0: &[f64],
    bounds: &Bounds,
    options: &NelderMeadOptions,
    progress: &mut dyn FnMut(usize, f64),
) -> Result<Minimum> {
    nelder_mead_parallel(f, None, x0, bounds, options, progress)
}

/// [`nelder_mead`] with an optional spare instance of the objective evaluated on a second
/// thread. While the search evaluates a reflection, the spare evaluates the point the step
/// is likely to need next: the expansion right after a step that expanded, otherwise the
/// inside contraction; also the initial simplex and shrinks two points at a time. The search itself is unchanged: it takes the same points, in the same order,
/// and its result and evaluation count are those of [`nelder_mead`] when the spare gives the
/// same values; evaluations made ahead and not used are reported in
/// [`Minimum::unused_ahead`].
pub fn nelder_mead_parallel<'a>(
    f: &'a mut dyn FnMut(&[f64]) -> Result<f64>,
    spare: Option<&'a mut Spare<'a>>,
    x0: &[f64],
    bounds: &'a Bounds,
    options: &NelderMeadOptions,
    progress: &'a mut dyn FnMut(usize, f64),
) -> Result<Minimum> {
    let mut counted = Counted {
        f,
        bounds,
        evaluations: 0,
        best: (x0.to_vec(), f64::INFINITY),
        progress,
        spare,
        ahead: None,
        wasted: 0,
    };
    let m = nm_core(
        &mut counted,
        &bounds.to_unit(check_start(x0, bounds)?),
        options,
    )?;
    Ok(Minimum {
        x: counted.best.0,
        f: counted.best.1,
        evaluations: counted.evaluations,
        converged: m.0,
        f_start: m.1,
        unused_ahead: counted.wasted + usize::from(counted.ahead.is_some()),
    })
}

fn check_start<'a>(x0: &'a [f64], bounds: &Bounds) -> Result<&'a [f64]> {
    if x0.len() != bounds.dim() || bounds.dim() == 0 {
        return Err(Error::invalid(
            "starting point",
            format!("{} parameters", x0.len()),
            format!("{} parameters", bounds.dim()),
        ));
    }
    if let Some(i) = x0.iter().position(|v| !v.is_finite()) {
        return Err(Error::invalid(
            format!("starting value of parameter {}", i + 1),
            x0[i],
            "finite",
        ));
    }
    Ok(x0)
}

/// The Nelder-Mead iteration in unit coordinates; returns (converged, f(start)).
fn nm_core(c: &mut Counted, u0: &[f64], o: &NelderMeadOptions) -> Result<(bool, f64)> {
    let n = u0.len();
    let nf = n as f64;
    let (alpha, beta, gamma, delta) = (
        1.0,
        1.0 + 2.0 / nf,
        0.75 - 0.5 / nf,
        if n > 1 { 1.0 - 1.0 / nf } else { 0.5 },
    );
    let budget = c.evaluations + o.max_evals.max(n + 1);
    // Initial simplex: steps along each axis, turned inward at a bound.
    let mut simplex: Vec<(Vec<f64>, f64)> = Vec::with_capacity(n + 1);
    let step = o.initial_step.clamp(1e-6, 0.5);
    let vertices: Vec<Vec<f64>> = (0..n)
        .map(|i| {
            let mut v = u0.to_vec();
            v[i] = if v[i] + step <= 1.0 {
                v[i] + step
            } else {
                v[i] - step
            };
            v
        })
        .collect();
    // with a spare objective, the vertices are evaluated two at a time
    let f0 = c.eval_ahead(u0, vertices.first().map(|v| v.as_slice()))?;
    simplex.push((u0.to_vec(), f0));
    for i in 0..n {
        if c.evaluations >= budget {
            break;
        }
        let v = &vertices[i];
        let fv = if i % 2 == 0 {
            c.eval_unit(v)?
        } else {
            c.eval_ahead(v, vertices.get(i + 1).map(|v| v.as_slice()))?
        };
        simplex.push((v.clone(), fv));
    }
    if simplex.len() < n + 1 {
        return Ok((false, f0));
    }
    let order = |s: &mut Vec<(Vec<f64>, f64)>| s.sort_by(|a, b| a.1.total_cmp(&b.1));
    order(&mut simplex);
    /// What the spare evaluates ahead of a step's reflection: the inside contraction, the
    /// most frequent second point once the search closes in (about two steps in three of a
    /// breathing fit), or the expansion right after a step that expanded.
    #[derive(Clone, Copy, PartialEq)]
    enum Second {
        Expansion,
        Inside,
    }
    let mut last = Second::Inside;
    loop {
        let best = &simplex[0];
        let x_spread = simplex[1..]
            .iter()
            .flat_map(|(v, _)| v.iter().zip(&best.0).map(|(a, b)| (a - b).abs()))
            .fold(0.0, f64::max);
        let f_spread = simplex[n].1 - best.1;
        if x_spread <= o.x_tol && f_spread <= o.f_tol.max(0.0) + o.f_rel_tol.max(0.0) * best.1.abs()
        {
            return Ok((true, f0));
        }
        if c.evaluations >= budget {
            return Ok((false, f0));
        }
        let centroid: Vec<f64> = (0..n)
            .map(|k| simplex[..n].iter().map(|(v, _)| v[k]).sum::<f64>() / nf)
            .collect();
        let worst = simplex[n].clone();
        let xr = along(&centroid, &worst.0, -alpha);
        let guess = match last {
            Second::Expansion => along(&centroid, &xr, beta),
            Second::Inside => along(&centroid, &worst.0, gamma),
        };
        last = Second::Inside;
        let fr = c.eval_ahead(
            &xr,
            (c.evaluations + 1 < budget).then_some(guess.as_slice()),
        )?;
        let (f1, fnn) = (simplex[0].1, simplex[n - 1].1);
        let mut shrink = false;
        if fr < f1 {
            if c.evaluations >= budget {
                simplex[n] = (xr, fr);
            } else {
                let xe = along(&centroid, &xr, beta);
                last = Second::Expansion;
                let fe = c.eval_unit(&xe)?;
                simplex[n] = if fe < fr { (xe, fe) } else { (xr, fr) };
            }
        } else if fr < fnn {
            simplex[n] = (xr, fr);
        } else if c.evaluations >= budget {
            if fr < worst.1 {
                simplex[n] = (xr, fr);
            }
        } else if fr < worst.1 {
            let xo = along(&centroid, &xr, gamma);
            let fo = c.eval_unit(&xo)?;
            if fo <= fr {
                simplex[n] = (xo, fo);
            } else {
                shrink = true;
            }
        } else {
            let xi = along(&centroid, &worst.0, gamma);
            let fi = c.eval_unit(&xi)?;
            if fi < worst.1 {
                simplex[n] = (xi, fi);
            } else {
                shrink = true;
            }
        }
        if shrink {
            let x1 = simplex[0].0.clone();
            let shrunk: Vec<Vec<f64>> = simplex[1..]
                .iter()
                .map(|s| along(&x1, &s.0, delta))
                .collect();
            for (k, v) in shrunk.iter().enumerate() {
                if c.evaluations >= budget {
                    break;
                }
                let fv = if k % 2 == 1 {
                    c.eval_unit(v)?
                } else {
                    let next = shrunk.get(k + 1).filter(|_| c.evaluations + 1 < budget);
                    c.eval_ahead(v, next.map(|v| v.as_slice()))?
                };
                simplex[k + 1] = (v.clone(), fv);
            }
        }
        order(&mut simplex);
    }
}

/// Multi-start Nelder-Mead: `starts` runs sharing the budget, the first from `x0`, the
/// others from a space-filling design (a scrambled stratified sample of the box, fixed by
/// `seed`); a final run polishes the best point with what budget remains.
pub fn multistart(
    f: &mut dyn FnMut(&[f64]) -> Result<f64>,
    x0: &[f64],
    bounds: &Bounds,
    options: &NelderMeadOptions,
    starts: usize,
    seed: u64,
    progress: &mut dyn FnMut(usize, f64),
) -> Result<Minimum> {
    let n = bounds.dim();
    check_start(x0, bounds)?;
    let starts = starts.max(1);
    let mut rng = Pcg64::new(seed, 7);
    // Stratified starts: each coordinate cut into `starts` strata, permuted independently.
    let mut design: Vec<Vec<f64>> = vec![bounds.to_unit(x0)];
    let perms: Vec<Vec<usize>> = (0..n)
        .map(|_| {
            let mut p: Vec<usize> = (0..starts).collect();
            for i in (1..p.len()).rev() {
                p.swap(i, rng.below(i + 1));
            }
            p
        })
        .collect();
    for s in 1..starts {
        let mut u = Vec::with_capacity(n);
        for p in &perms {
            u.push((p[s] as f64 + rng.uniform()) / starts as f64);
        }
        design.push(u);
    }
    let mut counted = Counted {
        f,
        bounds,
        evaluations: 0,
        best: (x0.to_vec(), f64::INFINITY),
        progress,
        spare: None,
        ahead: None,
        wasted: 0,
    };
    // Each start gets an equal share of three quarters of the budget; the polish the rest.
    let share = (3 * options.max_evals / 4 / starts).max(n + 2);
    let mut f_start = f64::NAN;
    let mut converged = false;
    for u in &design {
        if counted.evaluations + n + 1 > options.max_evals {
            break;
        }
        let o = NelderMeadOptions {
            max_evals: share.min(options.max_evals - counted.evaluations),
            ..options.clone()
        };
        let (_, f0) = nm_core(&mut counted, u, &o)?;
        if f_start.is_nan() {
            f_start = f0;
        }
    }
    let left = options.max_evals.saturating_sub(counted.evaluations);
    if left > n + 1 {
        let o = NelderMeadOptions {
            max_evals: left,
            initial_step: options.initial_step * 0.3,
            ..options.clone()
        };
        let u = bounds.to_unit(&counted.best.0);
        converged = nm_core(&mut counted, &u, &o)?.0;
    }
    Ok(Minimum {
        x: counted.best.0,
        f: counted.best.1,
        evaluations: counted.evaluations,
        converged,
        f_start,
        unused_ahead: 0,
    })
}

/// CMA-ES from `x0` with initial step `sigma0` (fraction of each range), population
/// 4 + floor(3 ln n), at most `max_evals` evaluations (see the module doc).
pub fn cmaes(
    f: &mut dyn FnMut(&[f64]) -> Result<f64>,
    x0: &[f64],
    bounds: &Bounds,
    max_evals: usize,
    sigma0: f64,
    seed: u64,
    progress: &mut dyn FnMut(usize, f64),
) -> Result<Minimum> {
    check_start(x0, bounds)?;
    let n = bounds.dim();
    let nf = n as f64;
    let lambda = 4 + (3.0 * nf.ln()).floor() as usize;
    let mu = lambda / 2;
    let raw: Vec<f64> = (0..mu)
        .map(|i| ((lambda as f64 + 1.0) / 2.0).ln() - ((i + 1) as f64).ln())
        .collect();
    let wsum: f64 = raw.iter().sum();
    let w: Vec<f64> = raw.iter().map(|v| v / wsum).collect();
    let mueff = 1.0 / w.iter().map(|v| v * v).sum::<f64>();
    let cc = (4.0 + mueff / nf) / (nf + 4.0 + 2.0 * mueff / nf);
    let cs = (mueff + 2.0) / (nf + mueff + 5.0);
    let c1 = 2.0 / ((nf + 1.3).powi(2) + mueff);
    let cmu = (1.0 - c1).min(2.0 * (mueff - 2.0 + 1.0 / mueff) / ((nf + 2.0).powi(2) + mueff));
    let damps = 1.0 + 2.0 * (0.0f64).max(((mueff - 1.0) / (nf + 1.0)).sqrt() - 1.0) + cs;
    let chin = nf.sqrt() * (1.0 - 1.0 / (4.0 * nf) + 1.0 / (21.0 * nf * nf));

    let mut rng = Pcg64::new(seed, 11);
    let mut mean = DVector::from_vec(bounds.to_unit(x0));
    let mut sigma = sigma0.clamp(1e-3, 0.5);
    let mut cov = DMatrix::<f64>::identity(n, n);
    let (mut pc, mut ps) = (DVector::zeros(n), DVector::zeros(n));
    let mut counted = Counted {
        f,
        bounds,
        evaluations: 0,
        best: (x0.to_vec(), f64::INFINITY),
        progress,
        spare: None,
        ahead: None,
        wasted: 0,
    };
    let f_start = counted.eval_unit(mean.as_slice())?;
    let mut converged = false;
    let mut generation = 0usize;
    while counted.evaluations + lambda <= max_evals {
        generation += 1;
        let eig = cov.clone().symmetric_eigen();
        let d: DVector<f64> = eig.eigenvalues.map(|v| v.max(1e-20).sqrt());
        let b = eig.eigenvectors;
        let mut pop: Vec<(DVector<f64>, DVector<f64>, f64)> = Vec::with_capacity(lambda);
        for _ in 0..lambda {
            let z = DVector::from_fn(n, |_, _| rng.normal());
            let y = &b * z.component_mul(&d);
            let x = &mean + sigma * &y;
            let mut inside = x.as_slice().to_vec();
            project(&mut inside);
            let outside: f64 = x.iter().zip(&inside).map(|(a, b)| (a - b).powi(2)).sum();
            let fx = counted.eval_unit(&inside)?;
            pop.push((x, y, fx + outside * (1.0 + fx.abs())));
        }
        pop.sort_by(|a, b| a.2.total_cmp(&b.2));
        let old = mean.clone();
        mean = DVector::zeros(n);
        let mut yw = DVector::zeros(n);
        for (i, wi) in w.iter().enumerate() {
            mean += *wi * &pop[i].0;
            yw += *wi * &pop[i].1;
        }
        // C^(-1/2) yw = B D^-1 B^T yw.
        let inv_sqrt = &b * DMatrix::from_diagonal(&d.map(|v| 1.0 / v)) * b.transpose();
        ps = (1.0 - cs) * &ps + (cs * (2.0 - cs) * mueff).sqrt() * (&inv_sqrt * &yw);
        let hsig = ps.norm() / (1.0 - (1.0 - cs).powi(2 * generation as i32)).sqrt() / chin
            < 1.4 + 2.0 / (nf + 1.0);
        let hs = if hsig { 1.0 } else { 0.0 };
        pc = (1.0 - cc) * &pc + hs * (cc * (2.0 - cc) * mueff).sqrt() * &yw;
        let mut rank_mu = DMatrix::zeros(n, n);
        for (i, wi) in w.iter().enumerate() {
            rank_mu += *wi * &pop[i].1 * pop[i].1.transpose();
        }
        cov = (1.0 - c1 - cmu) * &cov
            + c1 * (&pc * pc.transpose() + (1.0 - hs) * cc * (2.0 - cc) * &cov)
            + cmu * rank_mu;
        cov = 0.5 * (&cov + cov.transpose());
        sigma *= ((cs / damps) * (ps.norm() / chin - 1.0)).exp();
        sigma = sigma.min(1.0);
        let moved = (&mean - &old).amax();
        if sigma * d.max() < 1e-3 && moved < 1e-3 {
            converged = true;
            break;
        }
    }
    Ok(Minimum {
        x: counted.best.0,
        f: counted.best.1,
        evaluations: counted.evaluations,
        converged,
        f_start,
        unused_ahead: 0,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quiet(_: usize, _: f64) {}

    #[test]
    fn coefficients_follow_gao_han() {
        // A 1-D parabola: the adaptive coefficients with n = 1 still converge.
        let b = Bounds::new(&[(-5.0, 5.0)]).unwrap();
        let mut f = |x: &[f64]| Ok((x[0] - 1.3).powi(2));
        let m = nelder_mead(
            &mut f,
            &[4.0],
            &b,
            &NelderMeadOptions::default(),
            &mut quiet,
        )
        .unwrap();
        assert!((m.x[0] - 1.3).abs() < 1e-2, "{m:?}");
    }

    #[test]
    fn stays_inside_the_box() {
        let b = Bounds::new(&[(0.0, 1.0), (0.0, 1.0)]).unwrap();
        let mut f = |x: &[f64]| {
            assert!(x.iter().all(|v| (0.0..=1.0).contains(v)), "{x:?}");
            Ok((x[0] + 1.0).powi(2) + (x[1] - 0.5).powi(2))
        };
        let m = nelder_mead(
            &mut f,
            &[0.9, 0.9],
            &b,
            &NelderMeadOptions::default(),
            &mut quiet,
        )
        .unwrap();
        assert!(m.x[0] < 1e-3 && (m.x[1] - 0.5).abs() < 1e-2, "{m:?}");
    }

    /// Evaluating ahead on a spare objective leaves the search unchanged: the same points
    /// asked in the same order, the same minimum and count; the spare's evaluations that
    /// were used took their turn on the other thread, and the unused ones are counted.
    #[test]
    fn evaluating_ahead_keeps_the_search() {
        let rosen = |x: &[f64]| {
            (0..x.len() - 1)
                .map(|i| 100.0 * (x[i + 1] - x[i] * x[i]).powi(2) + (1.0 - x[i]).powi(2))
                .sum::<f64>()
        };
        let b = Bounds::new(&[(-2.0, 2.0); 4]).unwrap();
        let o = NelderMeadOptions {
            max_evals: 400,
            ..NelderMeadOptions::default()
        };
        let x0 = [-1.2, 1.0, -0.5, 0.8];
        let mut seq_points = Vec::new();
        let mut f = |x: &[f64]| {
            seq_points.push(x.to_vec());
            Ok(rosen(x))
        };
        let seq = nelder_mead(&mut f, &x0, &b, &o, &mut quiet).unwrap();
        let mut main_points = Vec::new();
        let mut f = |x: &[f64]| {
            main_points.push(x.to_vec());
            Ok(rosen(x))
        };
        let spare_calls = std::sync::atomic::AtomicUsize::new(0);
        let mut g = |x: &[f64]| {
            spare_calls.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            Ok(rosen(x))
        };
        let mut reported = Vec::new();
        let par = nelder_mead_parallel(&mut f, Some(&mut g), &x0, &b, &o, &mut |n, best| {
            reported.push((n, best))
        })
        .unwrap();
        assert_eq!(
            (&par.x, par.f, par.evaluations),
            (&seq.x, seq.f, seq.evaluations)
        );
        assert_eq!(par.converged, seq.converged);
        let ahead = spare_calls.load(std::sync::atomic::Ordering::Relaxed);
        // every point the search asked for came from one of the two objectives, once
        assert_eq!(
            main_points.len() + ahead - par.unused_ahead,
            seq.evaluations
        );
        assert!(
            ahead > seq.evaluations / 4,
            "{ahead} of {}",
            seq.evaluations
        );
        assert_eq!(reported.len(), seq.evaluations);
        assert_eq!(reported.last().map(|r| r.1), Some(seq.f));
        println!(
            "{} evaluations, {} on the spare ({} unused)",
            seq.evaluations, ahead, par.unused_ahead
        );
    }
}
