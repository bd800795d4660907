//! Special functions and the distribution functions the validation tests need: log-gamma,
//! the regularised incomplete beta function, Student t, Fisher F and standard normal CDFs
//! and quantiles, the Beta density and the modified Bessel function I0.
//!
//! Written here rather than taken from a crate so the whole test chain is visible; the
//! algorithms are the textbook ones (Lanczos log-gamma, Lentz's continued fraction for the
//! incomplete beta as in Numerical Recipes 3rd ed. section 6.4, Acklam's normal quantile
//! refined by one Halley step). Upper tails are computed directly (never as `1 - cdf`) so
//! that p-values as small as 1e-300 keep their digits.

use std::f64::consts::PI;

/// Natural log of the gamma function for `x > 0` (Lanczos approximation, g = 7, 9 terms;
/// relative error below 1e-14 on the positive axis).
pub fn ln_gamma(x: f64) -> f64 {
    const G: f64 = 7.0;
    const COEF: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if x < 0.5 {
        // Reflection: Gamma(x) Gamma(1 - x) = pi / sin(pi x).
        return (PI / (PI * x).sin()).abs().ln() - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let mut a = COEF[0];
    let t = x + G + 0.5;
    for (i, c) in COEF.iter().enumerate().skip(1) {
        a += c / (x + i as f64);
    }
    0.5 * (2.0 * PI).ln() + (x + 0.5) * t.ln() - t + a.ln()
}

/// Log of the Beta function B(a, b).
pub fn ln_beta(a: f64, b: f64) -> f64 {
    ln_gamma(a) + ln_gamma(b) - ln_gamma(a + b)
}

/// Log density of the Beta(a, b) distribution at `x` in (0, 1); `-inf` outside.
pub fn beta_ln_pdf(x: f64, a: f64, b: f64) -> f64 {
    if !(x > 0.0 && x < 1.0) {
        return f64::NEG_INFINITY;
    }
    (a - 1.0) * x.ln() + (b - 1.0) * (1.0 - x).ln() - ln_beta(a, b)
}

/// Continued fraction for the incomplete beta function (modified Lentz method).
fn beta_cf(a: f64, b: f64, x: f64) -> f64 {
    const TINY: f64 = 1e-300;
    const EPS: f64 = 1e-16;
    let qab = a + b;
    let qap = a + 1.0;
    let qam = a - 1.0;
    let mut c = 1.0;
    let mut d = 1.0 - qab * x / qap;
    if d.abs() < TINY {
        d = TINY;
    }
    d = 1.0 / d;
    let mut h = d;
    for m in 1..=10_000 {
        let m = m as f64;
        let m2 = 2.0 * m;
        let aa = m * (b - m) * x / ((qam + m2) * (a + m2));
        d = 1.0 + aa * d;
        if d.abs() < TINY {
            d = TINY;
        }
        c = 1.0 + aa / c;
        if c.abs() < TINY {
            c = TINY;
        }
        d = 1.0 / d;
        h *= d * c;
        let aa = -(a + m) * (qab + m) * x / ((a + m2) * (qap + m2));
        d = 1.0 + aa * d;
        if d.abs() < TINY {
            d = TINY;
        }
        c = 1.0 + aa / c;
        if c.abs() < TINY {
            c = TINY;
        }
        d = 1.0 / d;
        let del = d * c;
        h *= del;
        if (del - 1.0).abs() < EPS {
            break;
        }
    }
    h
}

/// Regularised incomplete beta function I_x(a, b) for a, b > 0 and x in [0, 1].
pub fn beta_inc(a: f64, b: f64, x: f64) -> f64 {
    if x <= 0.0 {
        return 0.0;
    }
    if x >= 1.0 {
        return 1.0;
    }
    let ln_front = a * x.ln() + b * (1.0 - x).ln() - ln_beta(a, b);
    if x < (a + 1.0) / (a + b + 2.0) {
        (ln_front.exp() * beta_cf(a, b, x) / a).clamp(0.0, 1.0)
    } else {
        (1.0 - ln_front.exp() * beta_cf(b, a, 1.0 - x) / b).clamp(0.0, 1.0)
    }
}

/// Upper tail 1 - I_x(a, b), computed without cancellation: I_{1-x}(b, a).
pub fn beta_inc_upper(a: f64, b: f64, x: f64) -> f64 {
    beta_inc(b, a, 1.0 - x)
}

/// CDF of Fisher's F(d1, d2) at `f`.
pub fn f_cdf(f: f64, d1: f64, d2: f64) -> f64 {
    if f <= 0.0 {
        return 0.0;
    }
    beta_inc(0.5 * d1, 0.5 * d2, d1 * f / (d1 * f + d2))
}

/// Survival function P(F > f) of F(d1, d2): the p-value of an F test.
pub fn f_sf(f: f64, d1: f64, d2: f64) -> f64 {
    if f.is_nan() {
        return f64::NAN;
    }
    if f <= 0.0 {
        return 1.0;
    }
    // P(F > f) = I_{d2 / (d2 + d1 f)}(d2/2, d1/2).
    beta_inc(0.5 * d2, 0.5 * d1, d2 / (d2 + d1 * f))
}

/// CDF of Student's t with `nu` degrees of freedom.
pub fn t_cdf(t: f64, nu: f64) -> f64 {
    let tail = 0.5 * beta_inc(0.5 * nu, 0.5, nu / (nu + t * t));
    if t >= 0.0 { 1.0 - tail } else { tail }
}

/// Two-sided p-value P(|T| > |t|) of Student's t with `nu` degrees of freedom.
pub fn t_sf_two_sided(t: f64, nu: f64) -> f64 {
    if t.is_nan() {
        return f64::NAN;
    }
    beta_inc(0.5 * nu, 0.5, nu / (nu + t * t))
}

/// Quantile of Student's t (bisection on [`t_cdf`], 1e-12 absolute).
pub fn t_quantile(p: f64, nu: f64) -> f64 {
    if p <= 0.0 {
        return f64::NEG_INFINITY;
    }
    if p >= 1.0 {
        return f64::INFINITY;
    }
    let (mut lo, mut hi) = (-1.0, 1.0);
    while t_cdf(lo, nu) > p {
        lo *= 2.0;
    }
    while t_cdf(hi, nu) < p {
        hi *= 2.0;
    }
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if t_cdf(mid, nu) < p {
            lo = mid;
        } else {
            hi = mid;
        }
        if hi - lo < 1e-13 * (1.0 + mid.abs()) {
            break;
        }
    }
    0.5 * (lo + hi)
}

/// Complementary error function: Maclaurin series of erf for |x| < 2, Laplace's continued
/// fraction beyond (relative error about 1e-13 or better).
pub fn erfc(x: f64) -> f64 {
    let z = x.abs();
    let r = if z < 2.0 {
        // Series for erf: 2/sqrt(pi) * sum (-1)^n z^(2n+1) / (n! (2n+1)).
        let mut sum = 0.0f64;
        let mut term = z;
        let mut n = 0.0;
        while term.abs() > 1e-17 * sum.abs().max(1e-300) {
            sum += term / (2.0 * n + 1.0);
            n += 1.0;
            term *= -z * z / n;
            if n > 200.0 {
                break;
            }
        }
        1.0 - 2.0 / PI.sqrt() * sum
    } else {
        // Continued fraction (Lentz) for erfc at large z.
        let tiny = 1e-300;
        let mut f = z;
        let mut c = z;
        let mut d = 0.0;
        for k in 1..500 {
            // erfc(z) = exp(-z^2)/sqrt(pi) / (z + (1/2)/(z + 1/(z + (3/2)/(z + ...)))).
            let a = k as f64 * 0.5;
            d = z + a * d;
            if d.abs() < tiny {
                d = tiny;
            }
            c = z + a / c;
            if c.abs() < tiny {
                c = tiny;
            }
            d = 1.0 / d;
            let del = c * d;
            f *= del;
            if (del - 1.0).abs() < 1e-16 {
                break;
            }
        }
        (-z * z).exp() / PI.sqrt() / f
    };
    if x >= 0.0 { r } else { 2.0 - r }
}

/// Standard normal CDF.
pub fn normal_cdf(x: f64) -> f64 {
    0.5 * erfc(-x / std::f64::consts::SQRT_2)
}

/// Standard normal quantile (Acklam's rational approximation, one Halley refinement;
/// relative error near machine precision).
pub fn normal_quantile(p: f64) -> f64 {
    if p <= 0.0 {
        return f64::NEG_INFINITY;
    }
    if p >= 1.0 {
        return f64::INFINITY;
    }
    const A: [f64; 6] = [
        -3.969_683_028_665_376e1,
        2.209_460_984_245_205e2,
        -2.759_285_104_469_687e2,
        1.383_577_518_672_69e2,
        -3.066_479_806_614_716e1,
        2.506_628_277_459_239,
    ];
    const B: [f64; 5] = [
        -5.447_609_879_822_406e1,
        1.615_858_368_580_409e2,
        -1.556_989_798_598_866e2,
        6.680_131_188_771_972e1,
        -1.328_068_155_288_572e1,
    ];
    const C: [f64; 6] = [
        -7.784_894_002_430_293e-3,
        -3.223_964_580_411_365e-1,
        -2.400_758_277_161_838,
        -2.549_732_539_343_734,
        4.374_664_141_464_968,
        2.938_163_982_698_783,
    ];
    const D: [f64; 4] = [
        7.784_695_709_041_462e-3,
        3.224_671_290_700_398e-1,
        2.445_134_137_142_996,
        3.754_408_661_907_416,
    ];
    let plow = 0.02425;
    let x = if p < plow {
        let q = (-2.0 * p.ln()).sqrt();
        (((((C[0] * q + C[1]) * q + C[2]) * q + C[3]) * q + C[4]) * q + C[5])
            / ((((D[0] * q + D[1]) * q + D[2]) * q + D[3]) * q + 1.0)
    } else if p <= 1.0 - plow {
        let q = p - 0.5;
        let r = q * q;
        (((((A[0] * r + A[1]) * r + A[2]) * r + A[3]) * r + A[4]) * r + A[5]) * q
            / (((((B[0] * r + B[1]) * r + B[2]) * r + B[3]) * r + B[4]) * r + 1.0)
    } else {
        let q = (-2.0 * (1.0 - p).ln()).sqrt();
        -(((((C[0] * q + C[1]) * q + C[2]) * q + C[3]) * q + C[4]) * q + C[5])
            / ((((D[0] * q + D[1]) * q + D[2]) * q + D[3]) * q + 1.0)
    };
    // One Halley step on Phi(x) - p.
    let e = normal_cdf(x) - p;
    let u = e * (2.0 * PI).sqrt() * (0.5 * x * x).exp();
    x - u / (1.0 + 0.5 * x * u)
}

/// Modified Bessel function of the first kind, order zero (power series; converges for
/// every argument used by the Kaiser window).
pub fn bessel_i0(x: f64) -> f64 {
    let y = 0.25 * x * x;
    let mut term = 1.0;
    let mut sum = 1.0;
    let mut k = 1.0;
    while term > 1e-17 * sum {
        term *= y / (k * k);
        sum += term;
        k += 1.0;
    }
    sum
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gamma_matches_factorials() {
        for n in 1..20u32 {
            let fact: f64 = (1..n).map(f64::from).product();
            assert!((ln_gamma(f64::from(n)) - fact.ln()).abs() < 1e-12);
        }
        assert!((ln_gamma(0.5) - PI.sqrt().ln()).abs() < 1e-13);
    }

    #[test]
    fn beta_inc_symmetry_and_known_values() {
        // I_x(1, 1) = x; I_x(a, b) = 1 - I_{1-x}(b, a).
        assert!((beta_inc(1.0, 1.0, 0.3) - 0.3).abs() < 1e-14);
        let v = beta_inc(2.5, 4.0, 0.35);
        assert!((v + beta_inc(4.0, 2.5, 0.65) - 1.0).abs() < 1e-13);
        // I_x(a, 1) = x^a.
        assert!((beta_inc(3.2, 1.0, 0.7) - 0.7f64.powf(3.2)).abs() < 1e-13);
    }

    #[test]
    fn t_and_normal_quantiles_invert_cdfs() {
        assert!((normal_quantile(0.975) - 1.959_963_984_540_054).abs() < 1e-12);
        assert!((normal_cdf(1.959_963_984_540_054) - 0.975).abs() < 1e-14);
        assert!((normal_cdf(-8.0) - 6.220_960_574_271_785e-16).abs() < 1e-27);
        let q = t_quantile(0.975, 10.0);
        assert!((q - 2.228_138_851_986_273_5).abs() < 1e-9);
        // F(1, nu) is t^2: P(F > t^2) = P(|T| > t).
        let t = 1.7;
        assert!((f_sf(t * t, 1.0, 12.0) - t_sf_two_sided(t, 12.0)).abs() < 1e-13);
    }

    #[test]
    fn bessel_i0_known_value() {
        assert!((bessel_i0(5.0) - 27.239_871_823_604_45).abs() < 1e-11);
    }
}
