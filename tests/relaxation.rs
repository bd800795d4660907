//! The relaxed chest wall's and respiratory system's static pressure-volume curves
//! (`bench::relaxation`, `torso bench relaxation`), solved by the quasi-static mode from RV to
//! TLC. None of these figures was calibrated: the model's passive constants were set by hand
//! and against breathing (docs/dynamics.md, "What sets the passive chest wall";
//! docs/constants.md), and only the pleural pressure at FRC (-5 cmH2O, the rest's preload)
//! is fixed by construction, so it is not tested here.
//!
//! What a relaxation curve must show (Rahn et al. 1946, Am J Physiol 146:161; Agostoni &
//! Mead 1964, Handbook of Physiology, Respiration I, ch. 13): the recoil rises with volume
//! everywhere (a relaxed system that is stable), the chest wall stiffens towards RV and TLC,
//! its compliance over the tidal range is about 0.2 L/cmH2O (0.2 +- 0.045, the range issue 35
//! states from Agostoni & Mead 1964 and Estenne et al. 1985, J Appl Physiol 59:1842: 0.166
//! seated, 0.158 supine), it relaxes near 55-60 % of vital capacity, and the respiratory
//! system's compliance is 0.08-0.12 L/cmH2O. The model misses the last three (issue 35): they
//! stay here as ignored tests stating the measured figures.

use breathing_torso::anatomy::Posture;
use breathing_torso::bench::relaxation::{Relaxation, relaxation};
use breathing_torso::model::Config;

fn curves(lod: u32, posture: Posture) -> Relaxation {
    let mut c = Config::default();
    c.scene.level_of_detail = lod;
    c.subject.posture = posture;
    let r = relaxation(&c, 25).unwrap();
    println!(
        "level {lod}, {posture:?}: C_cw {:.4}, C_rs {:.4} L/cmH2O, chest wall relaxed at {:?} of \
         VC, {} points from {:.3} to {:.3} L (RV {:.3}, FRC {:.3}, TLC {:.3} L), failed {:?}",
        r.chest_wall_compliance,
        r.system_compliance,
        r.chest_wall_relaxation,
        r.points.len(),
        r.points[0].lung,
        r.points.last().unwrap().lung,
        r.rv,
        r.frc,
        r.tlc,
        r.failed
    );
    r
}

/// Compliance [L/cmH2O] of the chest wall between the points whose volumes lie in
/// [lo, hi] (a fraction of VC above RV each), by the end points' secant.
fn secant(r: &Relaxation, lo: f64, hi: f64) -> f64 {
    let vc = r.tlc - r.rv;
    let inside: Vec<_> = r
        .points
        .iter()
        .filter(|p| p.lung >= r.rv + lo * vc - 1e-9 && p.lung <= r.rv + hi * vc + 1e-9)
        .collect();
    let (a, b) = (inside[0], inside[inside.len() - 1]);
    (b.lung - a.lung) / ((b.chest_wall - a.chest_wall) / 98.0665)
}

/// The recoil rises with volume over the whole curve solved, and the chest wall is stiffer
/// in the lowest and the highest tenth of the volumes solved than over the tidal range.
fn recoil_rises_with_volume_and_stiffens_towards_the_ends(lod: u32) {
    for posture in [Posture::Standing, Posture::Supine] {
        let r = curves(lod, posture);
        let vc = r.tlc - r.rv;
        // the curve reaches TLC (RV: see the ignored test below)
        assert!(
            r.points.last().unwrap().lung >= r.tlc - 0.1 * vc,
            "{posture:?}: {:?}",
            r.failed
        );
        for w in r.points.windows(2) {
            assert!(
                w[1].chest_wall > w[0].chest_wall && w[1].system > w[0].system,
                "{posture:?}: recoil falls from {:?} to {:?}",
                w[0],
                w[1]
            );
        }
        let lowest = (r.points[0].lung - r.rv) / vc;
        let low = secant(&r, lowest, lowest + 0.1);
        let high = secant(&r, 0.9, 1.0);
        println!(
            "  C_cw lowest 10 % of VC {low:.4}, highest 10 % {high:.4}, tidal {:.4} L/cmH2O",
            r.chest_wall_compliance
        );
        assert!(low < r.chest_wall_compliance && high < r.chest_wall_compliance);
    }
}

#[test]
fn recoil_rises_with_volume_and_stiffens_towards_the_ends_at_level_0() {
    recoil_rises_with_volume_and_stiffens_towards_the_ends(0);
}

#[test]
fn recoil_rises_with_volume_and_stiffens_towards_the_ends_at_level_1() {
    recoil_rises_with_volume_and_stiffens_towards_the_ends(1);
}

/// Relaxation curves are measured from RV to TLC (Rahn et al. 1946; Agostoni & Mead 1964).
/// Issue 35: at level 1 the relaxed chest wall's equilibrium path ends below FRC
/// (`torso bench relaxation --lod 1`: standing at 3.225 L, FRC 3.500, RV 1.841 L, the solve to
/// 2.994 L followed 68 % of the way; supine at 2.648 L, FRC 2.874, RV 1.512 L); level 0
/// reaches RV standing; supine its equilibrium at RV (1.490 L) buckles, the curve starts at
/// 1.677 L.
#[test]
#[ignore = "issue 35: the relaxed chest wall cannot be deflated to RV at level 1"]
fn relaxation_curve_reaches_residual_volume() {
    for lod in [0, 1] {
        for posture in [Posture::Standing, Posture::Supine] {
            let r = curves(lod, posture);
            let vc = r.tlc - r.rv;
            assert!(
                r.points[0].lung <= r.rv + 0.1 * vc,
                "level {lod}, {posture:?}: {:?}",
                r.failed
            );
        }
    }
}

/// Issue 35: measured at level 1 (`torso bench relaxation --lod 1`) C_cw 0.0923 standing and
/// 0.1074 supine, against 0.2 +- 0.045 L/cmH2O.
#[test]
#[ignore = "issue 35: the chest wall is about twice as stiff as an adult's"]
fn chest_wall_compliance_is_an_adults() {
    for posture in [Posture::Standing, Posture::Supine] {
        let c = curves(1, posture).chest_wall_compliance;
        assert!(
            (0.155..=0.245).contains(&c),
            "{posture:?}: C_cw {c} L/cmH2O"
        );
    }
}

/// Issue 35: measured at level 1 (`torso bench relaxation --lod 1`) 38.0 % of VC standing and
/// 41.5 % supine, against 55-60 %.
#[test]
#[ignore = "issue 35: the chest wall relaxes too low"]
fn chest_wall_relaxes_near_55_to_60_percent_of_vital_capacity() {
    for posture in [Posture::Standing, Posture::Supine] {
        let f = curves(1, posture).chest_wall_relaxation.unwrap_or(f64::NAN);
        assert!(
            (0.55..=0.60).contains(&f),
            "{posture:?}: relaxed at {f} of VC"
        );
    }
}

/// Issue 35: measured at level 1 (`torso bench relaxation --lod 1`) C_rs 0.0629 standing and
/// 0.0696 supine, against 0.08-0.12 L/cmH2O.
#[test]
#[ignore = "issue 35: the respiratory system is too stiff"]
fn respiratory_system_compliance_is_an_adults() {
    for posture in [Posture::Standing, Posture::Supine] {
        let c = curves(1, posture).system_compliance;
        assert!((0.08..=0.12).contains(&c), "{posture:?}: C_rs {c} L/cmH2O");
    }
}
