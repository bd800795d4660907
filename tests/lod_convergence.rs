//! Mesh convergence of the breathing: the quiet tidal volume at the levels of detail. Issue
//! 19 fits a recording made at one level of detail at another and accepts a tidal volume
//! within 10 %; a fit can only meet that if the two levels breathe alike, so the target is
//! that the levels' quiet tidal volumes agree within 5 %.
//!
//! Asserted: levels 1 and 2 (the default and full detail). Printed, not asserted: level 0,
//! which falls short of that target (its quiet tidal volume is 5.1 % below level 2's, its
//! diaphragm alone 10.2 %: its dome has 28 muscular vertices and 52 fibre elements, whose
//! chords from the insertions pull the lower ribs inward, `cargo run --release --example
//! lod_diaphragm`).

use breathing_torso::Torso;
use breathing_torso::model::run::{BreathSummary, run, summarise};
use breathing_torso::model::{Config, Drive};

/// Quiet breathing at level of detail `lod`: two breaths after a settling one.
fn quiet(lod: u32, drive: Drive) -> BreathSummary {
    let mut config = Config {
        drive,
        ..Config::default()
    };
    config.scene.level_of_detail = lod;
    let mut torso = Torso::new(config).unwrap();
    let period = 1.0 / drive.frequency;
    let frames = run(&mut torso, 3.0 * period, 28.0).unwrap();
    summarise(&frames, period)
}

#[test]
fn quiet_tidal_volume_agrees_between_levels_1_and_2_within_5_percent() {
    let mut diaphragm_only = Drive::quiet();
    diaphragm_only.ribs.amplitude = 0.0;
    let mut vt = Vec::new();
    let mut alone = Vec::new();
    for lod in 0..3 {
        let s = quiet(lod, Drive::quiet());
        let d = quiet(lod, diaphragm_only);
        println!(
            "level {lod}: quiet VT {:.4} L, rib-cage share {:.1} %, excursion {:.2} cm; \
             diaphragm alone VT {:.4} L",
            s.tidal_volume,
            100.0 * s.rib_cage_share,
            100.0 * s.dome_excursion,
            d.tidal_volume
        );
        vt.push(s.tidal_volume);
        alone.push(d.tidal_volume);
    }
    for lod in [0, 1] {
        println!(
            "level {lod} against level 2: {:+.1} %, diaphragm alone {:+.1} %",
            100.0 * (vt[lod] / vt[2] - 1.0),
            100.0 * (alone[lod] / alone[2] - 1.0)
        );
    }
    let gap = (vt[1] / vt[2] - 1.0).abs();
    assert!(gap < 0.05, "levels 1 and 2 differ by {:.1} %", 100.0 * gap);
}
