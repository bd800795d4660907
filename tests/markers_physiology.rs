//! Marker motion of the default upright subject against the physiology reference (issue
//! acceptance): over the breath after one settling breath, upper-chest markers move 1-6 mm,
//! mostly cranially and ventrally; markers near the umbilicus move 2-10 mm, mostly
//! ventrally; forced breathing moves them about three times more.
//!
//! Groups, fixed before looking at the results: the upper chest is the second and third
//! rows of the 10 x 6 grid (about 2-10 cm below the clavicle line, over the manubrium and
//! upper sternum); "near the umbilicus" is every marker within 5 cm of the omphalion on the
//! midline. A marker's motion is its displacement from end-expiration (smallest lung volume
//! of the second breath) to end-inspiration (largest), sampled at 56 Hz.
//!
//! The same checks run under the passive-and-active muscle law with its own drives
//! (`Drive::quiet_for`, `Drive::scenario_for`); those it misses are ignored with their
//! figures (issue 35).

use breathing_torso::dynamics::muscle::MuscleLaw;
use breathing_torso::model::Drive;
use breathing_torso::{Config, Quantity, Torso};
use nalgebra::{Point3, Vector3};
use std::sync::OnceLock;

struct Breath {
    displacement: Vec<Vector3<f64>>,
    rest: Vec<Point3<f64>>,
    omphalion: Point3<f64>,
    tidal: f64,
}

fn breath(drive: Drive, muscle_law: MuscleLaw) -> Breath {
    let config = Config {
        drive,
        muscle_law,
        ..Config::default()
    };
    let mut torso = Torso::new(config).unwrap();
    let model = torso.marker_model().unwrap();
    let lm = &model.skin().landmarks;
    let omphalion = Point3::new(0.0, lm.omphalion_height, 0.0);
    let rest = torso.markers().unwrap().to_vec();
    let period = 1.0 / drive.frequency;
    let rate = 56.0;
    let n = (2.0 * period * rate).round() as usize;
    let mut lo = (f64::INFINITY, Vec::new());
    let mut hi = (f64::NEG_INFINITY, Vec::new());
    for i in 1..=n {
        let t = i as f64 / rate;
        torso.advance_to(t).unwrap();
        if t < period - 1e-9 {
            continue;
        }
        let v = torso.read(Quantity::LungVolume).unwrap();
        if v < lo.0 {
            lo = (v, torso.markers().unwrap().to_vec());
        }
        if v > hi.0 {
            hi = (v, torso.markers().unwrap().to_vec());
        }
    }
    Breath {
        displacement: hi.1.iter().zip(&lo.1).map(|(a, b)| a - b).collect(),
        rest,
        omphalion,
        tidal: hi.0 - lo.0,
    }
}

fn quiet() -> &'static Breath {
    static B: OnceLock<Breath> = OnceLock::new();
    B.get_or_init(|| breath(Drive::quiet(), MuscleLaw::Thesis))
}

fn forced() -> &'static Breath {
    static B: OnceLock<Breath> = OnceLock::new();
    B.get_or_init(|| breath(Drive::forced(), MuscleLaw::Thesis))
}

fn hill_quiet() -> &'static Breath {
    static B: OnceLock<Breath> = OnceLock::new();
    B.get_or_init(|| breath(Drive::quiet_for(MuscleLaw::Hill), MuscleLaw::Hill))
}

fn hill_forced() -> &'static Breath {
    static B: OnceLock<Breath> = OnceLock::new();
    let forced = Drive::scenario_for("forced", MuscleLaw::Hill).unwrap();
    B.get_or_init(|| breath(forced, MuscleLaw::Hill))
}

const COLS: usize = 6;

fn upper_chest() -> Vec<usize> {
    (COLS..3 * COLS).collect()
}

fn near_umbilicus(b: &Breath) -> Vec<usize> {
    (0..b.rest.len())
        .filter(|&i| {
            let p = b.rest[i];
            (p.y - b.omphalion.y).hypot(p.z) < 0.05
        })
        .collect()
}

fn report(name: &str, b: &Breath, group: &[usize]) -> f64 {
    println!("{name}: tidal volume {:.3} L", b.tidal);
    let mut sum = 0.0;
    for &i in group {
        let d = b.displacement[i] * 1e3;
        println!(
            "  marker[{:2}] |d| {:5.2} mm  ventral {:6.2}  cranial {:6.2}  right {:6.2}",
            i + 1,
            d.norm(),
            d.x,
            d.y,
            d.z
        );
        sum += d.norm();
    }
    let mean = sum / group.len() as f64;
    println!("  mean {mean:.2} mm");
    mean
}

/// Upper-chest markers move 1-6 mm, mostly cranially and ventrally.
fn upper_chest_moves_1_to_6_mm_cranially_and_ventrally(b: &Breath) {
    let group = upper_chest();
    report("quiet, upper chest", b, &group);
    for &i in &group {
        let d = b.displacement[i] * 1e3;
        let n = d.norm();
        assert!(
            (1.0..=6.0).contains(&n),
            "marker[{}] moves {n:.2} mm",
            i + 1
        );
        assert!(
            d.x > 0.0 && d.y > 0.0 && d.x * d.x + d.y * d.y >= 0.8 * n * n,
            "marker[{}] moves {d:?} mm: not mostly cranial and ventral",
            i + 1
        );
    }
}

#[test]
fn quiet_upper_chest_moves_1_to_6_mm_cranially_and_ventrally() {
    upper_chest_moves_1_to_6_mm_cranially_and_ventrally(quiet());
}

#[test]
#[ignore = "issue 35: under the hill law the upper chest moves 6.17 mm on average, its largest marker (13) 8.72 mm, against 1-6 mm; cargo test --release --test markers_physiology -- --ignored --nocapture"]
fn hill_quiet_upper_chest_moves_1_to_6_mm_cranially_and_ventrally() {
    upper_chest_moves_1_to_6_mm_cranially_and_ventrally(hill_quiet());
}

/// Markers within 5 cm of the umbilicus move 2-10 mm, mostly ventrally.
fn umbilical_markers_move_2_to_10_mm_ventrally(b: &Breath) {
    let group = near_umbilicus(b);
    assert!(!group.is_empty());
    report("quiet, near the umbilicus", b, &group);
    for &i in &group {
        let d = b.displacement[i] * 1e3;
        let n = d.norm();
        assert!(
            (2.0..=10.0).contains(&n),
            "marker[{}] moves {n:.2} mm",
            i + 1
        );
        assert!(
            d.x >= 0.7 * n,
            "marker[{}] moves {d:?} mm: not mostly ventral",
            i + 1
        );
    }
}

#[test]
fn quiet_umbilical_markers_move_2_to_10_mm_ventrally() {
    umbilical_markers_move_2_to_10_mm_ventrally(quiet());
}

#[test]
#[ignore = "issue 35: under the hill law the markers near the umbilicus move 0.57-1.01 mm (mean 0.78), against 2-10 mm: its quiet breath's abdominal share is 25 %; cargo test --release --test markers_physiology -- --ignored --nocapture"]
fn hill_quiet_umbilical_markers_move_2_to_10_mm_ventrally() {
    umbilical_markers_move_2_to_10_mm_ventrally(hill_quiet());
}

/// The top row lies on the clavicle line (thesis 3.2), whose skin is held by the clavicles;
/// the shoulder girdle does not take part in quiet breathing, so that row moves less than
/// the rows over the ribs below it: every top-row marker under 4 mm, and the row's mean under
/// half the upper chest's.
fn clavicle_line_moves_less_than_the_chest_below(b: &Breath) {
    let top: Vec<usize> = (0..COLS).collect();
    let mean_top = report("quiet, clavicle line", b, &top);
    let mean_chest = report("quiet, upper chest", b, &upper_chest());
    for &i in &top {
        let n = b.displacement[i].norm() * 1e3;
        assert!(n < 4.0, "marker[{}] moves {n:.2} mm", i + 1);
    }
    assert!(
        mean_top < 0.5 * mean_chest,
        "clavicle line {mean_top:.2} mm against {mean_chest:.2} mm below"
    );
}

#[test]
fn the_clavicle_line_moves_less_than_the_chest_below() {
    clavicle_line_moves_less_than_the_chest_below(quiet());
}

#[test]
fn hill_the_clavicle_line_moves_less_than_the_chest_below() {
    clavicle_line_moves_less_than_the_chest_below(hill_quiet());
}

/// Forced breathing moves the upper chest's and the umbilical markers 2-4 times as far as
/// quiet breathing (about 3x, Kaneko & Horie 2012).
fn forced_moves_markers_2_to_4_times_as_far(q: &Breath, f: &Breath) {
    for (name, group) in [
        ("upper chest", upper_chest()),
        ("near the umbilicus", near_umbilicus(q)),
    ] {
        let mq = report(&format!("quiet, {name}"), q, &group);
        let mf = report(&format!("forced, {name}"), f, &group);
        let ratio = mf / mq;
        println!("{name}: forced / quiet = {ratio:.2}");
        assert!(
            (2.0..=4.0).contains(&ratio),
            "{name}: forced / quiet mean displacement {ratio:.2}"
        );
    }
}

#[test]
fn forced_breathing_moves_markers_about_three_times_more() {
    forced_moves_markers_2_to_4_times_as_far(quiet(), forced());
}

#[test]
#[ignore = "issue 35: under the hill law the forced breath (1.793 L) moves the upper chest 0.61 times as far as the quiet one (0.664 L), against 2-4 times: its drive, the thesis law's forced amplitudes x HILL_DRIVE_SCALE (no EMG source), has the abdominals at 0.125 in expiration, which end it at 2.147 L with a 34.3 % rib-cage share (torso simulate --muscle-law hill --scenario forced --duration 20; without them 1.062 L, 65.5 %); cargo test --release --test markers_physiology -- --ignored --nocapture"]
fn hill_forced_breathing_moves_markers_about_three_times_more() {
    forced_moves_markers_2_to_4_times_as_far(hill_quiet(), hill_forced());
}
