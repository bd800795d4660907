//! The drives' calibration, and the breathing figures they give under a muscle law.
//!
//! `cargo run --release --example drive_calibration -- --fit` finds the common factor s on
//! the quiet drive's rib-cage and diaphragm amplitudes (their ratio kept) for which the default
//! subject (75 kg, standing, level of detail 1) breathes 7 mL/kg, 0.525 L (West & Luks,
//! Respiratory Physiology: The Essentials, 10th ed. 2016: 500 mL for 70 kg), by the secant on
//! log VT against log s from s = 1, then scales the forced drive's three amplitudes by the same
//! factor and checks (does not fit) that its tidal volume lies in deep breathing's 1.5-3 L. It
//! prints the amplitudes to put in `Drive::quiet` and `Drive::forced`; run again once they are
//! there, it finds a factor of 1 up to their rounding.
//!
//! Without `--fit` it prints, for `Drive::quiet` and `Drive::forced` standing and supine, the
//! tidal volume, the rib-cage and abdominal shares of the displaced volume, the pleural
//! pressure swing and the diaphragm's excursion per litre. `--law thesis|hill` picks the muscle
//! law (`Params::for_posture_and_law`; default: `Params::for_posture`'s); `--lod N` the level
//! of detail (default 1); `--scale S` multiplies both drives' amplitudes by S (the factor
//! `--fit` prints), for the figures a law gives with its calibrated drives. The drives here
//! are the thesis law's, `Drive::quiet` and `Drive::forced`: under the hill law the built-in
//! quiet drive is not fitted but set at cited fractions of maximum (`Drive::quiet_for`,
//! `HILL_QUIET_DIAPHRAGM`, `HILL_QUIET_RIBS`), so `--law hill --fit` is a what-if, not the
//! source of a constant.

use breathing_torso::anatomy::Posture;
use breathing_torso::dynamics::Params;
use breathing_torso::dynamics::muscle::MuscleLaw;
use breathing_torso::model::run::{frame, summarise};
use breathing_torso::model::{AdvanceOptions, Config, Drive};
use breathing_torso::{Quantity, Torso};

/// The quiet tidal volume per kilogram the quiet drive is calibrated to [L/kg].
/// Source: West & Luks, Respiratory Physiology: The Essentials, 10th ed. 2016: 500 mL for a
/// 70 kg adult, about 7 mL/kg.
const QUIET_VT_PER_KG: f64 = 0.007;

/// Deep breathing's tidal volume [L], checked for the forced drive (the project's physiology
/// reference: between three times a quiet breath and about two thirds of the default man's
/// 4.9 L vital capacity, ECSC 1993).
const FORCED_VT: std::ops::RangeInclusive<f64> = 1.5..=3.0;

/// One cmH2O in pascals.
const CMH2O: f64 = 98.0665;

struct Figures {
    tidal_volume: f64,
    rib_cage_share: f64,
    pleural_swing: f64,
    cm_per_litre: f64,
}

/// Three breaths of `drive`, the last two summarised (the first settles), as the physiology
/// tests run them (28 frames per second).
fn breathe(law: Option<MuscleLaw>, lod: u32, posture: Posture, drive: Drive) -> Figures {
    let mut config = Config {
        drive,
        ..Config::default()
    };
    config.scene.level_of_detail = lod;
    config.subject.posture = posture;
    config.params = Some(match law {
        Some(law) => Params::for_posture_and_law(posture, law),
        None => Params::for_posture(posture),
    });
    let mut torso = Torso::new(config).unwrap();
    let period = 1.0 / drive.frequency;
    let rate = 28.0;
    let n = (3.0 * period * rate).round() as usize;
    let options = AdvanceOptions {
        check_physiology: true,
    };
    let mut frames = vec![frame(&mut torso).unwrap()];
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for i in 1..=n {
        let t = i as f64 / rate;
        torso.advance_to_with(t, options).unwrap();
        frames.push(frame(&mut torso).unwrap());
        if t >= period - 1e-9 {
            let p = torso.read(Quantity::PleuralPressure).unwrap();
            lo = lo.min(p);
            hi = hi.max(p);
        }
    }
    let s = summarise(&frames, period);
    Figures {
        tidal_volume: s.tidal_volume,
        rib_cage_share: s.rib_cage_share,
        pleural_swing: (hi - lo) / CMH2O,
        cm_per_litre: 100.0 * s.dome_excursion / s.tidal_volume,
    }
}

/// `drive` with every amplitude times `s`.
fn scaled(drive: Drive, s: f64) -> Drive {
    let mut d = drive;
    d.ribs.amplitude *= s;
    d.diaphragm.amplitude *= s;
    d.abdominals.amplitude *= s;
    d
}

fn print(name: &str, posture: Posture, f: &Figures) {
    println!(
        "{name} {posture:?}: VT {:.3} L, rib cage {:.1} %, abdomen {:.1} %, pleural swing {:.2} \
         cmH2O, diaphragm {:.2} cm/L",
        f.tidal_volume,
        100.0 * f.rib_cage_share,
        100.0 * (1.0 - f.rib_cage_share),
        f.pleural_swing,
        f.cm_per_litre
    );
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let value = |flag: &str| {
        args.iter()
            .position(|a| a == flag)
            .and_then(|i| args.get(i + 1).cloned())
    };
    let law = value("--law").map(|l| MuscleLaw::parse(&l).unwrap());
    let lod: u32 = value("--lod").map_or(1, |v| v.parse().unwrap());
    let law_name = law.map_or("default".to_string(), |l| format!("{l:?}"));
    println!("muscle law: {law_name}; level of detail {lod}");
    if args.iter().any(|a| a == "--fit") {
        fit(law, lod);
        return;
    }
    // `--scale S`: the drives' amplitudes times S (a factor `--fit` found)
    let s: f64 = value("--scale").map_or(1.0, |v| v.parse().unwrap());
    for posture in [Posture::Standing, Posture::Supine] {
        for (name, drive) in [("quiet", Drive::quiet()), ("forced", Drive::forced())] {
            let f = breathe(law, lod, posture, scaled(drive, s));
            print(name, posture, &f);
        }
    }
}

fn fit(law: Option<MuscleLaw>, lod: u32) {
    let config = Config::default();
    let target = QUIET_VT_PER_KG * config.subject.mass;
    let quiet = Drive::quiet();
    let vt = |s: f64| breathe(law, lod, Posture::Standing, scaled(quiet, s)).tidal_volume;
    let (mut s0, mut v0) = (1.0, vt(1.0));
    println!("factor {s0:.5}: quiet VT {v0:.4} L (target {target:.4} L)");
    // First guess: VT proportional to the amplitudes.
    let mut s1 = s0 * target / v0;
    let mut v1 = vt(s1);
    println!("factor {s1:.5}: quiet VT {v1:.4} L");
    for _ in 0..8 {
        if (v1 / target - 1.0).abs() < 1e-3 {
            break;
        }
        let slope = (v1.ln() - v0.ln()) / (s1.ln() - s0.ln());
        let s2 = (s1.ln() + (target.ln() - v1.ln()) / slope).exp();
        (s0, v0) = (s1, v1);
        s1 = s2;
        v1 = vt(s1);
        println!("factor {s1:.5}: quiet VT {v1:.4} L");
    }
    let forced = Drive::forced();
    println!(
        "fitted factor {s1:.4}: quiet A_ribs {:.4}, A_diaphragm {:.4}; forced A_ribs {:.4}, \
         A_diaphragm {:.4}, A_abdominals {:.4}",
        quiet.ribs.amplitude * s1,
        quiet.diaphragm.amplitude * s1,
        forced.ribs.amplitude * s1,
        forced.diaphragm.amplitude * s1,
        forced.abdominals.amplitude * s1
    );
    let f = breathe(law, lod, Posture::Standing, scaled(forced, s1));
    print("forced (scaled)", Posture::Standing, &f);
    println!(
        "forced VT {:.3} L {} deep breathing's {:.1}-{:.1} L",
        f.tidal_volume,
        if FORCED_VT.contains(&f.tidal_volume) {
            "within"
        } else {
            "OUTSIDE"
        },
        FORCED_VT.start(),
        FORCED_VT.end()
    );
}
