//! The passive-and-active muscle law (`dynamics::muscle`, `Params::muscle_law = hill`) in the
//! whole model, with the passive wall fitted for it (`HILL_PASSIVE_WALL_SCALE`, fitted by
//! `torso bench relaxation --muscle-law hill --fit` to the standing chest wall's compliance
//! over the tidal range, 0.2 L/cmH2O, at level of detail 1; then its cartilage and abdominal
//! wall fitted apart, `HILL_CARTILAGE_FACTOR` and `HILL_ABDOMINAL_WALL_FACTOR`, by `torso bench
//! relaxation --muscle-law hill --fit-compartments` to young seated adults' rib cage and
//! diaphragm-abdomen compliances). Those figures are calibrated and are not tested here. What
//! is tested was not calibrated: the supine chest wall and compartments, the respiratory
//! system, the relaxation volume, the curve's stiffening, the compartments over the vital
//! capacity (a secant from RV to TLC against each compartment's own pressure, not the fitted
//! tidal slopes against the pleural pressure, though it follows them in part), the energy of a
//! relaxed motion, and what an activation does. Cited bounds the
//! model misses are ignored tests stating the measured figure (issue 35).
//!
//! Quiet breathing under the law uses the quiet drive at cited fractions of maximum
//! (`Drive::quiet_for`: the diaphragm's and the parasternal intercostals' EMG in quiet
//! breathing, Reilly et al. 2011) on the law's cited maximal forces
//! (`HILL_DIAPHRAGM_FORCE`, `HILL_INTERCOSTAL_TENSION`): nothing of the breath is fitted, so
//! the tidal volume, the pleural swing, the compartments' shares, the excursion per litre and a
//! paralysed side's motion are all outcomes, measured through the FMU by `bench::physiology`
//! (`torso bench physiology --muscle-law hill` prints them).

use breathing_torso::anatomy::{MuscleGroup, Posture};
use breathing_torso::bench::physiology::{
    DEEP_EXCURSION_MEN, EXCURSION_PER_LITRE, INSPIRATORY_CAPACITY, Laws, PARALYSED_SIDE_SHARE,
    PLEURAL_SWING, QuietBreath, REGIONAL_GRADIENT, RIB_ROTATION_TO_TLC, SNIFF_TRANSDIAPHRAGMATIC,
    SUPINE_ABDOMINAL_SHARE, SYSTEM_COMPLIANCE, UPRIGHT_RIB_CAGE_SHARE, full_inspiration,
    occluded_inspiration, pimax_range, pressure_step, quiet_breath, sniff,
};
use breathing_torso::bench::relaxation::{Relaxation, relaxation};
use breathing_torso::dynamics::GravityLoads;
use breathing_torso::dynamics::Params;
use breathing_torso::dynamics::muscle::MuscleLaw;
use breathing_torso::model::{Config, Drive};
use breathing_torso::{Quantity, Torso};

fn hill(posture: Posture) -> Config {
    let mut c = Config::default();
    c.subject.posture = posture;
    c.params = Some(Params::for_posture_and_law(posture, MuscleLaw::Hill));
    c
}

fn curves(posture: Posture) -> Relaxation {
    let r = relaxation(&hill(posture), 25).unwrap();
    println!(
        "hill, {posture:?}: C_cw {:.4}, C_rs {:.4} L/cmH2O, chest wall relaxed at {:?} of VC, \
         {} points from {:.3} to {:.3} L (RV {:.3}, FRC {:.3}, TLC {:.3} L), failed {:?}",
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

/// Supine, the relaxed chest wall's compliance over the tidal range is the adult's, 0.2 +-
/// 0.045 L/cmH2O (issue 35, after Agostoni & Mead 1964; Estenne et al. 1985, J Appl Physiol
/// 59:1842, measured 0.158 supine): not fitted (the fits are standing and seated). Measured
/// 0.1884 (0.1494 before the compartments were fitted apart).
#[test]
fn the_supine_chest_wall_has_an_adults_compliance() {
    let c = curves(Posture::Supine).chest_wall_compliance;
    assert!((0.155..=0.245).contains(&c), "C_cw supine {c:.4} L/cmH2O");
}

/// The respiratory system's compliance, 0.08-0.12 L/cmH2O (issue 35), standing and supine.
#[test]
fn the_respiratory_system_has_an_adults_compliance() {
    for posture in [Posture::Standing, Posture::Supine] {
        let c = curves(posture).system_compliance;
        assert!(
            (0.08..=0.12).contains(&c),
            "{posture:?}: C_rs {c:.4} L/cmH2O"
        );
    }
}

/// The relaxed recoil rises with volume over the whole curve solved (a stable relaxed
/// system; Rahn et al. 1946, Am J Physiol 146:161).
#[test]
fn the_relaxed_recoil_rises_with_volume() {
    for posture in [Posture::Standing, Posture::Supine] {
        let r = curves(posture);
        assert!(
            r.points.len() >= 10,
            "{posture:?}: {} points",
            r.points.len()
        );
        for w in r.points.windows(2) {
            assert!(
                w[1].chest_wall > w[0].chest_wall,
                "{posture:?}: recoil falls between {:.3} and {:.3} L",
                w[0].lung,
                w[1].lung
            );
        }
    }
}

/// The rib cage's and the diaphragm-abdomen's compliances of relaxed healthy adults, mean and
/// SD [L/cmH2O] (Estenne, Yernault & De Troyer 1985, J Appl Physiol 59:1842: 61 adults,
/// weighted spirometer and magnetometers, relaxation; read from the abstract): upright (seated),
/// the 24-39-year-olds (the default man is 30), rib cage 0.164 +- 0.041 and diaphragm-abdomen
/// 0.032 +- 0.012; supine, in 52 of them of all ages, 0.088 +- 0.038 and 0.070 +- 0.025. The
/// bounds are the mean +- 2 SD.
const ESTENNE_SEATED_YOUNG: [(f64, f64); 2] = [(0.164, 0.041), (0.032, 0.012)];
const ESTENNE_SUPINE: [(f64, f64); 2] = [(0.088, 0.038), (0.070, 0.025)];

fn within_two_sd(x: f64, (mean, sd): (f64, f64)) -> bool {
    (mean - 2.0 * sd..=mean + 2.0 * sd).contains(&x)
}

/// The relaxed compartments' compliances in `posture` within Estenne et al.'s `[rib cage,
/// diaphragm-abdomen]` means +- 2 SD.
fn compartments_within(posture: Posture, [rc, ab]: [(f64, f64); 2]) {
    let r = curves(posture);
    assert!(
        within_two_sd(r.rib_cage_compliance, rc) && within_two_sd(r.abdomen_compliance, ab),
        "{posture:?}: rib cage {:.4}, abdomen {:.4} L/cmH2O against {rc:?}, {ab:?}",
        r.rib_cage_compliance,
        r.abdomen_compliance
    );
}

/// The rib cage's and the abdomen's displaced volumes make up the lungs' volume change,
/// whatever the diaphragm carries, so their slopes against the pleural pressure add up to the
/// chest wall's compliance (Konno & Mead 1968; Estenne et al. 1985), less the abdominal
/// contents' compression (the lungs gain what the wall displaces plus what the contents give
/// up): within 2 %, the bound of optoelectronic plethysmography against spirometry (Aliverti
/// et al. 2001).
#[test]
fn the_compartments_compliances_add_up_to_the_chest_walls() {
    for posture in [Posture::Standing, Posture::Sitting, Posture::Supine] {
        let r = curves(posture);
        let sum = r.rib_cage_compliance + r.abdomen_compliance;
        println!(
            "{posture:?}: rib cage {:.4} + abdomen {:.4} = {sum:.4} against C_cw {:.4} L/cmH2O",
            r.rib_cage_compliance, r.abdomen_compliance, r.chest_wall_compliance
        );
        assert!(r.rib_cage_compliance > 0.0 && r.abdomen_compliance > 0.0);
        assert!(
            (sum / r.chest_wall_compliance - 1.0).abs() < 0.02,
            "{posture:?}: {sum} against {}",
            r.chest_wall_compliance
        );
    }
}

/// Upright, the relaxed rib cage is the compliant compartment and the diaphragm-abdomen the
/// stiff one (Estenne et al. 1985: 0.164 +- 0.041 and 0.032 +- 0.012 L/cmH2O seated, aged
/// 24-39). Calibrated, not a test of the model: these means are the targets of
/// `HILL_CARTILAGE_FACTOR` and `HILL_ABDOMINAL_WALL_FACTOR` (`torso bench relaxation
/// --muscle-law hill --fit-compartments`); this checks that the defaults carry the fit, to 1 %
/// (measured 0.1636 and 0.0320; before the fit 0.0814 and 0.1058, the abdomen taking 57 % of
/// the relaxed chest wall's compliance against 16 %).
#[test]
fn the_defaults_carry_the_seated_compartments_fit() {
    let r = curves(Posture::Sitting);
    let [(rc, _), (ab, _)] = ESTENNE_SEATED_YOUNG;
    assert!(
        (r.rib_cage_compliance / rc - 1.0).abs() < 0.01
            && (r.abdomen_compliance / ab - 1.0).abs() < 0.01,
        "rib cage {:.4}, abdomen {:.4} L/cmH2O against {rc}, {ab}",
        r.rib_cage_compliance,
        r.abdomen_compliance
    );
}

/// Supine, the relaxed rib cage and diaphragm-abdomen compliances (Estenne et al. 1985: 0.088
/// +- 0.038 and 0.070 +- 0.025 L/cmH2O). Not fitted (the fits are standing and seated):
/// measured 0.1431 and 0.0432.
#[test]
fn the_supine_compartments_have_adults_compliances() {
    compartments_within(Posture::Supine, ESTENNE_SUPINE);
}

/// The two-factor fit of the passive wall's compartments (`bench::relaxation::fit_compartments`,
/// `torso bench relaxation --muscle-law hill --fit-compartments`) reaches young seated
/// adults' rib cage and diaphragm-abdomen compliances (Estenne et al. 1985) from the law's
/// wall before the compartments' factors (`Params::before_compartments`), its last step is
/// what the fitted wall measures, it moves only the cartilage and the abdominal wall, and its
/// factors are the defaults' (`HILL_CARTILAGE_FACTOR`, `HILL_ABDOMINAL_WALL_FACTOR`, to
/// 0.5 %). A test of the fit, not of the model.
#[test]
fn the_compartments_fit_reaches_its_targets() {
    use breathing_torso::bench::relaxation::{
        SEATED_COMPARTMENTS, fit_compartments, tidal_compartments,
    };
    let mut config = hill(Posture::Sitting);
    config.params = Some(Params::before_compartments(
        Posture::Sitting,
        MuscleLaw::Hill,
    ));
    let steps = fit_compartments(&config, SEATED_COMPARTMENTS).unwrap();
    let last = *steps.last().unwrap();
    println!("{} iterates, last {last:?}", steps.len());
    assert!((last.rib_cage / SEATED_COMPARTMENTS[0] - 1.0).abs() < 5e-3);
    assert!((last.abdomen / SEATED_COMPARTMENTS[1] - 1.0).abs() < 5e-3);
    use breathing_torso::dynamics::{HILL_ABDOMINAL_WALL_FACTOR, HILL_CARTILAGE_FACTOR};
    assert!(
        (last.cartilage / HILL_CARTILAGE_FACTOR - 1.0).abs() < 5e-3
            && (last.abdominal_wall / HILL_ABDOMINAL_WALL_FACTOR - 1.0).abs() < 5e-3,
        "{last:?}"
    );
    let defaults = Params::before_compartments(Posture::Sitting, MuscleLaw::Hill);
    let mut p = defaults.clone();
    p.scale_compartments(last.cartilage, last.abdominal_wall);
    let mut only = defaults.clone();
    only.cartilage_stiffness = p.cartilage_stiffness;
    only.membrane_stiffness = p.membrane_stiffness;
    only.abdominal_wall_compliance = p.abdominal_wall_compliance;
    assert_eq!(only, p, "only the cartilage and the abdominal wall move");
    let mut c = config.clone();
    c.params = Some(p);
    let [rc, ab] = tidal_compartments(&c).unwrap();
    assert!((rc - last.rib_cage).abs() < 1e-9 && (ab - last.abdomen).abs() < 1e-9);
    let err = fit_compartments(&config, [0.164, f64::NAN]).unwrap_err();
    assert!(err.to_string().contains("target compartments"), "{err}");
}

/// Over the vital capacity the relaxed abdomen is less compliant than the rib cage (Konno &
/// Mead 1968, J Appl Physiol 24:544, six subjects standing and supine: "The abdomen was less
/// compliant than the rib cage for large volume changes"; each compartment's volume against
/// its own pressure, oesophageal for the rib cage and gastric for the abdomen): here the
/// secants from RV to TLC of the rib cage's displaced volume against the pleural pressure
/// and of the abdomen's against the abdominal pressure. Measured: rib cage 0.1059, abdomen
/// 0.0401 L/cmH2O standing, 0.1067 and 0.0923 supine (before the compartments were fitted
/// apart the abdomen was the more compliant: 0.304 against 0.082 standing).
#[test]
fn the_abdomen_is_stiffer_than_the_rib_cage_over_the_vital_capacity() {
    let mut softer = Vec::new();
    for posture in [Posture::Standing, Posture::Supine] {
        let r = curves(posture);
        assert!(
            r.failed.is_empty(),
            "{posture:?}: the curve spans RV to TLC"
        );
        let (a, b) = (&r.points[0], &r.points[r.points.len() - 1]);
        let rib_cage = (b.rib_cage - a.rib_cage) / ((b.chest_wall - a.chest_wall) / 98.0665);
        let abdomen =
            (b.abdomen - a.abdomen) / ((b.abdominal_pressure - a.abdominal_pressure) / 98.0665);
        println!("{posture:?}, RV to TLC: rib cage {rib_cage:.4}, abdomen {abdomen:.4} L/cmH2O");
        assert!(rib_cage > 0.0 && abdomen > 0.0, "{posture:?}");
        if abdomen >= rib_cage {
            softer.push((posture, abdomen, rib_cage));
        }
    }
    assert!(
        softer.is_empty(),
        "abdomen at least as compliant: {softer:?}"
    );
}

/// The chest wall relaxes near 55-60 % of vital capacity (Agostoni & Mead 1964).
#[test]
#[ignore = "issue 35: with the hill law the chest wall relaxes at 46.3 % of VC standing and 49.3 % supine, against 55-60 % (49.6 and 46.3 % before the compartments were fitted apart)"]
fn the_chest_wall_relaxes_near_55_to_60_percent_of_vital_capacity() {
    for posture in [Posture::Standing, Posture::Supine] {
        let f = curves(posture).chest_wall_relaxation.unwrap_or(f64::NAN);
        assert!((0.55..=0.60).contains(&f), "{posture:?}: {f:.3} of VC");
    }
}

/// The relaxed chest wall's compliance [L/cmH2O] between the first and the last of the
/// curve's points whose lung volume lies in [lo, hi] [L] (their secant); at least two must.
fn secant_between(r: &Relaxation, lo: f64, hi: f64) -> f64 {
    let inside: Vec<_> = r
        .points
        .iter()
        .filter(|p| p.lung >= lo - 1e-9 && p.lung <= hi + 1e-9)
        .collect();
    assert!(
        inside.len() >= 2,
        "{} points between {lo:.3} and {hi:.3} L",
        inside.len()
    );
    let (a, b) = (inside[0], inside[inside.len() - 1]);
    (b.lung - a.lung) / ((b.chest_wall - a.chest_wall) / 98.0665)
}

/// The relaxed chest wall stiffens towards RV too (Rahn et al. 1946; Agostoni & Mead 1964;
/// issue 35, deliverable 3): its compliance over the lowest tenth of the volumes solved (the
/// secant of the curve's points there) is below its compliance over the tidal range, as the
/// thesis law's is (`tests/relaxation.rs`).
#[test]
#[ignore = "issue 35: under the hill law the relaxed chest wall softens towards RV: over the lowest tenth of VC 0.3869 against 0.1977 L/cmH2O over the tidal range standing, 0.3262 against 0.1884 supine; cargo test --release --test muscle_law -- --ignored stiffens_towards_rv --nocapture"]
fn the_relaxed_chest_wall_stiffens_towards_rv() {
    let mut softer = Vec::new();
    for posture in [Posture::Standing, Posture::Supine] {
        let r = curves(posture);
        let vc = r.tlc - r.rv;
        let first = r.points[0].lung;
        let low = secant_between(&r, first, first + 0.1 * vc);
        println!(
            "{posture:?}: C_cw over the lowest tenth of VC from {first:.3} L (RV {:.3}) {low:.4}, \
             over the tidal range {:.4} L/cmH2O",
            r.rv, r.chest_wall_compliance
        );
        if !(low.is_finite() && low < r.chest_wall_compliance) {
            softer.push((posture, low, r.chest_wall_compliance));
        }
    }
    assert!(softer.is_empty(), "softer towards RV: {softer:?}");
}

/// The relaxed chest wall stiffens towards TLC (Agostoni & Mead 1964; issue 35, deliverable
/// 3): its compliance over the highest tenth of the vital capacity (the secant of the curve's
/// points there) is below its compliance over the tidal range. Measured: 0.0827 against
/// 0.1977 L/cmH2O standing, 0.1057 against 0.1884 supine. Before the compartments were fitted
/// apart the wall softened there (0.331 against 0.200 standing): the diaphragm, stretched at
/// FRC (`muscle::DIAPHRAGM_SLACK_OVER_REST`), loses passive tension as it shortens and passed
/// more of the pleural pressure on to the soft abdominal wall.
#[test]
fn the_relaxed_chest_wall_stiffens_towards_tlc() {
    let mut softer = Vec::new();
    for posture in [Posture::Standing, Posture::Supine] {
        let r = curves(posture);
        let vc = r.tlc - r.rv;
        let high = secant_between(&r, r.rv + 0.9 * vc, f64::INFINITY);
        assert!(high.is_finite(), "{posture:?}: {high}");
        println!(
            "{posture:?}: C_cw over the highest tenth of VC {high:.4}, over the tidal range {:.4} L/cmH2O",
            r.chest_wall_compliance
        );
        if high >= r.chest_wall_compliance {
            softer.push((posture, high, r.chest_wall_compliance));
        }
    }
    assert!(softer.is_empty(), "softer at the top: {softer:?}");
}

/// The relaxed curve reaches TLC and RV (Rahn et al. 1946 measured it over the whole vital
/// capacity).
#[test]
fn the_relaxed_curve_spans_the_vital_capacity() {
    for posture in [Posture::Standing, Posture::Supine] {
        let r = curves(posture);
        assert!(r.failed.is_empty(), "{posture:?}: {:?}", r.failed);
    }
}

/// The supine wall's compliance factor follows the wall's edges: with tension-only edges (the
/// hill law's) it is Estenne et al.'s seated-to-supine ratio of the diaphragm-abdomen
/// compliance on the sitting factor (1.1 x 0.070 / 0.025), with linear edges (the thesis
/// law's) the hand-set 1.8; sitting and standing are the same under both laws.
#[test]
fn the_supine_wall_factor_follows_the_walls_edges() {
    let ratio = |law: MuscleLaw, posture: Posture| {
        Params::for_posture_and_law(posture, law).abdominal_wall_compliance
            / Params::for_posture_and_law(Posture::Standing, law).abdominal_wall_compliance
    };
    // Estenne, Yernault & De Troyer 1985 (J Appl Physiol 59:1842): diaphragm-abdomen
    // compliance 0.070 L/cmH2O supine, 0.025 seated
    let estenne = 0.070 / 0.025;
    let sitting = ratio(MuscleLaw::Hill, Posture::Sitting);
    assert!((sitting - ratio(MuscleLaw::Thesis, Posture::Sitting)).abs() < 1e-12);
    assert!(
        (ratio(MuscleLaw::Hill, Posture::Supine) - sitting * estenne).abs() < 1e-12,
        "hill supine {} against {}",
        ratio(MuscleLaw::Hill, Posture::Supine),
        sitting * estenne
    );
    assert!((ratio(MuscleLaw::Thesis, Posture::Supine) - 1.8).abs() < 1e-12);
}

/// Under the hill law every membrane edge of the abdominal wall carries tension only, as the
/// dome's do (a membrane wrinkles rather than carry compression); under the thesis law the
/// wall's edges stay linear and only the dome's are tension only. The edges that carry tension
/// only under the thesis law are a strict subset of those under the hill law.
#[test]
fn the_abdominal_walls_edges_carry_tension_only_under_the_hill_law() {
    use breathing_torso::dynamics::{PASSIVE, PASSIVE_SLACK};
    let slots = |law: MuscleLaw| {
        let mut c = Config::default();
        c.scene.level_of_detail = 0;
        c.muscle_law = law;
        let torso = Torso::new(c).unwrap();
        let e = &torso.compiled().model.elements;
        let membrane: Vec<usize> = (0..e.group.len())
            .filter(|&i| e.group[i] == PASSIVE)
            .collect();
        let slack: Vec<usize> = membrane
            .iter()
            .copied()
            .filter(|&i| e.slot[i] == PASSIVE_SLACK)
            .collect();
        (membrane, slack)
    };
    let (thesis_edges, thesis_slack) = slots(MuscleLaw::Thesis);
    let (hill_edges, hill_slack) = slots(MuscleLaw::Hill);
    assert_eq!(
        thesis_edges, hill_edges,
        "the same membrane under both laws"
    );
    assert_eq!(
        hill_slack, hill_edges,
        "hill: every membrane edge tension only"
    );
    assert!(
        !thesis_slack.is_empty() && thesis_slack.len() < thesis_edges.len(),
        "thesis: the dome's {} of {} edges tension only",
        thesis_slack.len(),
        thesis_edges.len()
    );
    let p = Params::for_posture_and_law(Posture::Standing, MuscleLaw::Hill);
    assert!(p.abdominal_wall_tension_only);
    let p = Params::for_posture_and_law(Posture::Standing, MuscleLaw::Thesis);
    assert!(!p.abdominal_wall_tension_only);
}

/// A breath in, held by the diaphragm at 0.3 for 1 s, then released: the mechanical energy at
/// the held activations and the passive one (every muscle relaxed), at the release and every
/// 20 ms for 4 s after it.
fn released_breath(torso: &mut Torso) -> Vec<(f64, f64)> {
    torso.set_activation(MuscleGroup::Diaphragm, 0.3).unwrap();
    torso.advance_to(1.0).unwrap();
    torso.set_activation(MuscleGroup::Diaphragm, 0.0).unwrap();
    let mut energies = vec![(torso.mechanical_energy_held(), torso.mechanical_energy())];
    for i in 1..=200 {
        torso.advance_to(1.0 + 0.02 * i as f64).unwrap();
        energies.push((torso.mechanical_energy_held(), torso.mechanical_energy()));
    }
    energies
}

/// The largest rise between successive samples of `energy` (0 if it never rises).
fn largest_rise(energy: impl Iterator<Item = f64>) -> f64 {
    let e: Vec<f64> = energy.collect();
    e.windows(2).map(|w| w[1] - w[0]).fold(0.0, f64::max)
}

/// With every muscle relaxed, a motion away from rest loses energy and returns to rest: the
/// elastic energy of the passive curve (`muscle::passive_energy`) is the potential of its
/// forces, so the mechanical energy never rises between samples.
#[test]
fn relaxed_motion_dissipates_energy_under_the_hill_law() {
    let mut config = hill(Posture::Standing);
    config.drive = Drive::default();
    // relaxed: no tone either (the energy counts the passive curves only)
    if let Some(p) = config.params.as_mut() {
        p.abdominal_tone = 0.0;
    }
    let mut torso = Torso::new(config.clone()).unwrap();
    let rest = torso.mechanical_energy();
    let energies = released_breath(&mut torso);
    let (start, last) = (energies[0].1 - rest, energies[energies.len() - 1].1 - rest);
    let worst_rise = largest_rise(energies.iter().map(|e| e.1));
    println!("energy above rest {start:.4e} J -> {last:.4e} J, largest rise {worst_rise:.2e} J");
    assert!(start > 0.0);
    assert!(worst_rise <= 1e-6 * start, "energy rose by {worst_rise}");
    assert!(last < 1e-3 * start, "energy left {last} of {start}");
}

/// Standing, with the abdominal wall's tone held, a motion away from rest loses energy and
/// returns to rest: each muscle's energy at its held activation (`muscle::energy`) is the
/// potential of its force, so the mechanical energy at the held activations never rises
/// between samples and falls to the toned rest's. The passive energy, which leaves the
/// tone's force out, rises over the same motion.
#[test]
fn motion_under_the_standing_tone_dissipates_energy() {
    let mut config = hill(Posture::Standing);
    config.drive = Drive::default();
    assert!(config.params.as_ref().unwrap().abdominal_tone > 0.0);
    let mut torso = Torso::new(config.clone()).unwrap();
    let rest = torso.mechanical_energy_held();
    assert!((torso.mechanical_energy() - rest).abs() > 1e-6);
    let energies = released_breath(&mut torso);
    let (start, last) = (energies[0].0 - rest, energies[energies.len() - 1].0 - rest);
    let worst_rise = largest_rise(energies.iter().map(|e| e.0));
    let passive_rise = largest_rise(energies.iter().map(|e| e.1));
    println!(
        "toned: energy above rest {start:.4e} J -> {last:.4e} J, largest rise {worst_rise:.2e} J \
         (the passive energy's largest rise {passive_rise:.2e} J)"
    );
    assert!(start > 0.0);
    assert!(worst_rise <= 1e-6 * start, "energy rose by {worst_rise}");
    assert!(last < 1e-3 * start, "energy left {last} of {start}");
    // the passive energy would fail the same check: the tone's potential is what makes it pass
    assert!(
        passive_rise > 1e-6 * start,
        "passive energy rose by {passive_rise}"
    );
}

/// Each inspiratory group, activated alone, inflates the lungs, and the diaphragm does it by
/// descending (thesis 2.1; De Troyer & Boriek 2011, Compr Physiol 1:1273).
#[test]
fn inspiratory_activations_inflate_and_the_diaphragm_descends() {
    for group in [
        MuscleGroup::Diaphragm,
        MuscleGroup::ExternalIntercostals,
        MuscleGroup::Scalenes,
    ] {
        let mut config = hill(Posture::Standing);
        config.drive = Drive::default();
        let mut torso = Torso::new(config).unwrap();
        let v0 = torso.read(Quantity::LungVolume).unwrap();
        torso.set_activation(group, 0.2).unwrap();
        torso.advance_to(3.0).unwrap();
        let dv = torso.read(Quantity::LungVolume).unwrap() - v0;
        let dome = torso.read(Quantity::DiaphragmDisplacement).unwrap();
        println!(
            "{group:?} at 0.2: lung volume +{dv:.3} L, diaphragm {:.1} mm",
            dome * 1e3
        );
        assert!(dv > 0.01, "{group:?}: {dv} L");
        if group == MuscleGroup::Diaphragm {
            assert!(dome < -1e-3, "the dome moved {dome} m");
        }
    }
}

/// Through the FMU: `muscle_law` = 1 builds the hill law with its fitted wall, and the FMU's
/// lung volume after a quiet-drive second is the library's, bit for bit; a code outside 0-1
/// is refused and keeps the thesis's law.
#[test]
fn the_fmu_parameter_selects_the_law() {
    use breathing_torso::fmi::instance::Instance;
    use breathing_torso::fmi::variables::table;
    use breathing_torso::fmi::{FMI2, Status};
    let t = table();
    let vr = |n: &str| t.by_name(n).unwrap().vr;
    let run = |law: Option<i32>| {
        let mut inst = Instance::new(&FMI2, "t", None, None, false);
        assert_eq!(
            inst.set_integer("fmi2SetInteger", &[vr("scene.level_of_detail")], &[0]),
            Status::Ok
        );
        if let Some(code) = law {
            assert_eq!(
                inst.set_integer("fmi2SetInteger", &[vr("muscle_law")], &[code]),
                Status::Ok
            );
        }
        assert_ne!(
            inst.set_integer("fmi2SetInteger", &[vr("muscle_law")], &[2]),
            Status::Ok
        );
        inst.setup_experiment("fmi2SetupExperiment", None, 0.0, None);
        assert_eq!(inst.enter_initialization_mode(), Status::Ok);
        assert_eq!(
            inst.exit_initialization_mode("fmi2ExitInitializationMode"),
            Status::Ok
        );
        assert_eq!(inst.do_step("fmi2DoStep", 0.0, 1.0), Status::Ok);
        let mut v = [0.0];
        assert_eq!(
            inst.get_real("fmi2GetReal", &[vr("volume.lung")], &mut v),
            Status::Ok
        );
        v[0]
    };
    let library = |law: MuscleLaw| {
        let mut c = Config::default();
        c.scene.level_of_detail = 0;
        c.drive = Drive::quiet();
        c.muscle_law = law;
        let mut torso = Torso::new(c).unwrap();
        torso.advance_to(1.0).unwrap();
        torso.read(Quantity::LungVolume).unwrap()
    };
    let (thesis, hill) = (run(None), run(Some(1)));
    println!("lung volume after 1 s: thesis {thesis:.6} L, hill {hill:.6} L");
    assert_eq!(thesis, library(MuscleLaw::Thesis));
    assert_eq!(hill, library(MuscleLaw::Hill));
    assert_ne!(thesis, hill);
}

/// A snapshot is restored only into the model it was taken from: the same passive wall under
/// the two laws gives two fingerprints, so a state saved under one law is refused by the other.
#[test]
fn the_two_laws_have_different_fingerprints_on_the_same_wall() {
    let mut a = Config::default();
    a.scene.level_of_detail = 0;
    let mut thesis = Params::for_posture(Posture::Standing);
    thesis.scale_passive_wall(breathing_torso::dynamics::HILL_PASSIVE_WALL_SCALE);
    let mut hill = thesis.clone();
    hill.muscle_law = MuscleLaw::Hill;
    a.params = Some(thesis);
    let mut b = a.clone();
    b.params = Some(hill);
    let (ta, mut tb) = (Torso::new(a).unwrap(), Torso::new(b).unwrap());
    let snapshot = ta.snapshot();
    let err = tb.restore(&snapshot);
    assert!(
        err.is_err(),
        "a thesis-law snapshot was restored into a hill-law model"
    );
}

fn within(value: f64, (lo, hi): (f64, f64)) -> bool {
    value >= lo && value <= hi
}

/// Quiet breathing of the default subject at level of detail 1 under the hill law with its
/// cited drive, the left hemidiaphragm's gain `left_gain` (0 paralysed).
fn hill_quiet(posture: Posture, left_gain: f64) -> QuietBreath {
    let q = quiet_breath(posture, 1, MuscleLaw::Hill, left_gain).unwrap();
    println!("hill, {posture:?}, left diaphragm gain {left_gain}: {q:?}");
    q
}

/// Quiet breathing's tidal volume, about 7 mL/kg (West & Luks, Respiratory Physiology: The
/// Essentials, 10th ed. 2016), 383 +- 91 mL (about 5.5 mL/kg) without a mouthpiece (Tobin et
/// al. 1983, Chest 84:202): 7 mL/kg +- 25 % holds both means (as tests/physiology.rs). Under
/// the hill law no drive amplitude is fitted to it (the quiet drive is cited EMG on cited
/// forces), so here it is a test.
fn hill_quiet_tidal_volume_per_kilogram(posture: Posture) {
    let mass = breathing_torso::anatomy::Subject::default().mass;
    let per_kg = hill_quiet(posture, 1.0).tidal_volume / mass;
    assert!(
        (0.00525..=0.00875).contains(&per_kg),
        "{posture:?}: {:.2} mL/kg against 5.25-8.75",
        1e3 * per_kg
    );
}

/// Standing, Thelen's force-length curve on the ascending limb (`dynamics::muscle::active`)
/// lets the quiet drive's cited activations move more than 7 mL/kg + 25 %.
#[test]
#[ignore = "issue 35: with the hill law standing quiet breathing measured 0.664 L, 8.86 mL/kg against 5.25-8.75 (0.707 L before the compartments were fitted apart, 0.714 L before the external intercostals' rostrocaudal drive, 0.626 L while the active stiffness also cost force below the optimal length)"]
fn hill_quiet_tidal_volume_per_kilogram_standing() {
    hill_quiet_tidal_volume_per_kilogram(Posture::Standing);
}

/// Supine, with quiet expiration passive (`dynamics::expiration_with_abdominals`), the breath
/// is the inspiratory muscles' alone, and the stretched supine diaphragm moves less than the
/// standing one under the hill law: the diaphragm alone at its quiet activation adds 0.267 L
/// supine against 0.385 L standing (`cargo run --release --example diaphragm_pressure`), where in people the longer supine diaphragm is the more
/// effective (Druz & Sharp 1981, J Appl Physiol 51:1552).
#[test]
#[ignore = "issue 35: with the hill law supine quiet breathing measured 0.299 L, 3.99 mL/kg against 5.25-8.75 (0.374 L before the compartments were fitted apart, 0.529 L before quiet expiration became passive supine)"]
fn hill_quiet_tidal_volume_per_kilogram_supine() {
    hill_quiet_tidal_volume_per_kilogram(Posture::Supine);
}

#[test]
fn hill_quiet_pleural_swing() {
    let q = hill_quiet(Posture::Standing, 1.0);
    assert!(
        within(q.pleural_swing, PLEURAL_SWING),
        "pleural swing {} cmH2O against {PLEURAL_SWING:?}",
        q.pleural_swing
    );
}

/// The forced drive under the hill law (the thesis law's amplitudes times the quiet
/// diaphragm's cited fraction over its thesis amplitude, `HILL_DRIVE_SCALE`; nothing fitted):
/// a deep breath of 1.5-3 L (the project's physiology reference: three times a quiet breath
/// to two thirds of the vital capacity), standing and supine.
#[test]
fn hill_forced_tidal_volume_is_a_deep_breath() {
    use breathing_torso::model::run::{run, summarise};
    for posture in [Posture::Standing, Posture::Supine] {
        let mut c = Config {
            muscle_law: MuscleLaw::Hill,
            drive: Drive::scenario_for("forced", MuscleLaw::Hill).unwrap(),
            ..Config::default()
        };
        c.subject.posture = posture;
        let period = 1.0 / c.drive.frequency;
        let mut torso = Torso::new(c).unwrap();
        let frames = run(&mut torso, 3.0 * period, 28.0).unwrap();
        let vt = summarise(&frames, period).tidal_volume;
        println!("hill, forced, {posture:?}: VT {vt:.3} L");
        assert!((1.5..=3.0).contains(&vt), "{posture:?}: {vt} L");
    }
}

/// Supine under the hill law the internal intercostals take the abdominal family's wave: silent
/// in quiet breathing, whose drive has no abdominal wave (passive quiet expiration supine, De
/// Troyer et al. 1987; Estenne, Ninane & De Troyer 1988), active with the abdominal muscles in
/// forced breathing. Standing, and under the thesis law in every posture, they keep the rib
/// family's antiphase wave (the triangularis sterni's expiratory activity in quiet standing,
/// Estenne et al. 1988).
#[test]
fn supine_quiet_expiration_is_passive_under_the_hill_law() {
    use breathing_torso::anatomy::MuscleGroup::{InternalIntercostals, TransversusAbdominis};
    let largest = |law: MuscleLaw, posture: Posture, scenario: &str| {
        let mut c = Config {
            muscle_law: law,
            drive: Drive::scenario_for(scenario, law).unwrap(),
            postural_tone: false,
            ..Config::default()
        };
        c.subject.posture = posture;
        let period = 1.0 / c.drive.frequency;
        let mut torso = Torso::new(c).unwrap();
        let (mut internal, mut abdominal) = (0.0f64, 0.0f64);
        for k in 1..=40 {
            torso.advance_to(period * f64::from(k) / 40.0).unwrap();
            internal = internal.max(torso.applied_activation(InternalIntercostals));
            abdominal = abdominal.max(torso.applied_activation(TransversusAbdominis));
        }
        (internal, abdominal)
    };
    let quiet = Drive::quiet_for(MuscleLaw::Hill);
    // quiet: silent supine, the rib family's amplitude standing
    let (supine, _) = largest(MuscleLaw::Hill, Posture::Supine, "quiet");
    assert_eq!(supine, 0.0);
    let (standing, _) = largest(MuscleLaw::Hill, Posture::Standing, "quiet");
    assert!(
        (standing - quiet.ribs.amplitude).abs() < 0.02 * quiet.ribs.amplitude,
        "{standing}"
    );
    // forced, supine: with the abdominal muscles
    let (internal, abdominal) = largest(MuscleLaw::Hill, Posture::Supine, "forced");
    assert!(abdominal > 0.0);
    assert!(
        (internal - abdominal).abs() < 1e-12,
        "{internal} against {abdominal}"
    );
    // the thesis law keeps its drive's structure supine
    let (thesis, _) = largest(MuscleLaw::Thesis, Posture::Supine, "quiet");
    let amplitude = Drive::quiet_for(MuscleLaw::Thesis).ribs.amplitude;
    assert!((thesis - amplitude).abs() < 0.02 * amplitude, "{thesis}");
}

/// Upright, the rib cage takes most of a quiet breath (Verschakelen & Demedts 1995).
#[test]
fn hill_upright_rib_cage_share() {
    let q = hill_quiet(Posture::Standing, 1.0);
    assert!(
        within(q.rib_cage_share, UPRIGHT_RIB_CAGE_SHARE),
        "rib-cage share {}",
        q.rib_cage_share
    );
}

/// Supine, the abdomen takes most of a quiet breath (Aliverti et al. 2001): 57.7 % under the
/// hill law (72.5 % before the compartments were fitted apart), with quiet expiration passive supine (`dynamics::expiration_with_abdominals`;
/// 17.0 % while the internal intercostals took the rib family's antiphase wave supine too).
#[test]
fn hill_supine_abdominal_share() {
    let q = hill_quiet(Posture::Supine, 1.0);
    let abdominal = 1.0 - q.rib_cage_share;
    assert!(
        within(abdominal, SUPINE_ABDOMINAL_SHARE),
        "supine abdominal share {abdominal} against {SUPINE_ABDOMINAL_SHARE:?}"
    );
}

/// The dome descends 1.66 +- 0.48 cm per litre of quiet breath (Houston et al. 1994).
#[test]
fn hill_quiet_excursion_per_litre() {
    let q = hill_quiet(Posture::Standing, 1.0);
    assert!(
        within(q.excursion_per_litre, EXCURSION_PER_LITRE),
        "{} cm/L against {EXCURSION_PER_LITRE:?}",
        q.excursion_per_litre
    );
}

/// The sniff test's paradox in quiet breathing: with its muscle relaxed (a soft passive
/// curve, not the thesis law's spring) the paralysed left hemidiaphragm rises while the right
/// one descends, and its side takes under 40 % of the breath.
#[test]
fn hill_paralysed_hemidiaphragm_rises_in_quiet_breathing() {
    let q = hill_quiet(Posture::Standing, 0.0);
    assert!(
        q.hemidiaphragm_motion[0] > 0.0 && q.hemidiaphragm_motion[1] < 0.0,
        "hemidiaphragms move {:?} cm (left, right; cranial +)",
        q.hemidiaphragm_motion
    );
    assert!(
        within(q.left_share, PARALYSED_SIDE_SHARE),
        "paralysed side's share {} against {PARALYSED_SIDE_SHARE:?}",
        q.left_share
    );
}

/// The sniff test's paradox (Alexander 1966): in a sniff of full inspiratory activation the
/// paralysed left hemidiaphragm, relaxed, is drawn cranially while the healthy right one
/// descends.
#[test]
fn hill_paralysed_hemidiaphragm_rises_in_a_sniff() {
    let s = sniff(Posture::Standing, 1, MuscleLaw::Hill, 0.0).unwrap();
    println!("hill, sniff, left diaphragm paralysed: {s:?}");
    assert!(
        s.hemidiaphragm_motion[0] > 0.0 && s.hemidiaphragm_motion[1] < 0.0,
        "hemidiaphragms move {:?} cm (left, right; cranial +)",
        s.hemidiaphragm_motion
    );
}

/// Full inspiratory activation against the occluded airway after a maximal expiration: the
/// mouth pressure within the default man's reference range (Harik-Khan, Wise & Fozard 1998;
/// ATS/ERS 2002), with the hill law's cited maximal forces (nothing fitted to it).
#[test]
#[ignore = "issue 35: with the hill law and the external intercostals' rostrocaudal drive (no drive below the 7th interspace) the occluded maximal inspiration reaches 66.4 cmH2O against 77.0-164.8 (75.9 before the compartments were fitted apart, 80.0 before that drive)"]
fn hill_maximal_inspiratory_pressure() {
    let o = occluded_inspiration(Posture::Standing, 1, MuscleLaw::Hill).unwrap();
    println!("hill: {o:?}");
    let range = pimax_range(&Config::default().subject);
    assert!(
        within(-o.mouth_pressure, range),
        "{} cmH2O against {range:?}",
        o.mouth_pressure
    );
}

/// Full inspiratory activation with the airway open (the diaphragm, external intercostals,
/// scalenes and sternocleidomastoids at 1, `bench::physiology::INSPIRATORY`) adds the default
/// man's inspiratory capacity, 2.9-4.3 L (ECSC 1993), under the hill law's cited maximal forces
/// (nothing fitted to it).
#[test]
fn hill_full_inspiration_volume() {
    let f = full_inspiration(Posture::Standing, 1, MuscleLaw::Hill).unwrap();
    println!("hill: {f:?}");
    assert!(
        within(f.added, INSPIRATORY_CAPACITY),
        "{} L against {INSPIRATORY_CAPACITY:?}",
        f.added
    );
}

/// Under the hill law the posterior dome, followed as M-mode ultrasound follows it (a line
/// through the posterior third of the right dome), descends at least 4.7 cm in a full
/// inspiration (Boussuges et al. 2009, men near inspiratory capacity): 4.97 cm (4.30 while the
/// first rib's cartilage was as soft as the others', `Params::first_cartilage_stiffness`; 4.99
/// before the compartments were fitted apart). Nothing is
/// fitted to it: the diaphragm's force is cited (`muscle::HILL_DIAPHRAGM_FORCE`), and the
/// lowest interspaces' external intercostals are silent (`anatomy::external_intercostal_drive`,
/// De Troyer et al. 2003), so the floating ribs no longer carry the back of the dome up. The
/// pass is conditional on applying that quiet-breathing gradient at full activation: with the
/// uniform drive of before it was 2.05 cm (docs/dynamics.md, "Physiological figures").
#[test]
fn hill_deep_m_mode_excursion() {
    let f = full_inspiration(Posture::Standing, 1, MuscleLaw::Hill).unwrap();
    println!("hill: M-mode {:.3} cm", f.m_mode_excursion);
    assert!(
        within(f.m_mode_excursion, DEEP_EXCURSION_MEN),
        "{} cm against {DEEP_EXCURSION_MEN:?}",
        f.m_mode_excursion
    );
}

/// Under the hill law the back of the dome descends most in a full inspiration (Gierada et
/// al. 1995, MRI near vital capacity: the excursion grows from anterior to middle to posterior).
#[test]
fn hill_the_back_of_the_dome_descends_most() {
    let f = full_inspiration(Posture::Standing, 1, MuscleLaw::Hill).unwrap();
    let [posterior, middle, _] = f.regional_excursion.expect("every line meets the dome");
    assert!(
        within(posterior - middle, REGIONAL_GRADIENT),
        "posterior third {posterior} cm, middle third {middle} cm (Gierada et al. 1995)"
    );
}

/// Under the hill law the ribs turn no more in a full inspiratory activation than from FRC to
/// TLC (Wilson et al. 1987: rib 3 11 deg pump-handle and 13 bucket-handle, rib 7 7 and 10).
/// The rib cage, softened to the relaxed chest wall's 0.2 L/cmH2O over the tidal range
/// (`HILL_PASSIVE_WALL_SCALE`) with its relaxed muscles at their slack lengths, has no
/// stiffening at large rotations, and the maximally active rib-cage muscles turn it past the
/// TLC rotations at 3.87 L above FRC; the costal margin carries the diaphragm's insertions up
/// with it (docs/dynamics.md, "Physiological figures").
#[test]
#[ignore = "issue 35: under the hill law a full inspiration turns rib 3 15.4 deg pump-handle and 18.0 bucket-handle (cited at most 11 and 13 at TLC; 13.6 and 15.8 before the compartments were fitted apart, whose cartilage is softer), rib 7 4.1 and 7.0 (at most 7 and 10; 7.1 and 12.1 before)"]
fn hill_ribs_turn_no_more_than_to_tlc() {
    let f = full_inspiration(Posture::Standing, 1, MuscleLaw::Hill).unwrap();
    for (rib, pump, bucket) in RIB_ROTATION_TO_TLC {
        let (p, b) = f.rib_rotation[rib as usize - 1];
        println!("rib {rib}: pump {p:.2} deg, bucket {b:.2} deg");
        assert!(
            within(p, (0.0, pump)) && within(b, (0.0, bucket)),
            "rib {rib}: pump {p:.1} deg (at most {pump}), bucket {b:.1} deg (at most {bucket})"
        );
    }
}

/// Under the hill law a maximal sniff's transdiaphragmatic pressure exceeds 38 cmH2O (Wanke et
/// al. 1990: 68 (SD 15) cmH2O at 95 % of TLC, 163 (18) at RV). The 422 N diaphragm
/// (`muscle::HILL_DIAPHRAGM_FORCE`) would give about 108 cmH2O as a piston over 0.04 m^2 of
/// dome (docs/dynamics.md, "Physiological figures", for what the model loses on the way).
#[test]
fn hill_sniff_transdiaphragmatic_pressure() {
    let s = sniff(Posture::Standing, 1, MuscleLaw::Hill, 1.0).unwrap();
    println!("{s:?}");
    assert!(
        within(s.transdiaphragmatic, SNIFF_TRANSDIAPHRAGMATIC),
        "{} cmH2O against {SNIFF_TRANSDIAPHRAGMATIC:?}",
        s.transdiaphragmatic
    );
}

/// The hill law with gravity acting (the tissues carrying the reference loads,
/// `dynamics::pretension`): the respiratory system's compliance by a 10 cmH2O airway-opening
/// step through the FMU. Its passive wall was fitted with gravity preloaded, standing, so this
/// configuration's compliance was not calibrated.
fn hill_acting_compliance(posture: Posture) -> f64 {
    let laws = Laws {
        muscle: MuscleLaw::Hill,
        gravity_loads: GravityLoads::Acting,
        postural_tone: true,
    };
    let s = pressure_step(posture, 1, laws).unwrap();
    println!(
        "hill, gravity acting, {posture:?}: C_rs {:.4} L/cmH2O",
        s.compliance
    );
    s.compliance
}

#[test]
fn hill_acting_respiratory_system_compliance_standing() {
    let c = hill_acting_compliance(Posture::Standing);
    assert!(
        within(c, SYSTEM_COMPLIANCE),
        "C_rs {c} against {SYSTEM_COMPLIANCE:?}"
    );
}

#[test]
fn hill_acting_respiratory_system_compliance_supine() {
    let c = hill_acting_compliance(Posture::Supine);
    assert!(
        within(c, SYSTEM_COMPLIANCE),
        "C_rs {c} against {SYSTEM_COMPLIANCE:?}"
    );
}

/// The abdominal wall's tone standing (`Params::abdominal_tone`, 1.7 % of maximum: Cholewicki
/// et al. 1997) lowers the end-expiratory volume (De Troyer 1983, Respir Physiol 53:341: the
/// tonic activity of the abdominal muscles standing lowers it), with gravity preloaded and
/// acting; the rest with the tone is reported against the ECSC FRC and -5 cmH2O (outcomes).
#[test]
fn standing_tone_lowers_the_end_expiratory_volume() {
    for loads in [GravityLoads::Preloaded, GravityLoads::Acting] {
        let config = Config {
            muscle_law: MuscleLaw::Hill,
            gravity_loads: loads,
            ..Config::default()
        };
        let toned = config.model_params();
        assert_eq!(
            toned.abdominal_tone,
            breathing_torso::dynamics::STANDING_ABDOMINAL_TONE
        );
        let rest = |tone: f64| {
            let mut c = config.clone();
            let mut p = toned.clone();
            p.abdominal_tone = tone;
            c.params = Some(p);
            let mut t = Torso::new(c).unwrap();
            (
                t.read(Quantity::LungVolume).unwrap(),
                t.read(Quantity::PleuralPressure).unwrap() / 98.0665,
            )
        };
        let (relaxed, toned_rest) = (rest(0.0), rest(toned.abdominal_tone));
        println!(
            "hill, {loads:?}, standing: end-expiratory volume {:.4} L relaxed, {:.4} L with the \
             tone (pleural pressure {:.2} / {:.2} cmH2O)",
            relaxed.0, toned_rest.0, relaxed.1, toned_rest.1
        );
        assert!(
            toned_rest.0 < relaxed.0,
            "{loads:?}: {toned_rest:?} against {relaxed:?}"
        );
    }
}

/// The tone belongs to standing under the hill law: none supine (silent: De Troyer 1983;
/// Strohl et al. 1981) nor under the thesis's law, and none without gravity.
#[test]
fn the_tone_is_postural() {
    let tone = |law, posture, g| {
        let mut c = Config {
            muscle_law: law,
            gravity: g,
            ..Config::default()
        };
        c.subject.posture = posture;
        c.model_params().abdominal_tone
    };
    let standing = breathing_torso::dynamics::STANDING_ABDOMINAL_TONE;
    assert_eq!(
        tone(
            MuscleLaw::Hill,
            Posture::Standing,
            breathing_torso::dynamics::GRAVITY
        ),
        standing
    );
    assert_eq!(
        tone(
            MuscleLaw::Hill,
            Posture::Supine,
            breathing_torso::dynamics::GRAVITY
        ),
        0.0
    );
    assert_eq!(
        tone(
            MuscleLaw::Thesis,
            Posture::Standing,
            breathing_torso::dynamics::GRAVITY
        ),
        0.0
    );
    assert_eq!(tone(MuscleLaw::Hill, Posture::Standing, 0.0), 0.0);
    assert_eq!(
        tone(
            MuscleLaw::Hill,
            Posture::Sitting,
            breathing_torso::dynamics::GRAVITY
        ),
        0.0
    );
    // under gravity acting the anatomy is the standing one, the tone the true posture's
    for (posture, expected) in [(Posture::Standing, standing), (Posture::Supine, 0.0)] {
        let mut c = Config {
            muscle_law: MuscleLaw::Hill,
            gravity_loads: GravityLoads::Acting,
            ..Config::default()
        };
        c.subject.posture = posture;
        assert_eq!(c.model_params().abdominal_tone, expected, "{posture:?}");
    }
    // the applied activation carries it
    let t = Torso::new(hill(Posture::Standing)).unwrap();
    assert_eq!(t.applied_activation(MuscleGroup::RectusAbdominis), standing);
    assert_eq!(t.applied_activation(MuscleGroup::Scalenes), 0.0);
    // out of range is refused by name
    let mut p = Params::for_posture_and_law(Posture::Standing, MuscleLaw::Hill);
    p.abdominal_tone = 1.5;
    let e = p.validate().unwrap_err().to_string();
    assert!(e.contains("params.abdominal_tone"), "{e}");
}

/// The hill law's maximal forces are the cited ones: each diaphragm element carries
/// `HILL_DIAPHRAGM_FORCE` over the thesis law's `DIAPHRAGM_FORCE` times its anatomy's force
/// (the fibres' chains share the total by arc), each intercostal `HILL_INTERCOSTAL_TENSION`
/// over `INTERCOSTAL_TENSION` times it; the scalenes and abdominal muscles are unchanged.
#[test]
fn the_hill_law_uses_the_cited_maximal_forces() {
    use breathing_torso::anatomy::{DIAPHRAGM_FORCE, INTERCOSTAL_TENSION};
    use breathing_torso::dynamics::muscle::{HILL_DIAPHRAGM_FORCE, HILL_INTERCOSTAL_TENSION};
    let thesis = Torso::new(Config::default()).unwrap();
    let hill = Torso::new(hill(Posture::Standing)).unwrap();
    let (a, m) = (&thesis.compiled().anatomy, &hill.compiled().model);
    for (e, muscle) in a.muscles.iter().enumerate() {
        let f = m.elements.max_force[e];
        let expected = match muscle.group {
            MuscleGroup::Diaphragm => muscle.max_force * HILL_DIAPHRAGM_FORCE / DIAPHRAGM_FORCE,
            MuscleGroup::ExternalIntercostals | MuscleGroup::InternalIntercostals => {
                muscle.max_force * HILL_INTERCOSTAL_TENSION / INTERCOSTAL_TENSION
            }
            _ => muscle.max_force,
        };
        assert!(
            (f - expected).abs() <= 1e-9 * expected,
            "{:?}: {f} against {expected}",
            muscle.group
        );
    }
}

/// The hill law standing through the FMU with `postural_tone` = `on` (the default) or off.
fn hill_standing(postural_tone: bool) -> Laws {
    Laws {
        muscle: MuscleLaw::Hill,
        gravity_loads: GravityLoads::Preloaded,
        postural_tone,
    }
}

/// With `postural_tone` = 0 the FMU's 10 cmH2O airway-opening step measures the relaxed
/// respiratory system, the one the relaxation bench measures with every muscle relaxed
/// (`bench::relaxation`, which zeroes the tone): two routes to the same equilibria, one
/// settling dynamically through the FMU, the other solving quasi-static equilibria. The step
/// starts at the bench's FRC and ends where the relaxed system's recoil (alveolar pressure,
/// airway shut) is 10 cmH2O, so its compliance is the secant of the bench's curve from FRC to
/// 10 cmH2O, read off the curve by linear interpolation between its points. Tolerance
/// 0.001 L/cmH2O (10 mL on the step's held volume) from the two methods' errors: the curve's
/// points lie 0.23 L apart there, where the recoil's slope falls from 9.4 to 9.1 cmH2O/L
/// from one interval to the next (measured), so the interpolation errs by about 1 mL (h^2
/// |p''| / 8 = 0.01 cmH2O); the step is called settled when the volume moved less than 0.1 mL over a second,
/// under 0.5 mL from the end for time constants up to 5 s. The rest is the same equilibrium
/// solved twice, within 0.1 mL. The bench's tidal-range compliance (FRC to FRC + 0.5 L, the
/// 0.0991 of `torso bench relaxation --muscle-law hill`) is printed beside it: the step spans
/// about 1 L, where the curve is softer.
#[test]
fn with_the_tone_off_the_fmu_step_measures_the_relaxed_system() {
    use breathing_torso::bench::physiology::PRESSURE_STEP;
    use breathing_torso::bench::relaxation::CMH2O;
    let relaxed = pressure_step(Posture::Standing, 1, hill_standing(false)).unwrap();
    let toned = pressure_step(Posture::Standing, 1, hill_standing(true)).unwrap();
    let r = relaxation(&hill(Posture::Standing), 25).unwrap();
    let target = PRESSURE_STEP * CMH2O;
    let held = r
        .points
        .windows(2)
        .find_map(|w| {
            let (a, b) = (w[0].system - target, w[1].system - target);
            (a <= 0.0 && b > 0.0).then(|| w[0].lung + (w[1].lung - w[0].lung) * (-a) / (b - a))
        })
        .expect("the relaxed curve reaches 10 cmH2O");
    let secant = (held - r.frc) / PRESSURE_STEP;
    println!(
        "hill, standing, through the FMU: postural_tone 0: rest {:.4} L, held {:.4} L, C_rs \
         {:.4} L/cmH2O; postural_tone 1: rest {:.4} L, C_rs {:.4} L/cmH2O; relaxation bench: \
         FRC {:.4} L, {held:.4} L at 10 cmH2O, secant {secant:.4} L/cmH2O, tidal-range C_rs \
         {:.4} L/cmH2O",
        relaxed.rest,
        relaxed.held,
        relaxed.compliance,
        toned.rest,
        toned.compliance,
        r.frc,
        r.system_compliance
    );
    assert!(
        (relaxed.rest - r.frc).abs() < 1e-4,
        "FMU rest {} L against the bench's FRC {} L",
        relaxed.rest,
        r.frc
    );
    assert!(
        (relaxed.compliance - secant).abs() < 1e-3,
        "FMU C_rs {} against the bench's {secant} L/cmH2O",
        relaxed.compliance
    );
    assert!(
        within(relaxed.compliance, SYSTEM_COMPLIANCE),
        "C_rs {} against {SYSTEM_COMPLIANCE:?}",
        relaxed.compliance
    );
}

/// The FMU's lung volume at the start (the rest, drive off) of the default subject standing
/// at level of detail 0 under muscle law `law` with `postural_tone` = `tone`, when given.
fn fmu_rest(law: i32, tone: Option<i32>) -> f64 {
    use breathing_torso::fmi::instance::Instance;
    use breathing_torso::fmi::variables::table;
    use breathing_torso::fmi::{FMI2, Status};
    let t = table();
    let vr = |n: &str| t.by_name(n).unwrap().vr;
    let mut inst = Instance::new(&FMI2, "t", None, None, false);
    let mut set = |name: &str, v: i32| {
        assert_eq!(
            inst.set_integer("fmi2SetInteger", &[vr(name)], &[v]),
            Status::Ok,
            "{name} = {v}"
        )
    };
    set("scene.level_of_detail", 0);
    set("muscle_law", law);
    if let Some(tone) = tone {
        set("postural_tone", tone);
    }
    assert_eq!(
        inst.set_boolean("fmi2SetBoolean", &[vr("drive.enabled")], &[0]),
        Status::Ok
    );
    inst.setup_experiment("fmi2SetupExperiment", None, 0.0, None);
    assert_eq!(inst.enter_initialization_mode(), Status::Ok);
    assert_eq!(
        inst.exit_initialization_mode("fmi2ExitInitializationMode"),
        Status::Ok
    );
    let mut v = [0.0];
    assert_eq!(
        inst.get_real("fmi2GetReal", &[vr("volume.lung")], &mut v),
        Status::Ok
    );
    v[0]
}

/// The library's model of the default subject standing at level of detail 0 under `law`,
/// the drive off, with `postural_tone` = `tone`, or, with `zero_tone`, with its own
/// constants carrying no abdominal tone.
fn library_torso(law: MuscleLaw, tone: bool, zero_tone: bool) -> Torso {
    let mut c = Config {
        muscle_law: law,
        postural_tone: tone,
        ..Config::default()
    };
    c.scene.level_of_detail = 0;
    c.drive.enabled = false;
    if zero_tone {
        let mut p = c.model_params();
        p.abdominal_tone = 0.0;
        c.params = Some(p);
    }
    Torso::new(c).unwrap()
}

/// The standing tone lowers the end-expiratory volume (De Troyer 1983; the direction only),
/// and `postural_tone` = 0 is the model without it: the FMU's rest is the library's with its
/// constants' tone set to 0, bit for bit, as is the compiled model (its fingerprint); with
/// the tone on it is the library's default. Under the thesis's law, which has no tone, the
/// switch changes nothing.
#[test]
fn the_postural_tone_switch_removes_the_tone() {
    let on = fmu_rest(1, None);
    let off = fmu_rest(1, Some(0));
    println!("hill, standing, lod 0: rest {on:.4} L with the tone, {off:.4} L without");
    assert!(on < off, "with the tone {on} L, without {off} L");
    assert_eq!(on, fmu_rest(1, Some(1)));
    let volume = |t: &mut Torso| t.read(Quantity::LungVolume).unwrap();
    let mut toned = library_torso(MuscleLaw::Hill, true, false);
    let mut switched = library_torso(MuscleLaw::Hill, false, false);
    let mut zeroed = library_torso(MuscleLaw::Hill, true, true);
    assert_eq!(on, volume(&mut toned));
    assert_eq!(off, volume(&mut switched));
    assert_eq!(off, volume(&mut zeroed));
    assert_eq!(
        switched.snapshot().fingerprint,
        zeroed.snapshot().fingerprint
    );
    assert_ne!(
        switched.snapshot().fingerprint,
        toned.snapshot().fingerprint
    );
    assert_eq!(
        switched.applied_activation(MuscleGroup::RectusAbdominis),
        0.0
    );
    assert_eq!(fmu_rest(0, Some(0)), fmu_rest(0, None));
    let thesis = |tone: bool| {
        let mut c = Config {
            postural_tone: tone,
            ..Config::default()
        };
        c.subject.posture = Posture::Standing;
        c.model_params()
    };
    assert_eq!(thesis(false), thesis(true));
}

/// `postural_tone` outside 0-1 is refused with an error naming it, through the FMU (the
/// start value is 1), the C ABI (`bt_config_set` and `bt_create`) and the command line; a
/// configuration written before the switch existed reads it on.
#[test]
fn postural_tone_out_of_range_is_refused_by_name() {
    use breathing_torso::capi::*;
    use breathing_torso::fmi::instance::{Instance, LogSink};
    use breathing_torso::fmi::variables::table;
    use breathing_torso::fmi::{FMI2, Status};
    use std::sync::{Arc, Mutex};
    let t = table();
    let vr = t.by_name("postural_tone").expect("an FMU variable").vr;
    let log = Arc::new(Mutex::new(Vec::<String>::new()));
    let sink_log = log.clone();
    let sink: LogSink =
        Box::new(move |_s, _c: &str, m: &str| sink_log.lock().unwrap().push(m.to_string()));
    let mut inst = Instance::new(&FMI2, "t", None, Some(sink), false);
    let mut start = [-1];
    assert_eq!(
        inst.get_integer("fmi2GetInteger", &[vr], &mut start),
        Status::Ok
    );
    assert_eq!(start[0], 1);
    for bad in [2, -1] {
        assert_ne!(
            inst.set_integer("fmi2SetInteger", &[vr], &[bad]),
            Status::Ok
        );
    }
    let messages = log.lock().unwrap().join("\n");
    assert!(messages.contains("postural_tone"), "{messages}");
    unsafe {
        let mut config = std::mem::zeroed::<BtConfig>();
        assert_eq!(bt_config_default(&mut config), BT_OK);
        assert_eq!(config.postural_tone, 1);
        assert_eq!(
            bt_config_set(&mut config, c"postural_tone".as_ptr(), 0.0),
            BT_OK
        );
        assert_eq!(config.postural_tone, 0);
        assert_ne!(
            bt_config_set(&mut config, c"postural_tone".as_ptr(), 2.0),
            BT_OK
        );
        assert_eq!(config.postural_tone, 0);
        config.level_of_detail = 0;
        config.postural_tone = 2;
        let h = bt_create(&config);
        assert!(h.is_null());
        let message = std::ffi::CStr::from_ptr(bt_creation_error()).to_string_lossy();
        assert!(
            message.contains("postural_tone") && message.contains("0 off or 1 on"),
            "{message}"
        );
    }
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_torso"))
        .args([
            "simulate",
            "--lod",
            "0",
            "--duration",
            "0.1",
            "--postural-tone",
            "maybe",
        ])
        .current_dir(std::env::temp_dir())
        .output()
        .expect("run torso");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(
        err.contains("--postural-tone") && err.contains("on or off"),
        "{err}"
    );
    // a configuration written before the switch existed
    let mut json = serde_json::to_value(Config::default()).unwrap();
    json.as_object_mut().unwrap().remove("postural_tone");
    let old: Config = serde_json::from_value(json).unwrap();
    assert!(old.postural_tone);
}
