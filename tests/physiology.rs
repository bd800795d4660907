//! Physics against physiology: the default subject breathes within the ranges of the
//! physiology reference (tidal volumes, FRC, diaphragm excursion, compartment shares, rib
//! rotation), each muscle group does what anatomy says it does, and the rest state is an
//! equilibrium.

use breathing_torso::anatomy::{MuscleGroup, Posture};
use breathing_torso::model::run::{BreathSummary, run, summarise};
use breathing_torso::model::{Config, Drive, Wave};
use breathing_torso::{Quantity, Torso};

/// Runs `drive` for two breaths after one settling breath and summarises the last two.
fn breathe(drive: Drive, posture: Posture) -> (BreathSummary, Torso) {
    let mut config = Config {
        drive,
        ..Config::default()
    };
    config.subject.posture = posture;
    let mut torso = Torso::new(config).unwrap();
    let period = 1.0 / drive.frequency;
    let frames = run(&mut torso, 3.0 * period, 28.0).unwrap();
    (summarise(&frames, period), torso)
}

fn only(group: &str, amplitude: f64) -> Drive {
    let w = Wave {
        amplitude,
        phase: 0.0,
    };
    let z = Wave::default();
    match group {
        "ribs" => Drive {
            frequency: 0.25,
            ribs: w,
            diaphragm: z,
            abdominals: z,
        },
        "diaphragm" => Drive {
            frequency: 0.25,
            ribs: z,
            diaphragm: w,
            abdominals: z,
        },
        _ => Drive {
            frequency: 0.25,
            ribs: z,
            diaphragm: z,
            abdominals: w,
        },
    }
}

#[test]
fn rest_is_an_equilibrium_near_frc() {
    let mut torso = Torso::new(Config::default()).unwrap();
    let frc = torso.config().subject.frc_ecsc();
    let lung = torso.read(Quantity::LungVolume).unwrap();
    println!("rest lung volume {lung:.3} L, ECSC FRC {frc:.3} L");
    assert!(
        (lung - frc).abs() <= 0.3 * frc,
        "rest lung volume {lung} L vs FRC {frc} L"
    );
    let y0 = torso.state().to_vec();
    torso.advance_to(60.0).unwrap();
    let drift = torso
        .state()
        .iter()
        .zip(&y0)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    println!("largest state drift over 60 s at rest: {drift:e}");
    assert!(drift < 1e-6, "rest drifts by {drift}");
}

#[test]
fn quiet_and_forced_breathing_are_physiological() {
    let (quiet, _) = breathe(Drive::quiet(), Posture::Standing);
    let (forced, _) = breathe(Drive::forced(), Posture::Standing);
    for (name, s) in [("quiet", quiet), ("forced", forced)] {
        println!(
            "{name}: VT {:.3} L, EELV {:.3} L, rib share {:.1} %, excursion {:.2} cm ({:.2} cm/L), abdomen swing {:.3} %, pressure swing {:.0} Pa",
            s.tidal_volume,
            s.end_expiratory_volume,
            100.0 * s.rib_cage_share,
            100.0 * s.dome_excursion,
            100.0 * s.dome_excursion / s.tidal_volume,
            100.0 * s.abdomen_relative_swing,
            s.pressure_swing
        );
    }
    assert!(
        (0.35..=0.8).contains(&quiet.tidal_volume),
        "quiet tidal volume {}",
        quiet.tidal_volume
    );
    assert!(
        (1.2..=3.5).contains(&forced.tidal_volume),
        "forced tidal volume {}",
        forced.tidal_volume
    );
    assert!(
        quiet.abdomen_relative_swing < 0.01,
        "abdominal volume swing {}",
        quiet.abdomen_relative_swing
    );
    assert!(
        (0.01..=0.03).contains(&quiet.dome_excursion),
        "quiet excursion {}",
        quiet.dome_excursion
    );
    assert!(
        (0.035..=0.07).contains(&forced.dome_excursion),
        "forced excursion {}",
        forced.dome_excursion
    );
    for s in [quiet, forced] {
        let cm_per_l = 100.0 * s.dome_excursion / s.tidal_volume;
        assert!((1.2..=2.2).contains(&cm_per_l), "{cm_per_l} cm/L");
    }
    assert!(
        (0.40..=0.75).contains(&quiet.rib_cage_share),
        "upright rib-cage share {}",
        quiet.rib_cage_share
    );
}

#[test]
fn supine_breathing_is_more_abdominal() {
    let (upright, _) = breathe(Drive::quiet(), Posture::Standing);
    let (supine, _) = breathe(Drive::quiet(), Posture::Supine);
    println!(
        "rib-cage share: upright {:.3}, supine {:.3}",
        upright.rib_cage_share, supine.rib_cage_share
    );
    assert!(supine.rib_cage_share < upright.rib_cage_share);
}

#[test]
fn tidal_volume_grows_with_each_amplitude() {
    for family in ["ribs", "diaphragm"] {
        let mut last = 0.0;
        for a in [0.1, 0.2, 0.3, 0.4] {
            let (s, _) = breathe(only(family, a), Posture::Standing);
            println!("{family} amplitude {a}: VT {:.3} L", s.tidal_volume);
            assert!(
                s.tidal_volume > last,
                "{family}: VT {} at amplitude {a} not above {last}",
                s.tidal_volume
            );
            last = s.tidal_volume;
        }
    }
}
