//! Mesh convergence of the breathing: the quiet tidal volume at the levels of detail. Issue
//! 19 fits a recording made at one level of detail at another and accepts a tidal volume
//! within 10 %; a fit can only meet that if the two levels breathe alike, so the target is
//! that the levels' quiet tidal volumes agree within 5 %.
//!
//! Asserted: levels 1 and 2 (the default and full detail), under the default law and, in a
//! test ignored while it misses, under the passive-and-active law. Printed, not asserted:
//! level 0, whose quiet tidal volume is 2.7 % below level 2's under the default law, its
//! diaphragm alone 6.7 % (its dome has 28 muscular vertices and 52 fibre elements, whose
//! chords from the insertions pull the lower ribs inward, `cargo run --release --example
//! lod_diaphragm`).

use breathing_torso::Torso;
use breathing_torso::dynamics::muscle::MuscleLaw;
use breathing_torso::model::run::{BreathSummary, run, summarise};
use breathing_torso::model::{Config, Drive};

/// Quiet breathing at level of detail `lod` under muscle law `law`: two breaths after a
/// settling one.
fn quiet(lod: u32, drive: Drive, law: MuscleLaw) -> BreathSummary {
    let mut config = Config {
        drive,
        muscle_law: law,
        ..Config::default()
    };
    config.scene.level_of_detail = lod;
    let mut torso = Torso::new(config).unwrap();
    let period = 1.0 / drive.frequency;
    let frames = run(&mut torso, 3.0 * period, 28.0).unwrap();
    summarise(&frames, period)
}

/// The quiet breath under `law` with its quiet drive at levels 0, 1 and 2, and the same with
/// the diaphragm alone (the rib family silent), printed with the levels' gaps to level 2;
/// returns how far level 1 is from level 2 (a fraction).
fn level_gap(law: MuscleLaw) -> f64 {
    let drive = Drive::quiet_for(law);
    let mut diaphragm_only = drive;
    diaphragm_only.ribs.amplitude = 0.0;
    let mut vt = Vec::new();
    let mut alone = Vec::new();
    for lod in 0..3 {
        let s = quiet(lod, drive, law);
        let d = quiet(lod, diaphragm_only, law);
        println!(
            "{law:?}, level {lod}: quiet VT {:.4} L, rib cage {:.4} L ({:.1} %), excursion \
             {:.2} cm; diaphragm alone VT {:.4} L",
            s.tidal_volume,
            s.tidal_volume * s.rib_cage_share,
            100.0 * s.rib_cage_share,
            100.0 * s.dome_excursion,
            d.tidal_volume
        );
        vt.push(s.tidal_volume);
        alone.push(d.tidal_volume);
    }
    for lod in [0, 1] {
        println!(
            "{law:?}, level {lod} against level 2: {:+.1} %, diaphragm alone {:+.1} %",
            100.0 * (vt[lod] / vt[2] - 1.0),
            100.0 * (alone[lod] / alone[2] - 1.0)
        );
    }
    (vt[1] / vt[2] - 1.0).abs()
}

#[test]
fn quiet_tidal_volume_agrees_between_levels_1_and_2_within_5_percent() {
    let gap = level_gap(MuscleLaw::default());
    assert!(gap < 0.05, "levels 1 and 2 differ by {:.1} %", 100.0 * gap);
}

/// The same target under the passive-and-active law, with its quiet drive at the cited
/// fractions of maximum. Missed: its diaphragm is force-controlled (an activation sets a force,
/// not a rest length), and the pressure the same force makes falls as the mesh is refined;
/// the relaxed chest wall itself agrees across the levels within 2.5 % (`torso bench
/// relaxation --muscle-law hill --lod L`: C_cw 0.2005 / 0.1977 / 0.2025 L/cmH2O), and the rib
/// cage's part of the breath within 3 %. Most of the gap is the tension-only law's fixed
/// 0.1 N toe: every slack element pulls 0.069 N whatever its size, and the finer levels have
/// more and smaller elements; with the toe at a hundredth levels 1 and 2 are 2.8 % apart
/// (`cargo run --release --example lod_toe -- 1 0.01`), but the relaxed hill wall leans on
/// that pull for want of a resting prestress (docs/dynamics.md).
#[test]
#[ignore = "issue 35: under the hill law levels 1 and 2 differ by 8.5 % (quiet VT 0.7107 / 0.6643 / 0.6121 L at levels 0 / 1 / 2; the diaphragm alone 0.1512 / 0.1354 / 0.1104 L, +22.6 % at level 1), most of it the fixed toe (2.8 % with it at a hundredth, examples/lod_toe.rs); cargo test --release --test lod_convergence -- --ignored --nocapture"]
fn hill_quiet_tidal_volume_agrees_between_levels_1_and_2_within_5_percent() {
    let gap = level_gap(MuscleLaw::Hill);
    assert!(gap < 0.05, "levels 1 and 2 differ by {:.1} %", 100.0 * gap);
}
