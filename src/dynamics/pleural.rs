//! The pressure-volume law of the lungs and chest: the pleural pressure as a function of the
//! thoracic volume, its slope (for the Jacobian) and its integral (the elastic energy stored
//! by the lungs, for the energy-dissipation tests).
//!
//! The law is the sigmoidal pressure-volume curve of Venegas, Harris & Simon (1998, J Appl
//! Physiol 84:389, eq. 1), V(P) = a + b / (1 + exp(-(P - c) / d)), inverted to give the recoil
//! pressure from the volume:
//!
//! P(V) = c + d ln((V - a) / (a + b - V)),
//!
//! with its lower asymptote `a` at the residual volume and its upper one `a + b` at the total
//! lung capacity. Its two free constants are set so that the law equals the linear one of
//! constant lung elastance E at the rest volume V0 in value and slope: P(V0) = 0 (pressures
//! are relative to rest) and P'(V0) = d b / ((V0 - a)(a + b - V0)) = E, so quiet breathing
//! about V0 is nearly unchanged while the recoil grows without bound as the volume nears
//! either asymptote. The pleural pressure on the thoracic surface is -P(V).
//!
//! The logarithm has no value at or beyond the asymptotes, yet an explicit solver probes
//! overshooting stages: within a margin of each asymptote (a fraction `m` of the distance from
//! rest to it, [`super::Params::pleural_barrier_margin`]) the law continues along its tangent,
//! so it is C1, increasing and finite for every volume, with a slope there of the order of
//! E / m.

use crate::anatomy::Subject;

/// Where the thorax's volume limits come from: the ECSC/ERS 1993 reference equations (Quanjer
/// et al. 1993, Eur Respir J 6 Suppl 16:5-40) give a subject's residual volume, functional
/// residual capacity and total lung capacity; the model's rest state (muscles relaxed) is its
/// functional residual capacity, so the limits are placed at the same multiples of the rest
/// thoracic volume as RV / FRC and TLC / FRC. Since the lung volume is a fixed ratio of the
/// thoracic volume (thesis 4.2), the lung volume then meets the limits at the subject's RV and
/// TLC scaled to the model's own FRC, whatever the generated geometry's size.
pub fn capacity_ratios(subject: &Subject) -> (f64, f64) {
    let frc = subject.frc_ecsc();
    let rv = subject.rv_ecsc() / frc;
    let tlc = subject.tlc_ecsc() / frc;
    // The equations keep 0.38 <= RV/FRC <= 0.89 and 1.37 <= TLC/FRC <= 2.43 over the declared
    // subject ranges; the clamps only keep rest strictly inside for any future range.
    (
        if rv.is_finite() {
            rv.clamp(0.2, 0.9)
        } else {
            0.5
        },
        if tlc.is_finite() {
            tlc.clamp(1.2, 4.0)
        } else {
            2.0
        },
    )
}

/// The inverted Venegas sigmoid (module doc) fitted to a rest volume and elastance, with
/// tangent continuations beyond its margins. Volumes in m^3, pressures in Pa.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PleuralLaw {
    /// Rest volume V0 (zero pressure).
    pub rest: f64,
    /// Lower asymptote a (residual volume).
    pub lower: f64,
    /// Upper asymptote a + b (total lung capacity).
    pub upper: f64,
    /// Width d of the sigmoid [Pa].
    pub width: f64,
    /// Volume below which the law follows its tangent.
    join_low: f64,
    /// Volume above which the law follows its tangent.
    join_high: f64,
    /// Recoil, slope and energy at the lower join.
    low: [f64; 3],
    /// Recoil, slope and energy at the upper join.
    high: [f64; 3],
}

impl PleuralLaw {
    /// The law with rest volume `rest`, slope `elastance` there [Pa/m^3], asymptotes at
    /// `ratios` = (RV/FRC, TLC/FRC) times `rest`, and tangent continuations a fraction
    /// `margin` of the rest-to-asymptote distance away from each asymptote.
    pub fn new(rest: f64, elastance: f64, ratios: (f64, f64), margin: f64) -> PleuralLaw {
        let lower = rest * ratios.0;
        let upper = rest * ratios.1;
        let (x0, y0) = (rest - lower, upper - rest);
        let width = elastance * x0 * y0 / (upper - lower);
        let mut law = PleuralLaw {
            rest,
            lower,
            upper,
            width,
            join_low: lower + margin * x0,
            join_high: upper - margin * y0,
            low: [0.0; 3],
            high: [0.0; 3],
        };
        for (v, out) in [(law.join_low, 0), (law.join_high, 1)] {
            let values = [law.inner_recoil(v), law.inner_slope(v), law.inner_energy(v)];
            if out == 0 {
                law.low = values;
            } else {
                law.high = values;
            }
        }
        law
    }

    /// Recoil P(V) - P(V0) of the sigmoid itself (inside the joins).
    fn inner_recoil(&self, v: f64) -> f64 {
        let dv = v - self.rest;
        let (x0, y0) = (self.rest - self.lower, self.upper - self.rest);
        self.width * ((dv / x0).ln_1p() - (-dv / y0).ln_1p())
    }

    /// Slope dP/dV of the sigmoid itself.
    fn inner_slope(&self, v: f64) -> f64 {
        self.width * (1.0 / (v - self.lower) + 1.0 / (self.upper - v))
    }

    /// Integral of the recoil from V0 to V (inside the joins): with x = V - a, y = a + b - V,
    /// d (x ln(x/x0) - (x - x0) + y ln(y/y0) - (y - y0)), each term >= 0.
    fn inner_energy(&self, v: f64) -> f64 {
        let dv = v - self.rest;
        let (x0, y0) = (self.rest - self.lower, self.upper - self.rest);
        let (x, y) = (v - self.lower, self.upper - v);
        self.width * (x * (dv / x0).ln_1p() - dv + y * (-dv / y0).ln_1p() + dv)
    }

    /// Elastic recoil pressure P(V) - P(V0) [Pa] at thoracic volume `v` [m^3]; the pleural
    /// pressure is its negative.
    pub fn recoil(&self, v: f64) -> f64 {
        if v < self.join_low {
            self.low[0] + self.low[1] * (v - self.join_low)
        } else if v > self.join_high {
            self.high[0] + self.high[1] * (v - self.join_high)
        } else {
            self.inner_recoil(v)
        }
    }

    /// Slope dP/dV [Pa/m^3] of [`PleuralLaw::recoil`] at `v`.
    pub fn slope(&self, v: f64) -> f64 {
        if v < self.join_low {
            self.low[1]
        } else if v > self.join_high {
            self.high[1]
        } else {
            self.inner_slope(v)
        }
    }

    /// Elastic energy [J] stored at `v`: the integral of [`PleuralLaw::recoil`] from the rest
    /// volume (zero at rest, convex).
    pub fn energy(&self, v: f64) -> f64 {
        let tangent = |[p, k, e]: [f64; 3], s: f64| e + p * s + 0.5 * k * s * s;
        if v < self.join_low {
            tangent(self.low, v - self.join_low)
        } else if v > self.join_high {
            tangent(self.high, v - self.join_high)
        } else {
            self.inner_energy(v)
        }
    }

    /// Volumes [m^3] below and above which the law follows its tangents.
    pub fn joins(&self) -> (f64, f64) {
        (self.join_low, self.join_high)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 1 cmH2O in Pa.
    const CMH2O: f64 = 98.0665;

    /// The default subject's law: rest 4.5 L, 0.2 L/cmH2O.
    fn law() -> PleuralLaw {
        let e = CMH2O / 0.2e-3;
        PleuralLaw::new(
            4.5e-3,
            e,
            capacity_ratios(&Subject::default()),
            crate::dynamics::Params::for_posture(crate::anatomy::Posture::Standing)
                .pleural_barrier_margin,
        )
    }

    #[test]
    fn equals_the_linear_law_at_rest_in_value_and_slope() {
        let l = law();
        let e = CMH2O / 0.2e-3;
        assert_eq!(l.recoil(l.rest), 0.0);
        assert!((l.slope(l.rest) / e - 1.0).abs() < 1e-12);
        // within a quiet breath (+-0.1 L) the two differ by under 5 %
        for dv in [-1e-4, -5e-5, 5e-5, 1e-4] {
            let lin = e * dv;
            let r = l.recoil(l.rest + dv);
            assert!((r / lin - 1.0).abs() < 0.05, "{dv}: {r} vs {lin}");
        }
    }

    #[test]
    fn is_increasing_c1_and_finite_everywhere() {
        let l = law();
        let (j0, j1) = l.joins();
        let mut last = f64::NEG_INFINITY;
        for i in 0..=4000 {
            let v = -1e-3 + 12e-3 * i as f64 / 4000.0;
            let (p, k, w) = (l.recoil(v), l.slope(v), l.energy(v));
            assert!(p.is_finite() && k.is_finite() && w.is_finite(), "{v}");
            assert!(p > last && k > 0.0 && w >= 0.0, "{v}");
            last = p;
        }
        // C1 at the joins: value, slope and energy agree from both sides
        for j in [j0, j1] {
            let h = 1e-12;
            for (a, b) in [
                (l.recoil(j - h), l.recoil(j + h)),
                (l.energy(j - h), l.energy(j + h)),
            ] {
                assert!((a - b).abs() <= 1e-6 * a.abs().max(1e-9), "{a} {b}");
            }
            let (a, b) = (l.slope(j - h), l.slope(j + h));
            assert!((a / b - 1.0).abs() < 1e-6, "{a} {b}");
        }
        assert!(j0 > l.lower && j0 < l.rest && j1 < l.upper && j1 > l.rest);
    }

    #[test]
    fn slope_and_energy_are_the_derivative_and_integral_of_the_recoil() {
        let l = law();
        for v in [
            0.5e-3, 2.0e-3, 2.4e-3, 3.9e-3, 4.5e-3, 6.0e-3, 9.0e-3, 9.6e-3, 11e-3,
        ] {
            let h = 1e-9;
            let dp = (l.recoil(v + h) - l.recoil(v - h)) / (2.0 * h);
            assert!(
                (dp / l.slope(v) - 1.0).abs() < 1e-5,
                "{v}: {dp} {}",
                l.slope(v)
            );
            let dw = (l.energy(v + h) - l.energy(v - h)) / (2.0 * h);
            let p = l.recoil(v);
            assert!((dw - p).abs() < 1e-5 * p.abs().max(1.0), "{v}: {dw} {p}");
        }
    }

    #[test]
    fn recoil_near_the_residual_volume_exceeds_30_cmh2o() {
        let l = law();
        let x0 = l.rest - l.lower;
        // a hundredth of the way from RV to rest, and at RV itself
        assert!(l.recoil(l.lower + 0.01 * x0) < -30.0 * CMH2O);
        assert!(l.recoil(l.lower) < -30.0 * CMH2O);
        let y0 = l.upper - l.rest;
        assert!(l.recoil(l.upper - 0.01 * y0) > 30.0 * CMH2O);
    }

    #[test]
    fn capacity_ratios_bracket_rest_over_the_subject_ranges() {
        use crate::anatomy::{SUBJECT_RANGES, Sex};
        for sex in [Sex::Male, Sex::Female] {
            for age in [SUBJECT_RANGES[0].1, SUBJECT_RANGES[0].2] {
                for stature in [SUBJECT_RANGES[1].1, SUBJECT_RANGES[1].2] {
                    let s = Subject {
                        sex,
                        age,
                        stature,
                        ..Subject::default()
                    };
                    let (rv, tlc) = capacity_ratios(&s);
                    let raw = (s.rv_ecsc() / s.frc_ecsc(), s.tlc_ecsc() / s.frc_ecsc());
                    assert_eq!((rv, tlc), raw, "no clamp within the ranges: {s:?}");
                    assert!(rv > 0.38 && rv < 0.89 && tlc > 1.36 && tlc < 2.44, "{s:?}");
                }
            }
        }
    }
}
