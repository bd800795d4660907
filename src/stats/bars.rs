//! BARS: Bayesian adaptive regression splines (DiMatteo, Genovese & Kass 2001, Biometrika
//! 88:1055-1071; thesis 4.4.4), and the equality test of two curves on a joint knot set
//! (Behseta & Kass 2005, Statistics in Medicine 24:3523-3534, as reconstructed in the
//! project's statistics reference; marked [R] there: the original test is not reproduced
//! verbatim).
//!
//! Model: `y_i = f(t_i) + e_i`, `t` rescaled to [0, 1], `f` a natural cubic spline with `k`
//! interior knots, i.e. `k + 2` basis functions including the constant (boundary knots at 0
//! and 1). The basis is built from the clamped cubic B-splines (de Boor) constrained to
//! `f''(0) = f''(1) = 0`; it spans the same space as the truncated-power natural basis of
//! Hastie, Tibshirani & Friedman (ESL eq. 5.4-5.5) but is banded, so each fit costs O(n)
//! whatever the number of knots and stays well conditioned. Prior on `k`: uniform on
//! `1..=60`; knots: ordered uniform; coefficients: unit-information prior, so the marginal
//! likelihood ratio is the BIC one, `p(y|xi') / p(y|xi) ~ n^((k - k')/2) (RSS / RSS')^(n/2)`.
//!
//! Reversible-jump moves with `c = 0.4`, `tau = 50`: birth with probability
//! `b_k = c min(1, pi(k+1)/pi(k))`, death `d_k = c min(1, pi(k-1)/pi(k))`, relocation
//! otherwise. Proposals pick an existing knot `s` uniformly and draw `t ~ Beta(tau s,
//! tau (1 - s))`. Acceptance, with `l = -(n/2) log RSS`:
//! - birth: `exp(l' - l + log k - log sum_r Beta(t; tau r, tau (1-r)) - 0.5 log n)`,
//! - death: `exp(l' - l - log(k - 1) + log sum_{r != t} Beta(t; tau r, tau (1-r)) + 0.5 log n)`,
//! - relocation: `exp(l' - l + log Beta(s; tau t, tau (1-t)) - log Beta(t; tau s, tau (1-s)))`,
//!
//! each multiplied by `d_{k+1} / b_k` (resp. `b_{k-1} / d_k`), which is 1 inside the
//! uniform prior's range. Knot sets whose basis is numerically rank deficient (two knots
//! closer than the data resolve) are given zero prior mass, i.e. rejected.
//!
//! The chain starts from the equally spaced knot set with the best BIC among `k = 1..=60`
//! (so a short burn-in suffices), runs `burn_in` iterations (200) then `samples` (2000),
//! all driven by a seeded [`Pcg64`](crate::numeric::rng::Pcg64): the same seed gives the same fit.
//! At each retained iteration the fitted curve is recorded (its average is the posterior
//! mean curve) and one curve is drawn from `N(beta_hat, sigma^2 (B'B)^-1)`, whose pointwise
//! 2.5 and 97.5 % quantiles make the 95 % band.
//!
//! Equality of two curves on the same grid [R]: BARS is run on the pooled data (both
//! series, `N = 2n` points; with one grid the pooled residual sum of squares is
//! `2 RSS(m) + |y1 - y2|^2 / 2` with `m` the average series). For each retained knot set
//! with `p` columns, `log B10 = (N/2) log(RSS_0 / RSS_1) - (p/2) log N` where `RSS_0` is the
//! pooled fit (one coefficient vector) and `RSS_1 = RSS(y1) + RSS(y2)` (one vector each);
//! `P(H0 | xi, data) = 1 / (1 + B10)` (even prior odds) and `P(H0 | data)` is its average
//! over the knot draws. The companion modified Hotelling `T^2 = d' (S1 + S2)^-1 d` on the
//! coefficient difference, with `S_j = sigma_j^2 (B'B)^-1`, reduces on one grid to
//! `|f1_hat - f2_hat|^2 / (sigma_1^2 + sigma_2^2)`; it is reported at the knot draw with
//! the best BIC with the screening p-value of `T^2 / p ~ F(p, 2(n - p))`.

use super::special::{beta_ln_pdf, f_sf};
use crate::numeric::rng::Pcg64;
use crate::{Error, Result};
use serde::Serialize;

/// Settings of a BARS run (defaults: the public implementation's and the thesis's).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct BarsConfig {
    /// Iterations discarded before sampling.
    pub burn_in: usize,
    /// Iterations retained.
    pub samples: usize,
    /// Jump-probability constant c.
    pub c: f64,
    /// Concentration of the Beta knot proposals tau.
    pub tau: f64,
    /// Smallest number of interior knots.
    pub k_min: usize,
    /// Largest number of interior knots.
    pub k_max: usize,
    /// Seed of the random number generator.
    pub seed: u64,
}

impl Default for BarsConfig {
    fn default() -> Self {
        BarsConfig {
            burn_in: 200,
            samples: 2000,
            c: 0.4,
            tau: 50.0,
            k_min: 1,
            k_max: 60,
            seed: 1,
        }
    }
}

impl BarsConfig {
    fn validate(&self) -> Result<()> {
        if self.samples == 0 {
            return Err(Error::invalid("BARS samples", self.samples, ">= 1"));
        }
        if !(self.c > 0.0 && self.c <= 0.5) {
            return Err(Error::invalid("BARS c", self.c, "(0, 0.5]"));
        }
        if !(self.tau > 0.0 && self.tau.is_finite()) {
            return Err(Error::invalid("BARS tau", self.tau, "(0, inf)"));
        }
        if self.k_min < 1 || self.k_max < self.k_min || self.k_max > 200 {
            return Err(Error::invalid(
                "BARS knot range",
                format!("{}..={}", self.k_min, self.k_max),
                "1 <= k_min <= k_max <= 200",
            ));
        }
        Ok(())
    }
}

/// Acceptance counts of the three move types.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct MoveStats {
    /// Birth proposals / acceptances.
    pub birth: [usize; 2],
    /// Death proposals / acceptances.
    pub death: [usize; 2],
    /// Relocation proposals / acceptances.
    pub relocate: [usize; 2],
}

/// Least-squares fits of several responses on one natural cubic spline basis.
struct SplineFit {
    /// Interior knots in (0, 1), sorted.
    knots: Vec<f64>,
    /// Per data point: first natural-basis index and the W weights of the row of B Z.
    rows: Vec<(usize, [f64; W])>,
    /// Number of natural basis functions p = k + 2.
    p: usize,
    /// Lower Cholesky factor of the Gram matrix (banded, stored dense row-major p x p).
    chol: Vec<f64>,
    /// Coefficients, one vector per response.
    coef: Vec<Vec<f64>>,
    /// Residual sums of squares per response.
    rss: Vec<f64>,
}

impl SplineFit {
    fn p(&self) -> usize {
        self.p
    }
}

/// Width of a row of the natural basis: 4 B-splines, widened by one at each boundary
/// where a constrained coefficient combines two free ones (both ends with few knots).
const W: usize = 6;

/// Data of a BARS problem: abscissae in [0, 1] and the centred responses.
struct Problem {
    x: Vec<f64>,
    ys: Vec<Vec<f64>>,
    means: Vec<f64>,
}

/// Values of the 4 cubic B-splines non-zero on knot span `span` at `x` (Cox-de Boor,
/// Piegl & Tiller, The NURBS Book, algorithm A2.2). `t` is the full knot vector.
fn bspline_values(t: &[f64], span: usize, x: f64) -> [f64; 4] {
    let mut n = [1.0, 0.0, 0.0, 0.0];
    let mut left = [0.0; 4];
    let mut right = [0.0; 4];
    for j in 1..=3 {
        left[j] = x - t[span + 1 - j];
        right[j] = t[span + j] - x;
        let mut saved = 0.0;
        for r in 0..j {
            let temp = n[r] / (right[r + 1] + left[j - r]);
            n[r] = saved + right[r + 1] * temp;
            saved = left[j - r] * temp;
        }
        n[j] = saved;
    }
    n
}

/// Natural-spline map Z from the p = k + 2 free coefficients to the k + 4 clamped B-spline
/// coefficients: for each B-spline, the (index, weight) pairs of its coefficient.
///
/// f''(0) = 0 for a clamped cubic spline reads (c1 - c0) / t4 = (c2 - c1) / t5 (from the
/// B-spline derivative formula), so c2 = c1 + r0 (c1 - c0) with r0 = t5 / t4; the right end
/// is the mirror image, c_{m-3} = c_{m-2} + r1 (c_{m-2} - c_{m-1}).
fn natural_map(knots: &[f64]) -> Vec<Vec<(usize, f64)>> {
    let k = knots.len();
    let m = k + 4;
    let t4 = knots[0];
    let t5 = if k >= 2 { knots[1] } else { 1.0 };
    let s4 = 1.0 - knots[k - 1];
    let s5 = if k >= 2 { 1.0 - knots[k - 2] } else { 1.0 };
    let (r0, r1) = (t5 / t4, s5 / s4);
    let mut z: Vec<Vec<(usize, f64)>> = vec![Vec::new(); m];
    let p = k + 2;
    z[0] = vec![(0, 1.0)];
    z[1] = vec![(1, 1.0)];
    z[2] = vec![(0, -r0), (1, 1.0 + r0)];
    z[m - 1] = vec![(p - 1, 1.0)];
    if k >= 2 {
        z[m - 2] = vec![(p - 2, 1.0)];
        z[m - 3] = vec![(p - 1, -r1), (p - 2, 1.0 + r1)];
        for (j, zj) in z.iter_mut().enumerate().take(m - 3).skip(3) {
            *zj = vec![(j - 1, 1.0)];
        }
    } else {
        // k = 1: c3 = (c2 + r1 c4) / (1 + r1) with c2 from the left-end constraint.
        let w = 1.0 / (1.0 + r1);
        z[3] = vec![(0, -r0 * w), (1, (1.0 + r0) * w), (2, r1 * w)];
    }
    z
}

impl Problem {
    fn new(t: &[f64], ys: &[&[f64]]) -> Result<Problem> {
        let n = t.len();
        if n < 8 {
            return Err(Error::invalid("BARS number of points", n, "at least 8"));
        }
        for y in ys {
            if y.len() != n {
                return Err(Error::invalid(
                    "BARS response length",
                    y.len(),
                    format!("{n}"),
                ));
            }
        }
        let (t0, t1) = (t[0], t[n - 1]);
        if t1.partial_cmp(&t0) != Some(std::cmp::Ordering::Greater)
            || t.windows(2).any(|w| w[1] < w[0])
        {
            return Err(Error::invalid(
                "BARS abscissae",
                "unsorted or constant",
                "non-decreasing with t_last > t_first",
            ));
        }
        let x: Vec<f64> = t.iter().map(|v| (v - t0) / (t1 - t0)).collect();
        let means: Vec<f64> = ys
            .iter()
            .map(|y| y.iter().sum::<f64>() / n as f64)
            .collect();
        let ys = ys
            .iter()
            .zip(&means)
            .map(|(y, m)| y.iter().map(|v| v - m).collect())
            .collect();
        Ok(Problem { x, ys, means })
    }

    /// Fits every response on the natural spline basis of `knots`; `None` when the basis
    /// is numerically degenerate (a basis function without data to determine it).
    fn fit(&self, knots: Vec<f64>) -> Option<SplineFit> {
        let n = self.x.len();
        let k = knots.len();
        let p = k + 2;
        if k == 0 || p + 1 >= n || knots[0] <= 0.0 || knots[k - 1] >= 1.0 {
            return None;
        }
        let mut tv = Vec::with_capacity(k + 8);
        tv.extend_from_slice(&[0.0; 4]);
        tv.extend_from_slice(&knots);
        tv.extend_from_slice(&[1.0; 4]);
        let m = k + 4;
        let z = natural_map(&knots);
        // Per knot span: first natural index and the 4 x W map from B-spline values to the
        // row of B Z (computed once per span, not per data point).
        let maps: Vec<(usize, [[f64; W]; 4])> = (3..m)
            .map(|span| {
                let lo = z[span - 3..=span]
                    .iter()
                    .flatten()
                    .map(|e| e.0)
                    .min()
                    .unwrap_or(0);
                let mut mm = [[0.0; W]; 4];
                for (bi, row) in mm.iter_mut().enumerate() {
                    for &(a, zw) in &z[span - 3 + bi] {
                        row[a - lo] += zw;
                    }
                }
                (lo, mm)
            })
            .collect();
        let mut rows = Vec::with_capacity(n);
        let mut gram = vec![0.0; p * p];
        let mut span = 3;
        for &xv in &self.x {
            while span < m - 1 && xv >= tv[span + 1] {
                span += 1;
            }
            let b = bspline_values(&tv, span, xv);
            // Row of B Z: natural indices lie within [lo, lo + W).
            let (lo, mm) = &maps[span - 3];
            let lo = *lo;
            let mut w = [0.0; W];
            for (bv, row) in b.iter().zip(mm) {
                for (wj, rj) in w.iter_mut().zip(row) {
                    *wj += bv * rj;
                }
            }
            let width = W.min(p - lo);
            for i in 0..width {
                for j in 0..=i {
                    gram[(lo + i) * p + lo + j] += w[i] * w[j];
                }
            }
            rows.push((lo, w));
        }
        let chol = banded_cholesky(gram, p, W - 1)?;
        let mut coef = Vec::with_capacity(self.ys.len());
        let mut rss = Vec::with_capacity(self.ys.len());
        for y in &self.ys {
            let mut b = vec![0.0; p];
            for ((lo, w), yi) in rows.iter().zip(y) {
                for (i, wi) in w.iter().enumerate().take(W.min(p - lo)) {
                    b[lo + i] += wi * yi;
                }
            }
            let beta = chol_solve(&chol, p, &b);
            let mut r = 0.0;
            for ((lo, w), yi) in rows.iter().zip(y) {
                let f: f64 = w
                    .iter()
                    .enumerate()
                    .take(W.min(p - lo))
                    .map(|(i, wi)| wi * beta[lo + i])
                    .sum();
                r += (yi - f) * (yi - f);
            }
            coef.push(beta);
            rss.push(r.max(f64::MIN_POSITIVE));
        }
        Some(SplineFit {
            knots,
            rows,
            p,
            chol,
            coef,
            rss,
        })
    }
}

/// In-place Cholesky factor of a symmetric banded matrix (lower half filled, `band`
/// sub-diagonals); `None` when a pivot is not clearly positive.
fn banded_cholesky(mut a: Vec<f64>, p: usize, band: usize) -> Option<Vec<f64>> {
    let dmax = (0..p).map(|i| a[i * p + i]).fold(0.0, f64::max);
    for j in 0..p {
        let k0 = j.saturating_sub(band);
        let mut s = a[j * p + j];
        for k in k0..j {
            s -= a[j * p + k] * a[j * p + k];
        }
        if s.is_nan() || s <= 1e-10 * dmax {
            return None;
        }
        let d = s.sqrt();
        a[j * p + j] = d;
        for i in j + 1..(j + band + 1).min(p) {
            let mut s = a[i * p + j];
            for k in i.saturating_sub(band)..j {
                s -= a[i * p + k] * a[j * p + k];
            }
            a[i * p + j] = s / d;
        }
    }
    Some(a)
}

/// Solves L L' x = b for row-major lower-triangular L (q x q).
fn chol_solve(l: &[f64], q: usize, b: &[f64]) -> Vec<f64> {
    let mut z = b.to_vec();
    for i in 0..q {
        let mut s = z[i];
        for k in i.saturating_sub(W - 1)..i {
            s -= l[i * q + k] * z[k];
        }
        z[i] = s / l[i * q + i];
    }
    chol_back(l, q, &mut z);
    z
}

/// Solves L' x = z (back substitution only): turns white noise into N(0, (L L')^-1).
fn chol_back(l: &[f64], q: usize, z: &mut [f64]) {
    for i in (0..q).rev() {
        let mut s = z[i];
        for k in i + 1..(i + W).min(q) {
            s -= l[k * q + i] * z[k];
        }
        z[i] = s / l[i * q + i];
    }
}

/// The chain's target: how the log-likelihood is read off a fit.
#[derive(Clone, Copy)]
enum Target {
    /// A single response (index 0), n points.
    Single,
    /// Two responses on one grid, pooled: responses are [y1, y2, m]; N = 2n.
    Pooled { dd_half: f64 },
}

impl Target {
    fn n_eff(&self, n: usize) -> f64 {
        match self {
            Target::Single => n as f64,
            Target::Pooled { .. } => 2.0 * n as f64,
        }
    }

    fn rss(&self, fit: &SplineFit) -> f64 {
        match self {
            Target::Single => fit.rss[0],
            Target::Pooled { dd_half } => 2.0 * fit.rss[2] + dd_half,
        }
    }

    fn loglik(&self, fit: &SplineFit, n: usize) -> f64 {
        -0.5 * self.n_eff(n) * self.rss(fit).ln()
    }
}

/// Log of the proposal mixture density sum_r Beta(t; tau r, tau (1 - r)).
fn log_mixture(t: f64, knots: &[f64], tau: f64, skip: Option<usize>) -> f64 {
    let mut vals: Vec<f64> = knots
        .iter()
        .enumerate()
        .filter(|(i, _)| Some(*i) != skip)
        .map(|(_, &r)| beta_ln_pdf(t, tau * r, tau * (1.0 - r)))
        .collect();
    let m = vals.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if !m.is_finite() {
        return f64::NEG_INFINITY;
    }
    for v in &mut vals {
        *v = (*v - m).exp();
    }
    m + vals.iter().sum::<f64>().ln()
}

/// Runs the reversible-jump chain; `visit` is called at every retained iteration.
fn run_chain(
    prob: &Problem,
    target: Target,
    cfg: &BarsConfig,
    stream: u64,
    mut visit: impl FnMut(&SplineFit, &mut Pcg64),
) -> Result<MoveStats> {
    cfg.validate()?;
    let n = prob.x.len();
    let n_eff = target.n_eff(n);
    let log_n = n_eff.ln();
    let mut rng = Pcg64::new(cfg.seed, stream);
    let k_cap = cfg.k_max.min(n.saturating_sub(4)).max(cfg.k_min);
    // Start: best BIC among equally spaced knot sets.
    let mut cur: Option<(SplineFit, f64)> = None;
    let mut best_bic = f64::NEG_INFINITY;
    for k in cfg.k_min..=k_cap {
        let knots: Vec<f64> = (1..=k).map(|j| j as f64 / (k + 1) as f64).collect();
        if let Some(f) = prob.fit(knots) {
            let l = target.loglik(&f, n);
            let bic = l - 0.5 * f.p() as f64 * log_n;
            if bic > best_bic {
                best_bic = bic;
                cur = Some((f, l));
            }
        }
    }
    let (mut cur, mut l_cur) = cur.ok_or_else(|| Error::Numerical {
        time: 0.0,
        reason: "no spline basis could be fitted to the data".into(),
    })?;
    let mut stats = MoveStats::default();
    let tau = cfg.tau;
    let prob_birth = |k: usize| if k < k_cap { cfg.c } else { 0.0 };
    let prob_death = |k: usize| if k > cfg.k_min { cfg.c } else { 0.0 };
    for it in 0..cfg.burn_in + cfg.samples {
        let k = cur.knots.len();
        let (bk, dk) = (prob_birth(k), prob_death(k));
        let u = rng.uniform();
        let s_idx = rng.below(k);
        let s = cur.knots[s_idx];
        if u < bk {
            stats.birth[0] += 1;
            let t = rng.beta(tau * s, tau * (1.0 - s));
            if t > 0.0 && t < 1.0 {
                let mut knots = cur.knots.clone();
                let pos = knots.partition_point(|&v| v < t);
                knots.insert(pos, t);
                if let Some(f) = prob.fit(knots) {
                    let l_new = target.loglik(&f, n);
                    let log_a = l_new - l_cur + (k as f64).ln()
                        - log_mixture(t, &cur.knots, tau, None)
                        - 0.5 * log_n
                        + (prob_death(k + 1) / bk).ln();
                    if rng.uniform_open().ln() < log_a {
                        stats.birth[1] += 1;
                        cur = f;
                        l_cur = l_new;
                    }
                }
            }
        } else if u < bk + dk {
            stats.death[0] += 1;
            let t = s;
            let mut knots = cur.knots.clone();
            knots.remove(s_idx);
            if let Some(f) = prob.fit(knots) {
                let l_new = target.loglik(&f, n);
                let log_a = l_new - l_cur - ((k - 1) as f64).ln()
                    + log_mixture(t, &cur.knots, tau, Some(s_idx))
                    + 0.5 * log_n
                    + (prob_birth(k - 1) / dk).ln();
                if rng.uniform_open().ln() < log_a {
                    stats.death[1] += 1;
                    cur = f;
                    l_cur = l_new;
                }
            }
        } else {
            stats.relocate[0] += 1;
            let t = rng.beta(tau * s, tau * (1.0 - s));
            if t > 0.0 && t < 1.0 {
                let mut knots = cur.knots.clone();
                knots.remove(s_idx);
                let pos = knots.partition_point(|&v| v < t);
                knots.insert(pos, t);
                if let Some(f) = prob.fit(knots) {
                    let l_new = target.loglik(&f, n);
                    let log_a = l_new - l_cur + beta_ln_pdf(s, tau * t, tau * (1.0 - t))
                        - beta_ln_pdf(t, tau * s, tau * (1.0 - s));
                    if rng.uniform_open().ln() < log_a {
                        stats.relocate[1] += 1;
                        cur = f;
                        l_cur = l_new;
                    }
                }
            }
        }
        if it >= cfg.burn_in {
            visit(&cur, &mut rng);
        }
    }
    Ok(stats)
}

/// Fitted values (original scale) of response `r` of a fit.
fn fitted(fit: &SplineFit, r: usize, mean: f64, n: usize) -> Vec<f64> {
    let c = &fit.coef[r];
    let p = fit.p;
    let mut f = Vec::with_capacity(n);
    for (lo, w) in &fit.rows {
        f.push(
            mean + w
                .iter()
                .enumerate()
                .take(W.min(p - lo))
                .map(|(i, wi)| wi * c[lo + i])
                .sum::<f64>(),
        );
    }
    f
}

/// Adds the curve of coefficient vector `c` to `out`.
fn add_curve(fit: &SplineFit, c: &[f64], out: &mut [f64]) {
    let p = fit.p;
    for (o, (lo, w)) in out.iter_mut().zip(&fit.rows) {
        *o += w
            .iter()
            .enumerate()
            .take(W.min(p - lo))
            .map(|(i, wi)| wi * c[lo + i])
            .sum::<f64>();
    }
}

/// Posterior summary of a BARS fit to one curve.
#[derive(Debug, Clone, Serialize)]
pub struct BarsFit {
    /// Settings used.
    pub config: BarsConfig,
    /// Posterior mean of f at the data abscissae.
    #[serde(skip)]
    pub mean: Vec<f64>,
    /// Pointwise 2.5 % quantile of the posterior curves.
    #[serde(skip)]
    pub lower: Vec<f64>,
    /// Pointwise 97.5 % quantile of the posterior curves.
    #[serde(skip)]
    pub upper: Vec<f64>,
    /// Posterior mean number of interior knots.
    pub knots_mean: f64,
    /// Posterior mode of the number of interior knots.
    pub knots_mode: usize,
    /// Posterior frequency of k = 0, 1, ..., k_max.
    pub knots_histogram: Vec<usize>,
    /// Posterior mean residual standard deviation sqrt(RSS / (n - p)).
    pub sigma: f64,
    /// Root mean square of y - posterior mean.
    pub residual_rms: f64,
    /// Move statistics.
    pub moves: MoveStats,
}

/// Fits BARS to the curve (t, y); `t` non-decreasing (see the module doc).
pub fn bars_fit(t: &[f64], y: &[f64], cfg: &BarsConfig) -> Result<BarsFit> {
    bars_fit_on_stream(t, y, cfg, 0)
}

/// [`bars_fit`] on random stream `stream` of the seed (independent chains for several
/// curves fitted with one seed).
pub fn bars_fit_on_stream(t: &[f64], y: &[f64], cfg: &BarsConfig, stream: u64) -> Result<BarsFit> {
    let prob = Problem::new(t, &[y])?;
    let n = t.len();
    let s = cfg.samples;
    let mut mean = vec![0.0; n];
    let mut draws: Vec<f32> = Vec::with_capacity(n * s);
    let mut hist = vec![0usize; cfg.k_max + 1];
    let mut sigma_sum = 0.0;
    let mut z = Vec::new();
    let moves = run_chain(&prob, Target::Single, cfg, stream, |fit, rng| {
        let f = fitted(fit, 0, prob.means[0], n);
        for (m, v) in mean.iter_mut().zip(&f) {
            *m += v;
        }
        let q = fit.p();
        let sigma = (fit.rss[0] / (n - q) as f64).sqrt();
        sigma_sum += sigma;
        z.clear();
        z.extend((0..q).map(|_| rng.normal() * sigma));
        chol_back(&fit.chol, q, &mut z);
        // Coefficient draw around beta_hat (the basis spans the constant, so this includes
        // the uncertainty of the level).
        let mut g = f;
        add_curve(fit, &z, &mut g);
        draws.extend(g.iter().map(|&v| v as f32));
        hist[fit.knots.len().min(cfg.k_max)] += 1;
    })?;
    for m in &mut mean {
        *m /= s as f64;
    }
    let (lower, upper) = pointwise_band(&draws, n, s);
    let knots_mean = hist
        .iter()
        .enumerate()
        .map(|(k, c)| k as f64 * *c as f64)
        .sum::<f64>()
        / s as f64;
    let knots_mode = hist
        .iter()
        .enumerate()
        .max_by_key(|(_, c)| **c)
        .map_or(0, |(k, _)| k);
    let residual_rms = (y
        .iter()
        .zip(&mean)
        .map(|(a, b)| (a - b) * (a - b))
        .sum::<f64>()
        / n as f64)
        .sqrt();
    Ok(BarsFit {
        config: *cfg,
        mean,
        lower,
        upper,
        knots_mean,
        knots_mode,
        knots_histogram: hist,
        sigma: sigma_sum / s as f64,
        residual_rms,
        moves,
    })
}

/// Pointwise 2.5 / 97.5 % quantiles of `s` draws of length `n` stored draw after draw.
fn pointwise_band(draws: &[f32], n: usize, s: usize) -> (Vec<f64>, Vec<f64>) {
    let mut lower = Vec::with_capacity(n);
    let mut upper = Vec::with_capacity(n);
    let mut col = vec![0f32; s];
    let lo_i = ((0.025 * (s - 1) as f64).round() as usize).min(s - 1);
    let hi_i = ((0.975 * (s - 1) as f64).round() as usize).min(s - 1);
    for i in 0..n {
        for (j, c) in col.iter_mut().enumerate() {
            *c = draws[j * n + i];
        }
        let (_, lo, above) = col.select_nth_unstable_by(lo_i, f32::total_cmp);
        lower.push(f64::from(*lo));
        let hi = if hi_i > lo_i {
            *above
                .select_nth_unstable_by(hi_i - lo_i - 1, f32::total_cmp)
                .1
        } else {
            *lo
        };
        upper.push(f64::from(hi));
    }
    (lower, upper)
}

/// Result of the BARS equality test of two curves.
#[derive(Debug, Clone, Serialize)]
pub struct BarsEquality {
    /// P(H0 | data): posterior probability that both curves are one function, averaged
    /// over the pooled chain's knot draws.
    pub p_h0: f64,
    /// log10 of `p_h0` (finite even when `p_h0` underflows).
    pub log10_p_h0: f64,
    /// P(H0 | xi, data) at the knot draw with the best BIC.
    pub p_h0_at_best: f64,
    /// Posterior mean of log B10.
    pub mean_log_b10: f64,
    /// Modified Hotelling T^2 at the best knot draw.
    pub t2: f64,
    /// Number of spline coefficients p compared by T^2.
    pub t2_df: usize,
    /// Screening p-value of T^2 / p ~ F(p, 2(n - p)).
    pub t2_p_value: f64,
    /// Posterior mean number of interior knots of the pooled chain.
    pub knots_mean: f64,
    /// Move statistics of the pooled chain.
    pub moves: MoveStats,
}

/// The BARS equality test of two curves `y1`, `y2` sampled at the same times `t`.
pub fn bars_equality(t: &[f64], y1: &[f64], y2: &[f64], cfg: &BarsConfig) -> Result<BarsEquality> {
    if y1.len() != y2.len() {
        return Err(Error::invalid(
            "series lengths",
            format!("{} and {}", y1.len(), y2.len()),
            "equal",
        ));
    }
    let m: Vec<f64> = y1.iter().zip(y2).map(|(a, b)| 0.5 * (a + b)).collect();
    let prob = Problem::new(t, &[y1, y2, &m])?;
    let n = t.len();
    // |y1 - y2|^2 / 2 of the centred series plus the mean difference's share.
    let dmean = prob.means[0] - prob.means[1];
    let dd_half = prob.ys[0]
        .iter()
        .zip(&prob.ys[1])
        .map(|(a, b)| (a - b) * (a - b))
        .sum::<f64>()
        / 2.0
        + n as f64 * dmean * dmean / 2.0;
    let target = Target::Pooled { dd_half };
    let big_n = 2.0 * n as f64;
    let mut log_terms = Vec::with_capacity(cfg.samples);
    let mut sum_log_b10 = 0.0;
    let mut best: Option<(f64, f64, f64, usize)> = None; // (bic, log_b10, t2, p)
    let mut k_sum = 0usize;
    let moves = run_chain(&prob, target, cfg, 1000, |fit, _| {
        let p = fit.p();
        // One-vector fit: one intercept for both (the pooled mean); RSS of the pooled data.
        let rss0 = target.rss(fit);
        let rss1 = fit.rss[0] + fit.rss[1] + 0.0;
        let log_b10 = 0.5 * big_n * (rss0 / rss1).ln() - 0.5 * p as f64 * big_n.ln();
        sum_log_b10 += log_b10;
        // log P(H0|xi) = -log(1 + e^{log_b10}).
        let lp = -softplus(log_b10);
        log_terms.push(lp);
        k_sum += fit.knots.len();
        let bic = target.loglik(fit, n) - 0.5 * p as f64 * big_n.ln();
        if best.is_none_or(|b| bic > b.0) {
            let f1 = fitted(fit, 0, prob.means[0], n);
            let f2 = fitted(fit, 1, prob.means[1], n);
            let s1 = fit.rss[0] / (n - p) as f64;
            let s2 = fit.rss[1] / (n - p) as f64;
            let t2 = f1
                .iter()
                .zip(&f2)
                .map(|(a, b)| (a - b) * (a - b))
                .sum::<f64>()
                / (s1 + s2);
            best = Some((bic, log_b10, t2, p));
        }
    })?;
    let mx = log_terms.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let ln_mean =
        mx + (log_terms.iter().map(|v| (v - mx).exp()).sum::<f64>() / log_terms.len() as f64).ln();
    let (_, lb_best, t2, p) = best.unwrap_or((0.0, f64::NAN, f64::NAN, 0));
    Ok(BarsEquality {
        p_h0: ln_mean.exp(),
        log10_p_h0: ln_mean / std::f64::consts::LN_10,
        p_h0_at_best: (-softplus(lb_best)).exp(),
        mean_log_b10: sum_log_b10 / cfg.samples as f64,
        t2,
        t2_df: p,
        t2_p_value: f_sf(t2 / p as f64, p as f64, 2.0 * (n - p) as f64),
        knots_mean: k_sum as f64 / cfg.samples as f64,
        moves,
    })
}

/// log(1 + e^x) without overflow.
fn softplus(x: f64) -> f64 {
    if x > 35.0 { x } else { x.exp().ln_1p() }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn natural_spline_basis_reproduces_cubic_free_line() {
        // A straight line is in the span: RSS zero.
        let t: Vec<f64> = (0..200).map(|i| i as f64 / 199.0).collect();
        let y: Vec<f64> = t.iter().map(|v| 3.0 * v - 1.0).collect();
        let prob = Problem::new(&t, &[&y]).unwrap();
        let fit = prob.fit(vec![0.3, 0.6]).unwrap();
        assert!(fit.rss[0] < 1e-20, "{}", fit.rss[0]);
        assert_eq!(fit.p(), 4);
    }

    #[test]
    fn fitted_spline_is_natural_at_both_ends() {
        // Second derivative of the fitted curve vanishes at x = 0 and x = 1.
        let n = 4001;
        let t: Vec<f64> = (0..n).map(|i| i as f64 / (n - 1) as f64).collect();
        let y: Vec<f64> = t.iter().map(|v| (5.0 * v).sin() + v * v * v).collect();
        for knots in [vec![0.4], vec![0.2, 0.5], vec![0.1, 0.3, 0.35, 0.8, 0.9]] {
            let prob = Problem::new(&t, &[&y]).unwrap();
            let fit = prob.fit(knots.clone()).unwrap();
            let f = fitted(&fit, 0, prob.means[0], n);
            let h = 1.0 / (n - 1) as f64;
            let second = |i: usize| (f[i - 1] - 2.0 * f[i] + f[i + 1]) / (h * h);
            let interior = second(n / 3).abs().max(1.0);
            assert!(
                second(1).abs() < 2e-2 * interior,
                "{knots:?}: {}",
                second(1)
            );
            assert!(
                second(n - 2).abs() < 2e-2 * interior,
                "{knots:?}: {}",
                second(n - 2)
            );
            assert_eq!(fit.p(), knots.len() + 2);
        }
    }

    #[test]
    fn recovers_smooth_curve_and_is_reproducible() {
        // DiMatteo et al. (2001) example 1 shape: a smooth bump, noise sd 0.1.
        let n = 500;
        let t: Vec<f64> = (0..n).map(|i| i as f64 / (n - 1) as f64).collect();
        let truth: Vec<f64> = t
            .iter()
            .map(|&x| {
                (2.0 * std::f64::consts::PI * x).sin() + 2.0 * (-30.0 * (x - 0.5).powi(2)).exp()
            })
            .collect();
        let mut g = Pcg64::new(5, 0);
        let y: Vec<f64> = truth.iter().map(|v| v + 0.1 * g.normal()).collect();
        let cfg = BarsConfig {
            seed: 9,
            samples: 500,
            ..BarsConfig::default()
        };
        let a = bars_fit(&t, &y, &cfg).unwrap();
        let b = bars_fit(&t, &y, &cfg).unwrap();
        assert_eq!(a.mean, b.mean);
        let rmse = (a
            .mean
            .iter()
            .zip(&truth)
            .map(|(m, v)| (m - v) * (m - v))
            .sum::<f64>()
            / n as f64)
            .sqrt();
        assert!(rmse < 0.05, "rmse {rmse}");
    }
}
