//! The stiff method (ROS34PW2, `Method::Rosenbrock`): observed order on a stiff linear
//! system and on a time-dependent problem, stiff benchmarks (Van der Pol with mu = 1000,
//! Robertson) against Dormand-Prince, dense output, the sparse-Jacobian path, and
//! serialisation.

use breathing_torso::solver::{
    Integrator, Jacobian, JacobianStructure, Method, Ode, Options, Pattern, StiffOde,
};

/// y' = A y with A = T diag(-1, -1000) T^{-1}, T = [[1, 1], [1, 2]]; exact solution known.
struct StiffLinear;
const LAMBDA: [f64; 2] = [-1.0, -1000.0];
fn linear_exact(t: f64) -> [f64; 2] {
    // y(0) = T (1, 1)
    let (a, b) = ((LAMBDA[0] * t).exp(), (LAMBDA[1] * t).exp());
    [a + b, a + 2.0 * b]
}
impl Ode for StiffLinear {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&mut self, _t: f64, y: &[f64], d: &mut [f64]) {
        // T^{-1} = [[2, -1], [-1, 1]]
        let z = [2.0 * y[0] - y[1], -y[0] + y[1]];
        let w = [LAMBDA[0] * z[0], LAMBDA[1] * z[1]];
        d[0] = w[0] + w[1];
        d[1] = w[0] + 2.0 * w[1];
    }
}

/// Prothero-Robinson with a mild λ: y' = λ (y - sin t) + cos t, y = sin t (time-dependent).
struct Prothero(f64);
impl Ode for Prothero {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&mut self, t: f64, y: &[f64], d: &mut [f64]) {
        d[0] = self.0 * (y[0] - t.sin()) + t.cos();
    }
}

fn fixed<O: Ode>(ode: &mut O, y0: &[f64], t_end: f64, n: u32) -> Vec<f64> {
    let mut it = Integrator::new(Method::Rosenbrock, Options::default(), y0.len()).unwrap();
    let (mut t, mut y) = (0.0, y0.to_vec());
    it.integrate_fixed(ode, &mut t, &mut y, t_end, t_end / n as f64)
        .unwrap();
    assert_eq!(it.stats().steps, n as u64);
    y
}

fn observed_order(errors: &[(u32, f64)]) -> f64 {
    let (a, b) = (errors[errors.len() - 2], errors[errors.len() - 1]);
    (a.1 / b.1).ln() / (b.0 as f64 / a.0 as f64).ln()
}

#[test]
fn order_three_on_a_stiff_linear_system() {
    // h from 0.1 down to 0.0125: h λ_stiff from -100 to -12.5 (the stiff mode is damped by
    // L-stability), the smooth mode's error decides the order
    let t_end = 2.0;
    let exact = linear_exact(t_end);
    let errs: Vec<(u32, f64)> = [20u32, 40, 80, 160]
        .iter()
        .map(|&n| {
            let y = fixed(&mut StiffLinear, &linear_exact(0.0), t_end, n);
            (n, (y[0] - exact[0]).abs().max((y[1] - exact[1]).abs()))
        })
        .collect();
    let p = observed_order(&errs);
    println!("stiff linear: {errs:?}, order {p:.2}");
    assert!((p - 3.0).abs() < 0.3, "observed order {p} ({errs:?})");
}

#[test]
fn order_three_on_a_time_dependent_problem() {
    let t_end = 3.0;
    let errs: Vec<(u32, f64)> = [16u32, 32, 64, 128]
        .iter()
        .map(|&n| {
            let y = fixed(&mut Prothero(-2.0), &[0.0], t_end, n);
            (n, (y[0] - t_end.sin()).abs())
        })
        .collect();
    let p = observed_order(&errs);
    println!("Prothero-Robinson: {errs:?}, order {p:.2}");
    assert!((p - 3.0).abs() < 0.3, "observed order {p} ({errs:?})");
}

/// Van der Pol, mu = 1000 (Hairer & Wanner II, Sec. IV.1): y1' = y2,
/// y2' = mu ((1 - y1^2) y2 - y1).
struct VanDerPol(f64);
impl Ode for VanDerPol {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&mut self, _t: f64, y: &[f64], d: &mut [f64]) {
        d[0] = y[1];
        d[1] = self.0 * (1.0 - y[0] * y[0]) * y[1] - y[0];
    }
}

fn opts(rtol: f64, atol: f64) -> Options {
    Options {
        rtol,
        atol,
        ..Options::default()
    }
}

#[test]
fn van_der_pol_mu_1000_takes_few_steps() {
    let t_end = 3000.0;
    let mut ros = Integrator::new(Method::Rosenbrock, opts(1e-6, 1e-6), 2).unwrap();
    let (mut t, mut y) = (0.0, [2.0, 0.0]);
    ros.integrate(&mut VanDerPol(1000.0), &mut t, &mut y, t_end)
        .unwrap();
    let s = ros.stats();
    println!("rosenbrock VdP: {s:?}, y = {y:?}");
    // after one and a half periods of the relaxation oscillation (period about 1614 for
    // mu = 1000) y1 is near -1.5 .. -2
    assert!(y[0] < -1.0 && y[0] > -2.1, "y = {y:?}");
    assert!(s.steps < 5_000, "{s:?}");
    // Dormand-Prince over a tenth of the span already needs far more steps
    let mut dp = Integrator::new(Method::Dopri5, opts(1e-6, 1e-6), 2).unwrap();
    let (mut t2, mut y2) = (0.0, [2.0, 0.0]);
    dp.integrate(&mut VanDerPol(1000.0), &mut t2, &mut y2, t_end / 10.0)
        .unwrap();
    println!("dopri5 VdP (a tenth of the span): {:?}", dp.stats());
    assert!(dp.stats().steps > 10 * s.steps, "{:?} vs {s:?}", dp.stats());
}

/// Robertson's chemical kinetics (Hairer & Wanner II, Sec. IV.1).
struct Robertson;
impl Ode for Robertson {
    fn dim(&self) -> usize {
        3
    }
    fn rhs(&mut self, _t: f64, y: &[f64], d: &mut [f64]) {
        d[0] = -0.04 * y[0] + 1e4 * y[1] * y[2];
        d[2] = 3e7 * y[1] * y[1];
        d[1] = -d[0] - d[2];
    }
}

#[test]
fn robertson_to_1e5_with_few_steps() {
    let mut ros = Integrator::new(Method::Rosenbrock, opts(1e-6, 1e-10), 3).unwrap();
    let (mut t, mut y) = (0.0, [1.0, 0.0, 0.0]);
    ros.integrate(&mut Robertson, &mut t, &mut y, 1e5).unwrap();
    let s = ros.stats();
    println!("Robertson at 1e5: {y:?}, {s:?}");
    // reference (Hairer & Wanner's RADAU5 at tight tolerance): y1(1e5) = 1.7832e-2,
    // y3(1e5) = 0.98217
    assert!((y[0] - 1.7832e-2).abs() < 2e-4, "{y:?}");
    assert!((y[2] - 0.98217).abs() < 2e-4, "{y:?}");
    assert!((y.iter().sum::<f64>() - 1.0).abs() < 1e-9);
    assert!(s.steps < 2_000, "{s:?}");
    // Dormand-Prince is stability-limited to h ~ 3.3/|λ| ~ 1e-3 once y2 settles: it cannot
    // reach t = 10 within the steps the stiff method needs for t = 1e5
    let mut dp = Integrator::new(
        Method::Dopri5,
        Options {
            max_steps: 20 * s.steps,
            ..opts(1e-6, 1e-10)
        },
        3,
    )
    .unwrap();
    let (mut t2, mut y2) = (0.0, [1.0, 0.0, 0.0]);
    assert!(dp.integrate(&mut Robertson, &mut t2, &mut y2, 1e2).is_err());
}

#[test]
fn dense_output_hits_output_times_accurately() {
    let mut it = Integrator::new(Method::Rosenbrock, opts(1e-8, 1e-10), 1).unwrap();
    let (mut t, mut y) = (0.0, [0.0]);
    let times: Vec<f64> = (1..=50).map(|i| i as f64 * 0.1).collect();
    let mut worst = 0.0f64;
    let mut seen = 0;
    it.integrate_dense(
        &mut Prothero(-50.0),
        &mut t,
        &mut y,
        5.0,
        &times,
        |tau, v| {
            worst = worst.max((v[0] - tau.sin()).abs());
            seen += 1;
        },
    )
    .unwrap();
    assert_eq!(seen, 50);
    assert!(worst < 1e-5, "dense output error {worst}");
    assert!((y[0] - 5f64.sin()).abs() < 1e-6);
}

/// A chain of masses on springs and dampers with the sparse Jacobian supplied exactly and
/// a rank-1 coupling (every mass feels the mean position): the sparse path must match the
/// dense-difference path.
struct Chain {
    n: usize,
    k: f64,
    c: f64,
    g: f64,
}
impl Ode for Chain {
    fn dim(&self) -> usize {
        2 * self.n
    }
    fn rhs(&mut self, _t: f64, y: &[f64], d: &mut [f64]) {
        let n = self.n;
        let mean: f64 = y[..n].iter().sum::<f64>() / n as f64;
        for i in 0..n {
            d[i] = y[n + i];
            let left = if i > 0 { y[i - 1] } else { 0.0 };
            let right = if i + 1 < n { y[i + 1] } else { 0.0 };
            let vl = if i > 0 { y[n + i - 1] } else { 0.0 };
            let vr = if i + 1 < n { y[n + i + 1] } else { 0.0 };
            d[n + i] = self.k * (left - 2.0 * y[i] + right) + self.c * (vl - 2.0 * y[n + i] + vr)
                - self.g * mean;
        }
    }
    fn as_stiff(&mut self) -> Option<&mut dyn StiffOde> {
        Some(self)
    }
}
impl StiffOde for Chain {
    fn jacobian_structure(&mut self) -> JacobianStructure {
        let n = self.n;
        let mut rows = vec![Vec::new(); 2 * n];
        for i in 0..n {
            rows[i].push((n + i) as u32);
            for j in i.saturating_sub(1)..(i + 2).min(n) {
                rows[n + i].push(j as u32);
                rows[n + i].push((n + j) as u32);
            }
        }
        JacobianStructure {
            pattern: Pattern::from_rows(rows),
            groups: (0..2 * n as u32).map(|i| i % n as u32).collect(),
            rank: 1,
        }
    }
    fn jacobian(&mut self, _t: f64, _y: &[f64], _f0: &[f64], jac: &mut Jacobian) -> u64 {
        let n = self.n;
        for i in 0..2 * n {
            for e in jac.pattern.row_range(i) {
                let j = jac.pattern.row(i)[e - jac.pattern.row_range(i).start] as usize;
                jac.values[e] = if i < n {
                    1.0
                } else {
                    let r = i - n;
                    let (col, scale) = if j < n { (j, self.k) } else { (j - n, self.c) };
                    if col == r { -2.0 * scale } else { scale }
                };
            }
        }
        for i in 0..2 * n {
            jac.u[i] = if i >= n { -self.g } else { 0.0 };
            jac.v[i] = if i < n { 1.0 / n as f64 } else { 0.0 };
        }
        0
    }
}

#[test]
fn sparse_low_rank_path_matches_dense_path() {
    let n = 30;
    let y0: Vec<f64> = (0..2 * n)
        .map(|i| if i < n { (i as f64 * 0.3).sin() } else { 0.0 })
        .collect();
    let run = |sparse: bool| {
        let mut it = Integrator::new(Method::Rosenbrock, opts(1e-8, 1e-10), 2 * n).unwrap();
        let (mut t, mut y) = (0.0, y0.clone());
        let mut chain = Chain {
            n,
            k: 1e4,
            c: 1e3,
            g: 50.0,
        };
        if sparse {
            it.integrate(&mut chain, &mut t, &mut y, 1.0).unwrap();
        } else {
            struct Plain<'a>(&'a mut Chain);
            impl Ode for Plain<'_> {
                fn dim(&self) -> usize {
                    self.0.dim()
                }
                fn rhs(&mut self, t: f64, y: &[f64], d: &mut [f64]) {
                    self.0.rhs(t, y, d)
                }
            }
            it.integrate(&mut Plain(&mut chain), &mut t, &mut y, 1.0)
                .unwrap();
        }
        (y, it.stats())
    };
    let (ys, ss) = run(true);
    let (yd, sd) = run(false);
    println!("sparse {ss:?}\ndense {sd:?}");
    let diff = ys
        .iter()
        .zip(&yd)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(diff < 1e-6, "sparse and dense paths differ by {diff}");
    assert!(ss.jacobian_evaluations >= 1 && ss.factorizations >= 1);
    // the supplied Jacobian costs no evaluations: fewer than the dense differences
    assert!(ss.rhs_evaluations < sd.rhs_evaluations, "{ss:?} vs {sd:?}");
}

#[test]
fn serde_round_trip_continues_within_tolerance() {
    let mut a = Integrator::new(Method::Rosenbrock, opts(1e-8, 1e-10), 2).unwrap();
    let (mut t, mut y) = (0.0, [2.0, 0.0]);
    a.integrate(&mut VanDerPol(10.0), &mut t, &mut y, 5.0)
        .unwrap();
    let json = serde_json::to_string(&a).unwrap();
    let mut b: Integrator = serde_json::from_str(&json).unwrap();
    assert_eq!(b.method(), Method::Rosenbrock);
    assert_eq!(b.stats(), a.stats());
    let (mut ta, mut ya) = (t, y);
    let (mut tb, mut yb) = (t, y);
    a.integrate(&mut VanDerPol(10.0), &mut ta, &mut ya, 10.0)
        .unwrap();
    b.integrate(&mut VanDerPol(10.0), &mut tb, &mut yb, 10.0)
        .unwrap();
    assert_eq!(ta, tb);
    assert!((ya[0] - yb[0]).abs() < 1e-5, "{ya:?} vs {yb:?}");
}

#[test]
fn method_is_named_and_coded() {
    assert_eq!(Method::from_name("rosenbrock"), Some(Method::Rosenbrock));
    assert_eq!(Method::from_code(3), Some(Method::Rosenbrock));
    assert_eq!(Method::Rosenbrock.code(), 3);
    assert!(Method::Rosenbrock.tableau().is_none());
}

/// A damped oscillator x' = v, v' = -w0^2 x - 2 zeta w0 v (w0 = 2 pi 2 Hz, zeta = 0.3),
/// optionally giving its velocity the error weight `weight` ([`Ode::error_weights`]), or
/// integrated in the rescaled velocity u = v / `scale` without weights.
struct Oscillator {
    weight: Option<[f64; 2]>,
    scale: f64,
}
const REFERENCE: [u32; 2] = [0, 1];
const W0: f64 = 2.0 * std::f64::consts::PI * 2.0;
const ZETA: f64 = 0.3;
impl Ode for Oscillator {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&mut self, _t: f64, y: &[f64], d: &mut [f64]) {
        let v = self.scale * y[1];
        d[0] = v;
        d[1] = (-W0 * W0 * y[0] - 2.0 * ZETA * W0 * v) / self.scale;
    }
    fn error_weights(&self) -> Option<breathing_torso::solver::ErrorWeights<'_>> {
        self.weight
            .as_ref()
            .map(|w| breathing_torso::solver::ErrorWeights {
                reference: &REFERENCE,
                weight: w,
            })
    }
}

/// The stiff method reads the problem's error weights as the explicit pairs do: a weight w
/// on the velocity's absolute tolerance is the same norm as integrating u = v / w with no
/// weights (scale atol_v = w atol, |e_v| / scale = |e_u| / (atol + rtol |u|) when the
/// relative part refers to the component itself and atol dominates), so the two runs take
/// the same steps; without the weight (the stiff method's old norm) it takes more.
#[test]
fn error_weights_are_those_of_the_explicit_pairs() {
    // rtol 0: the norm is purely absolute, so the equivalence is exact
    let o = Options {
        rtol: 0.0,
        atol: 1e-7,
        ..Options::default()
    };
    let w = 50.0;
    let run = |ode: &mut Oscillator, y0: [f64; 2]| {
        let mut s = Integrator::new(Method::Rosenbrock, o, 2).unwrap();
        let (mut t, mut y) = (0.0, y0);
        s.integrate(ode, &mut t, &mut y, 3.0).unwrap();
        (s.stats().steps + s.stats().rejected, y)
    };
    let (weighted, yw) = run(
        &mut Oscillator {
            weight: Some([1.0, w]),
            scale: 1.0,
        },
        [0.01, 0.0],
    );
    let (rescaled, yr) = run(
        &mut Oscillator {
            weight: None,
            scale: w,
        },
        [0.01, 0.0],
    );
    let (plain, _) = run(
        &mut Oscillator {
            weight: None,
            scale: 1.0,
        },
        [0.01, 0.0],
    );
    println!("attempts: weighted {weighted}, rescaled {rescaled}, unweighted {plain}");
    // the same norm, so the same steps; the positions then differ by rounding only (the
    // rescaled run's velocities are w times larger), far below atol = 1e-7: 1e-9 = atol / 100
    assert_eq!(
        weighted, rescaled,
        "step attempts, weighted against rescaled"
    );
    assert!((yw[0] - yr[0]).abs() < 1e-9, "{} vs {}", yw[0], yr[0]);
    // the unweighted norm holds the velocity to atol: more steps (not w^(1/3) = 3.7 times
    // more, as the position's error bounds the steps where the velocity passes zero)
    assert!(
        plain as f64 > 1.1 * weighted as f64,
        "{plain} vs {weighted}"
    );
}

/// Communication points cost the stiff method no step of its own: with
/// [`Integrator::integrate_ahead`] at 56 Hz it takes as many steps as one call to the end
/// (and fewer than a run stopping at every point), and its Hermite states at the points stay
/// within reach of the exact solution (10 rtol of the amplitude) and, at each point, within
/// rtol of the amplitude of the run that ends a step there. Both runs hold each step's error
/// to rtol |y| + atol with atol = rtol / 1000 (so rtol of the 0.01 amplitude, 10 atol), and
/// the cubic interpolant's error, O(h^4), is below the step's own; a linear interpolant's,
/// h^2 |y''| / 8, is not (at rtol 1e-3, 24 ms steps: about 1.1e-5 against the bound 1e-5;
/// at rtol 1e-5 the steps shrink as rtol^(1/3) only, so it exceeds the bound several times).
#[test]
fn integrate_ahead_does_not_clip_the_steps() {
    let amplitude = 0.01;
    for rtol in [1e-3, 1e-5] {
        let o = opts(rtol, rtol * 1e-3);
        let mut ode = Oscillator {
            weight: None,
            scale: 1.0,
        };
        let mut one = Integrator::new(Method::Rosenbrock, o, 2).unwrap();
        let (mut t, mut y) = (0.0, [amplitude, 0.0]);
        one.integrate(&mut ode, &mut t, &mut y, 3.0).unwrap();
        let mut ahead = Integrator::new(Method::Rosenbrock, o, 2).unwrap();
        let mut clipped = Integrator::new(Method::Rosenbrock, o, 2).unwrap();
        let (mut t, mut y) = (0.0, [amplitude, 0.0]);
        let (mut tc, mut yc) = (0.0, [amplitude, 0.0]);
        let (mut worst, mut worst_clipped) = (0.0f64, 0.0f64);
        for i in 1..=168 {
            let tau = i as f64 / 56.0;
            ahead
                .integrate_ahead(&mut ode, &mut t, &mut y, tau)
                .unwrap();
            clipped.integrate(&mut ode, &mut tc, &mut yc, tau).unwrap();
            assert_eq!(t, tau);
            // exact solution of the underdamped oscillator
            let wd = W0 * (1.0 - ZETA * ZETA).sqrt();
            let x = amplitude
                * (-ZETA * W0 * tau).exp()
                * ((wd * tau).cos() + ZETA * W0 / wd * (wd * tau).sin());
            worst = worst.max((y[0] - x).abs());
            let d = (y[0] - yc[0]).abs();
            worst_clipped = worst_clipped.max(d);
            assert!(
                d <= rtol * amplitude,
                "rtol {rtol:e}, t = {tau}: {} ahead against {} clipped",
                y[0],
                yc[0]
            );
        }
        let (s1, sa, sc) = (
            one.stats().steps,
            ahead.stats().steps,
            clipped.stats().steps,
        );
        println!(
            "rtol {rtol:e}: steps one call {s1}, ahead {sa}, clipped {sc}; worst error \
             {worst:.2e}, against the clipped run {worst_clipped:.2e}"
        );
        assert!(sa <= s1 + 1, "{sa} steps ahead vs {s1} in one call");
        assert!(sc >= 168 && sa < sc, "ahead {sa}, clipped {sc}");
        assert!(worst < 10.0 * rtol * amplitude, "worst error {worst:e}");
    }
}
