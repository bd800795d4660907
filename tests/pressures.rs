//! Pressures and flow against the respiratory system's laws: the alveolar pressure is the
//! airway opening's less the drop across the airway resistance, the pleural pressure the
//! alveolar one less the lungs' recoil (about -5 cmH2O at rest and 1 cmH2O more negative per
//! 0.2 L inspired, the lung compliance), the flow integrates to the lung volume, and a
//! ventilator's pressure at the airway opening inflates relaxed lungs and reaches the
//! alveolar and pleural pressures without a step.

use breathing_torso::anatomy::Posture;
use breathing_torso::dynamics::{LUNG_RECOIL_AT_FRC, Params};
use breathing_torso::model::Drive;
use breathing_torso::{Config, Quantity, Torso};

const CMH2O: f64 = 98.0665;

/// Lung compliance of the model, 0.2 L/cmH2O (physiology reference), in L/Pa.
fn lung_compliance() -> f64 {
    1e3 / Params::for_posture(Posture::Standing).lung_elastance
}

fn read(torso: &mut Torso) -> [f64; 4] {
    [
        torso.read(Quantity::LungVolume).unwrap(),
        torso.read(Quantity::AlveolarPressure).unwrap(),
        torso.read(Quantity::PleuralPressure).unwrap(),
        torso.read(Quantity::AirwayFlow).unwrap(),
    ]
}

#[test]
fn rest_has_the_pleural_pressure_of_frc_and_no_flow() {
    let mut torso = Torso::new(Config::default()).unwrap();
    let [_, alveolar, pleural, flow] = read(&mut torso);
    println!(
        "rest: alveolar {alveolar} Pa, pleural {:.3} cmH2O, flow {flow} L/s",
        pleural / CMH2O
    );
    assert!(alveolar.abs() < 1e-9 && flow.abs() < 1e-9);
    assert!((pleural + LUNG_RECOIL_AT_FRC).abs() < 1e-6);
}

/// Over quiet breathing: the transpulmonary pressure P_A - P_pl grows by the lung volume over
/// the lung compliance; the alveolar pressure is -R V'; the trapezoid integral of the flow
/// over two breaths follows the lung volume; the pleural pressure swings as much as the lung
/// volume over the compliance plus the resistive drop.
#[test]
fn quiet_breathing_pressures_follow_the_lungs_laws() {
    let drive = Drive::quiet();
    let mut torso = Torso::new(Config {
        drive,
        ..Config::default()
    })
    .unwrap();
    // the lung volume of the rest pose (FRC), then the run from the drive's start
    torso.start_at_rest();
    let rest = torso.read(Quantity::LungVolume).unwrap();
    torso.start_at_equilibrium();
    let period = 1.0 / drive.frequency;
    let n = 400;
    let dt = period / n as f64;
    torso.advance_to(period).unwrap();
    let mut samples = Vec::new();
    for k in 0..=2 * n {
        torso.advance_to(period + k as f64 * dt).unwrap();
        samples.push(read(&mut torso));
    }
    let c = lung_compliance();
    let resistance = {
        // R from the first sample with flow: -P_A / V'.
        let s = samples
            .iter()
            .max_by(|a, b| a[3].abs().total_cmp(&b[3].abs()))
            .unwrap();
        -s[1] / s[3]
    };
    let mut worst_law: f64 = 0.0;
    let mut integral = 0.0;
    let mut worst_flow: f64 = 0.0;
    for (k, s) in samples.iter().enumerate() {
        let [v, alveolar, pleural, flow] = *s;
        let transpulmonary = alveolar - pleural - LUNG_RECOIL_AT_FRC;
        worst_law = worst_law.max((transpulmonary - (v - rest) / c).abs());
        assert!((alveolar + resistance * flow).abs() < 1e-9 * resistance.max(1.0));
        if k > 0 {
            integral += 0.5 * (flow + samples[k - 1][3]) * dt;
            worst_flow = worst_flow.max((integral - (v - samples[0][0])).abs());
        }
    }
    let vt = samples.iter().map(|s| s[0]).fold(f64::MIN, f64::max)
        - samples.iter().map(|s| s[0]).fold(f64::MAX, f64::min);
    let pmin = samples.iter().map(|s| s[2]).fold(f64::MAX, f64::min) / CMH2O;
    let pmax = samples.iter().map(|s| s[2]).fold(f64::MIN, f64::max) / CMH2O;
    let amax = samples.iter().map(|s| s[1].abs()).fold(0.0, f64::max) / CMH2O;
    let qmax = samples.iter().map(|s| s[3].abs()).fold(0.0, f64::max);
    println!(
        "quiet: VT {vt:.3} L, pleural {pmin:.2} .. {pmax:.2} cmH2O, alveolar within +-{amax:.2} cmH2O, peak flow {qmax:.2} L/s, R {:.2} cmH2O s/L; lung law off by {:.2e} cmH2O, flow integral off by {worst_flow:.2e} L",
        resistance / CMH2O,
        worst_law / CMH2O
    );
    // The barriers add nothing within a quiet breath of rest: the law is linear there.
    assert!(worst_law < 0.01 * CMH2O, "{worst_law} Pa");
    assert!(worst_flow < 1e-3 * vt, "{worst_flow} L");
    // The resistance is the model's: 1 / (sGaw FRC), 0.5-2.5 cmH2O s/L in healthy adults.
    assert!((0.5..=2.5).contains(&(resistance / CMH2O)));
    // The pleural pressure swings at least by VT / C_L.
    assert!(pmax - pmin >= vt / c / CMH2O);
}

/// A ventilator's pressure at the airway opening with every muscle relaxed: the alveolar
/// and pleural pressures move with it at once (direct feedthrough, no step), the lung volume
/// only through the dynamics; once the flow has stopped the alveolar pressure equals the
/// applied one and the lungs sit where their law puts them, inflated (or deflated) by the
/// lung compliance times the transpulmonary pressure.
#[test]
fn airway_pressure_inflates_relaxed_lungs() {
    let mut torso = Torso::new(Config {
        drive: Drive {
            enabled: false,
            ..Drive::quiet()
        },
        scene: breathing_torso::model::Scene {
            level_of_detail: 0,
            ..Default::default()
        },
        ..Config::default()
    })
    .unwrap();
    let [rest, _, pleural_rest, _] = read(&mut torso);
    let c = lung_compliance();
    for (k, p) in [5.0, -5.0, 10.0].into_iter().enumerate() {
        let before = read(&mut torso);
        torso.set_airway_opening(p * CMH2O).unwrap();
        let now = read(&mut torso);
        assert_eq!(now[0], before[0], "the volume waits for the dynamics");
        let jump = p * CMH2O - torso_opening_before(k) * CMH2O;
        assert!((now[1] - before[1] - jump).abs() < 1e-9 * CMH2O);
        assert!((now[2] - before[2] - jump).abs() < 1e-9 * CMH2O);
        torso.advance_to(10.0 * (k + 1) as f64).unwrap();
        let [v, alveolar, pleural, flow] = read(&mut torso);
        let dv = v - rest;
        let transpulmonary = alveolar - pleural + pleural_rest;
        println!(
            "P_ao {p:+.1} cmH2O: lung {dv:+.4} L, alveolar {:+.3}, pleural {:+.3} cmH2O, flow {flow:+.1e} L/s, C_rs {:.4} L/cmH2O",
            alveolar / CMH2O,
            pleural / CMH2O,
            dv / p
        );
        assert!(dv * p > 0.0, "the lungs follow the sign of the pressure");
        assert!(flow.abs() < 2e-3, "still flowing: {flow} L/s");
        assert!((alveolar - p * CMH2O).abs() < 0.01 * CMH2O * p.abs());
        assert!((dv - c * transpulmonary).abs() < 0.01 * dv.abs());
    }
    torso.set_airway_opening(1e6).unwrap_err();
}

fn torso_opening_before(k: usize) -> f64 {
    [0.0, 5.0, -5.0][k]
}
