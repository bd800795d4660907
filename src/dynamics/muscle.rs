//! The muscle law: the force of a muscle element from its length and activation, with a
//! passive and an active part (a Hill-type law without its velocity dependence), and the
//! thesis's law it replaces as an option.
//!
//! - **Passive**: the relaxed tissue's force-length curve, an exponential toe from the
//!   tissue's slack length l_s, F_max f_PE(e) with e = l / l_s - 1 and
//!   f_PE(e) = (exp(k_PE e / e0) - 1) / (exp(k_PE) - 1) (Thelen 2003, J Biomech Eng 125:70,
//!   eq. 3: [`PASSIVE_SHAPE`], [`PASSIVE_STRAIN`]). Below the slack length it is slightly
//!   negative, and the element's tension, the softplus of its force
//!   ([`super::forces::tension`]), makes it slack there.
//! - **Active**: a F_max (f_L(x) + k_A s(x - 1)) with x = l / l_opt the length over the optimal
//!   length, f_L(x) = exp(-(x - 1)^2 / gamma) (Thelen 2003, eq. 4: [`ACTIVE_WIDTH`]), k_A the
//!   activation-proportional stiffness [`active_stiffness`] and s the stretch beyond the
//!   optimal length (zero at or below it, [`STRETCH_BLEND`]). f_L's slope is zero at the
//!   optimal length and negative beyond it, so an activation alone would soften the chest
//!   wall's equilibrium until it lost definiteness there; k_A is the smallest stiffness that
//!   keeps the active force's slope non-negative at every length. Below the optimal length,
//!   on the ascending limb, f_L's own slope is positive and the force is Thelen's curve
//!   itself: a k_A term there would only take force away (a diaphragm shortened to 0.7 of its
//!   optimal length would keep 0.44 of F_max where the curve gives 0.82). Skeletal muscle
//!   does resist a stretch while active, through its cross-bridges (the short-range
//!   stiffness, Cui et al. 2008, J Biomech 41:1945), but stiffly and over a short range from
//!   the length at which the activation rose: a history a quasi-static model, whose
//!   positions are not states, does not carry. k_A stands in for it beyond the optimal
//!   length, softly.
//! - **Not modelled**: the force-velocity relation (it would make the positions states
//!   again, against the quasi-static formulation) and activation dynamics (the activations
//!   are inputs).
//!
//! Which lengths: an element's optimal and slack lengths are set from its rest length at FRC
//! by [`RestLengths`]. The costal diaphragm at supine FRC stands at 1.05 of its optimal length,
//! and its slack length is 0.79 of the supine FRC length (Road et al. 1986, J Appl Physiol
//! 60:63, sonomicrometry in dogs: [`DIAPHRAGM_REST_OVER_OPTIMAL`], [`DIAPHRAGM_SLACK_OVER_REST`]),
//! so the relaxed diaphragm is stretched at FRC by the lungs' recoil and the abdominal
//! contents. For the other respiratory muscles no such measurement was found; they are taken
//! at their optimal and slack lengths at FRC, Thelen's convention for limb muscle.

use serde::{Deserialize, Serialize};

/// Which law gives a muscle element's force.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum MuscleLaw {
    /// The seed thesis's law (eq. 2.2-2.3): a linear spring F_max / (beta l0) whose rest length
    /// shortens with activation, l0 (1 - beta a); relaxed, every muscle is that spring.
    #[default]
    Thesis,
    /// Passive and active parts (this module): the relaxed muscle is its passive
    /// force-length curve, the active force a F_max f_L(l).
    Hill,
}

impl MuscleLaw {
    /// The laws, by code (FMI `muscle_law`: 0 thesis, 1 hill).
    pub const ALL: [MuscleLaw; 2] = [MuscleLaw::Thesis, MuscleLaw::Hill];

    /// The law's code (FMI `muscle_law`).
    pub fn code(self) -> i32 {
        match self {
            MuscleLaw::Thesis => 0,
            MuscleLaw::Hill => 1,
        }
    }

    /// The law of code `code`; the error names `muscle_law` and the codes.
    pub fn from_code(code: i64) -> crate::Result<MuscleLaw> {
        usize::try_from(code)
            .ok()
            .and_then(|c| MuscleLaw::ALL.get(c).copied())
            .ok_or_else(|| crate::Error::invalid("muscle_law", code, "0 thesis or 1 hill"))
    }

    /// The law named `name` (`thesis` or `hill`).
    pub fn parse(name: &str) -> crate::Result<MuscleLaw> {
        match name {
            "thesis" => Ok(MuscleLaw::Thesis),
            "hill" => Ok(MuscleLaw::Hill),
            _ => Err(crate::Error::invalid("muscle law", name, "thesis or hill")),
        }
    }
}

/// Shape factor k_PE of the passive force-length curve.
/// Source: Thelen 2003, J Biomech Eng 125:70, eq. 3 and Table 1: k_PE = 4 for young adults'
/// limb muscle; no respiratory-muscle value was found (ours 4, agrees).
pub const PASSIVE_SHAPE: f64 = 4.0;

/// Passive strain e0 at which the relaxed tissue carries F_max.
/// Source: Thelen 2003, J Biomech Eng 125:70, Table 1: e0 = 0.6 for young adults (0.5 for
/// older adults); no respiratory-muscle value was found (ours 0.6, agrees).
pub const PASSIVE_STRAIN: f64 = 0.6;

/// Width gamma of the active force-length curve f_L(x) = exp(-(x - 1)^2 / gamma).
/// Source: Thelen 2003, J Biomech Eng 125:70, eq. 4 and Table 1: gamma = 0.45. The diaphragm
/// keeps active force down to 40 % of its in-situ length (Kim et al. 1976, J Appl Physiol
/// 40:807, canine strips), where this curve gives 0.45 F_max (ours 0.45, agrees).
pub const ACTIVE_WIDTH: f64 = 0.45;

/// The costal diaphragm's rest length at supine FRC over its optimal length.
/// Source: Road, Newman, Derenne & Grassino 1986, J Appl Physiol 60:63 (sonomicrometry,
/// anaesthetised dogs, supine): the costal diaphragm is distended to 105 % of its optimal
/// length at FRC, the crural shortened to 92 % (ours 1.05, the costal part, agrees).
pub const DIAPHRAGM_REST_OVER_OPTIMAL: f64 = 1.05;

/// The costal diaphragm's slack length (excised, unloaded) over its length at supine FRC.
/// Source: Road, Newman, Derenne & Grassino 1986, J Appl Physiol 60:63: the equilibrium
/// length of excised strips was 79 +- 3.6 % of the FRC length for the costal diaphragm, 87 +-
/// 3.9 % for the crural (ours 0.79, the costal part, agrees).
pub const DIAPHRAGM_SLACK_OVER_REST: f64 = 0.79;

/// The diaphragm's maximal force under the passive-and-active law [N]: the in-vivo thickness
/// at FRC, 1.7 +- 0.2 mm (Ueki, De Bruin & Pride 1995, Thorax 50:1157), over the default man's
/// 92.6 cm insertion line at 26.8 N/cm^2 (Persad et al. 2024, J Appl Physiol): 422 (372-472)
/// N (`cargo run --release --example muscle_forces -- --all`). The thesis's law keeps
/// [`crate::anatomy::DIAPHRAGM_FORCE`]. Every subject gets this total (the anatomy spreads a
/// fixed total over the insertions), not one scaled with the subject's insertion line.
/// Source: Ueki et al. 1995 and Persad et al. 2024 over the model's insertion line: 422
/// (372-472) N; ours 422 N.
pub const HILL_DIAPHRAGM_FORCE: f64 = 422.0;

/// The largest active tension of an intercostal layer per metre of interspace under the
/// passive-and-active law [N/m]. The thesis's law keeps [`crate::anatomy::INTERCOSTAL_TENSION`].
/// Source: De Troyer 1998, 29 N/cm^2 over a 3 mm layer, 870 N/m; ours 870 N/m.
pub const HILL_INTERCOSTAL_TENSION: f64 = 870.0;

/// The factor on a muscle element's maximal force (the anatomy's) giving its cited maximal
/// force under the passive-and-active law; 1 for the scalenes, the sternocleidomastoids and
/// the abdominal muscles (the law keeps their anatomical forces).
pub fn hill_force_factor(group: crate::anatomy::MuscleGroup) -> f64 {
    use crate::anatomy::{DIAPHRAGM_FORCE, INTERCOSTAL_TENSION, MuscleGroup};
    match group {
        MuscleGroup::Diaphragm => HILL_DIAPHRAGM_FORCE / DIAPHRAGM_FORCE,
        MuscleGroup::ExternalIntercostals | MuscleGroup::InternalIntercostals => {
            HILL_INTERCOSTAL_TENSION / INTERCOSTAL_TENSION
        }
        _ => 1.0,
    }
}

/// Stretch beyond the optimal length, as a fraction of it, over which k_A's term blends in:
/// s(d) = d^2 / (2 w) up to w, d - w / 2 beyond, so the active force and its slope are
/// continuous at the optimal length, as the equilibrium's Newton corrections assume (without
/// the blend the slope would jump from 0 to k_A there), and the slope stays positive inside
/// the blend (k_A / w exceeds f_L's curvature 2 / gamma).
/// Numerical: a smoothing width, not a property of the tissue; 0.05 of the optimal length.
pub const STRETCH_BLEND: f64 = 0.05;

/// The activation-proportional stiffness k_A = sqrt(2 / gamma) exp(-1/2), the steepest
/// descent of f_L (at x = 1 + sqrt(gamma / 2)), so that f_L(x) + k_A s(x - 1) never falls with
/// length: 1.279 for gamma = [`ACTIVE_WIDTH`].
pub fn active_stiffness() -> f64 {
    (2.0 / ACTIVE_WIDTH).sqrt() * (-0.5f64).exp()
}

/// Passive force over F_max at strain `e` = l / l_s - 1 from the slack length, and its
/// derivative in e.
#[inline]
pub fn passive(e: f64) -> (f64, f64) {
    let scale = 1.0 / (PASSIVE_SHAPE.exp() - 1.0);
    let x = (PASSIVE_SHAPE / PASSIVE_STRAIN * e).exp();
    (
        scale * (x - 1.0),
        scale * PASSIVE_SHAPE / PASSIVE_STRAIN * x,
    )
}

/// Active force over a F_max at normalised length `x` = l / l_opt: f_L(x) + k_A s(x - 1), s
/// the stretch beyond the optimal length blended over [`STRETCH_BLEND`] (Thelen's f_L alone at
/// or below the optimal length), and its derivative in x.
#[inline]
pub fn active(x: f64, k_a: f64) -> (f64, f64) {
    let d = x - 1.0;
    let f = (-d * d / ACTIVE_WIDTH).exp();
    let (h, dh) = if d <= 0.0 {
        (0.0, 0.0)
    } else if d < STRETCH_BLEND {
        (0.5 * d * d / STRETCH_BLEND, d / STRETCH_BLEND)
    } else {
        (d - 0.5 * STRETCH_BLEND, 1.0)
    };
    (f + k_a * h, -2.0 * d / ACTIVE_WIDTH * f + k_a * dh)
}

/// The force [N] of a Hill element of largest isometric force `max_force`, optimal length
/// `optimal`, slack length `slack`, at length `l` and activation `a` (velocity terms aside).
#[inline]
pub fn force(l: f64, optimal: f64, slack: f64, max_force: f64, a: f64, k_a: f64) -> f64 {
    let (p, _) = passive(l / slack - 1.0);
    let (f, _) = active(l / optimal, k_a);
    max_force * (p + a * f)
}

/// The slope dF/dl [N/m] of [`force`].
pub fn stiffness(l: f64, optimal: f64, slack: f64, max_force: f64, a: f64, k_a: f64) -> f64 {
    let (_, dp) = passive(l / slack - 1.0);
    let (_, df) = active(l / optimal, k_a);
    max_force * (dp / slack + a * df / optimal)
}

/// The elastic energy [J] of a relaxed Hill element of slack length `slack` and largest force
/// `max_force` at length `l`: the integral from the slack length of its tension, the softplus
/// of width `toe` of the passive force ([`super::forces::tension`]); [`energy`] at zero
/// activation.
pub fn passive_energy(l: f64, slack: f64, max_force: f64, toe: f64) -> f64 {
    energy(l, 1.0, slack, max_force, 0.0, 0.0, toe)
}

/// The energy [J] of a Hill element held at activation `a`, the potential of its tension at
/// that activation: the integral from the slack length to `l` of the softplus of width `toe`
/// of [`force`] ([`super::forces::tension`]; velocity terms aside), by 8-point Gauss-Legendre
/// quadrature on panels of at most 2 % of the slack length, with panel edges at the optimal
/// length and at the end of the stretch blend ([`STRETCH_BLEND`]), where the active force's
/// curvature jumps, so that every panel's integrand is smooth (exact to rounding then). At a
/// constant activation (a postural tone, a held input) the element is then conservative; its
/// damper only dissipates, since the softplus rises with the force.
pub fn energy(l: f64, optimal: f64, slack: f64, max_force: f64, a: f64, k_a: f64, toe: f64) -> f64 {
    // nodes and weights on [-1, 1] (Abramowitz & Stegun 1964, Table 25.4)
    const NODES: [f64; 4] = [
        0.183_434_642_495_649_8,
        0.525_532_409_916_329,
        0.796_666_477_413_626_7,
        0.960_289_856_497_536_2,
    ];
    const WEIGHTS: [f64; 4] = [
        0.362_683_783_378_362,
        0.313_706_645_877_887_3,
        0.222_381_034_453_374_5,
        0.101_228_536_290_376_3,
    ];
    let tension = |x: f64| super::forces::tension(force(x, optimal, slack, max_force, a, k_a), toe);
    // the integral over [from, to] on panels of at most 2 % of the slack length
    let integral = |from: f64, to: f64| {
        let panels = ((to - from).abs() / (0.02 * slack)).ceil().max(1.0) as usize;
        let h = (to - from) / panels as f64;
        let mut sum = 0.0;
        for p in 0..panels {
            let mid = from + (p as f64 + 0.5) * h;
            for (x, w) in NODES.iter().zip(WEIGHTS) {
                sum += w * (tension(mid - 0.5 * h * x) + tension(mid + 0.5 * h * x));
            }
        }
        0.5 * h * sum
    };
    // the kinks of the active curve between the slack length and `l`, in order from the slack
    let (lo, hi) = (slack.min(l), slack.max(l));
    let mut edges = vec![slack];
    let mut kinks: Vec<f64> = if a > 0.0 {
        [optimal, (1.0 + STRETCH_BLEND) * optimal]
            .into_iter()
            .filter(|&k| k > lo && k < hi)
            .collect()
    } else {
        Vec::new()
    };
    if l < slack {
        kinks.reverse();
    }
    edges.extend(kinks);
    edges.push(l);
    edges.windows(2).map(|w| integral(w[0], w[1])).sum()
}

/// An element's optimal and slack lengths [m] from its rest length at FRC in its posture.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RestLengths {
    /// Optimal length l_opt [m].
    pub optimal: f64,
    /// Slack length l_s [m].
    pub slack: f64,
}

impl RestLengths {
    /// For a diaphragm fibre of rest length `rest` at FRC in a posture whose fibres are
    /// `ratio` times as long as supine ones (the supine fibre is longer:
    /// [`super::diaphragm_length_ratio`] of the posture over the supine one): its supine length
    /// stands at [`DIAPHRAGM_REST_OVER_OPTIMAL`] of the optimal length, and its slack length is
    /// [`DIAPHRAGM_SLACK_OVER_REST`] of the supine length.
    pub fn diaphragm(rest: f64, ratio: f64) -> RestLengths {
        let supine = rest / ratio;
        RestLengths {
            optimal: supine / DIAPHRAGM_REST_OVER_OPTIMAL,
            slack: supine * DIAPHRAGM_SLACK_OVER_REST,
        }
    }

    /// For another muscle: optimal and slack at its rest length.
    pub fn at_rest(rest: f64) -> RestLengths {
        RestLengths {
            optimal: rest,
            slack: rest,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_active_slope_is_never_negative_and_zero_at_its_steepest_descent() {
        let k_a = active_stiffness();
        assert!((k_a - 1.279).abs() < 1e-3, "{k_a}");
        // zero where f_L falls fastest, x = 1 + sqrt(gamma / 2): k_A is the smallest stiffness
        // that keeps the slope non-negative there
        let steepest = 1.0 + (ACTIVE_WIDTH / 2.0).sqrt();
        assert!(
            active(steepest, k_a).1.abs() < 1e-12,
            "{:?}",
            active(steepest, k_a)
        );
        // and positive at every other length but the optimal one
        for i in 0..=4000 {
            let x = 0.2 + 1.8 * i as f64 / 4000.0;
            if (x - steepest).abs() < 1e-3 || (x - 1.0).abs() < 1e-3 {
                continue;
            }
            let (_, slope) = active(x, k_a);
            assert!(slope > 0.0, "slope {slope} at x {x}");
        }
    }

    #[test]
    fn below_the_optimal_length_the_active_force_is_thelens_curve() {
        let k = active_stiffness();
        for x in [0.4, 0.7, 0.917, 1.0] {
            let f_l = (-(x - 1.0) * (x - 1.0) / ACTIVE_WIDTH).exp();
            assert_eq!(active(x, k).0, f_l, "x {x}");
        }
        // the force and its slope are continuous where the stretch term starts and where its
        // blend ends
        for x0 in [1.0, 1.0 + STRETCH_BLEND] {
            let (lo, hi) = (active(x0 - 1e-9, k), active(x0 + 1e-9, k));
            assert!((lo.0 - hi.0).abs() < 1e-8, "force at {x0}");
            assert!(
                (lo.1 - hi.1).abs() < 1e-6,
                "slope at {x0}: {} {}",
                lo.1,
                hi.1
            );
        }
        // beyond the optimal length the stretch term holds the force up
        assert!(active(1.3, k).0 > 1.0);
    }

    #[test]
    fn the_curves_have_their_cited_values() {
        // Thelen 2003: F_max at the strain e0, zero at slack; f_L(1) = 1.
        assert!((passive(PASSIVE_STRAIN).0 - 1.0).abs() < 1e-12);
        assert_eq!(passive(0.0).0, 0.0);
        assert!((active(1.0, 0.0).0 - 1.0).abs() < 1e-15);
        // derivatives against central differences
        for x in [0.5, 0.9, 1.02, 1.2, 1.6] {
            let h = 1e-6;
            let k = active_stiffness();
            let fd = (active(x + h, k).0 - active(x - h, k).0) / (2.0 * h);
            assert!((fd - active(x, k).1).abs() < 1e-6);
            let fd = (passive(x - 1.0 + h).0 - passive(x - 1.0 - h).0) / (2.0 * h);
            assert!((fd - passive(x - 1.0).1).abs() < 1e-6 * (1.0 + fd.abs()));
        }
        let (l, o, s, f, a) = (0.11, 0.1, 0.095, 300.0, 0.4);
        let h = 1e-7;
        let k = active_stiffness();
        let fd = (force(l + h, o, s, f, a, k) - force(l - h, o, s, f, a, k)) / (2.0 * h);
        assert!((fd - stiffness(l, o, s, f, a, k)).abs() < 1e-4 * fd.abs());
    }

    #[test]
    fn the_diaphragm_is_stretched_at_frc() {
        let r = RestLengths::diaphragm(0.2, 1.0);
        assert!((0.2 / r.optimal - 1.05).abs() < 1e-12);
        assert!(r.slack < 0.2);
        // standing, the fibres are shorter than supine (ratio 1 / 1.145): below optimal
        let r = RestLengths::diaphragm(0.2, 1.0 / 1.145);
        assert!(0.2 / r.optimal < 1.0);
    }

    #[test]
    fn the_passive_energy_is_the_potential_of_the_tension() {
        let (slack, f_max, toe) = (0.12, 400.0, 0.1);
        for l in [0.10, 0.12, 0.13, 0.15, 0.19] {
            let h = 1e-6;
            let de = (passive_energy(l + h, slack, f_max, toe)
                - passive_energy(l - h, slack, f_max, toe))
                / (2.0 * h);
            let t = crate::dynamics::forces::tension(f_max * passive(l / slack - 1.0).0, toe);
            assert!(
                (de - t).abs() < 1e-5 * (1.0 + t),
                "l {l}: dE/dl {de} against {t}"
            );
        }
    }

    /// At a held activation the energy is the potential of the tension, the active force
    /// and its stretch stiffness included, on both sides of the optimal length and through
    /// the stretch blend.
    #[test]
    fn the_held_energy_is_the_potential_of_the_tension() {
        let (optimal, slack, f_max, toe, k_a) = (0.11, 0.12, 400.0, 0.1, active_stiffness());
        for a in [0.05, 0.3, 1.0] {
            for l in [0.08, 0.10, 0.11, 0.112, 0.13, 0.16] {
                let h = 1e-6;
                let e = |x: f64| energy(x, optimal, slack, f_max, a, k_a, toe);
                let de = (e(l + h) - e(l - h)) / (2.0 * h);
                let f = force(l, optimal, slack, f_max, a, k_a);
                let t = crate::dynamics::forces::tension(f, toe);
                assert!(
                    (de - t).abs() < 1e-5 * (1.0 + t),
                    "a {a}, l {l}: dE/dl {de} against {t}"
                );
            }
        }
        // at zero activation it is the passive energy
        assert_eq!(
            energy(0.15, optimal, slack, f_max, 0.0, k_a, toe),
            passive_energy(0.15, slack, f_max, toe)
        );
    }

    #[test]
    fn names_parse() {
        assert_eq!(MuscleLaw::parse("hill").unwrap(), MuscleLaw::Hill);
        assert!(MuscleLaw::parse("linear").is_err());
    }
}
