//! How the quiet and forced scenarios' drive amplitudes set the default subject's breath and
//! surface-marker motion: tidal volume, compartment swings and rib-cage share, dome
//! excursion, abdominal pressure swing, end-expiratory volume, then the upper-chest markers'
//! displacement (rows 2-3 of the grid: mean, largest, smallest; per litre of rib-cage
//! displacement) and each marker within 5 cm of the omphalion (ventral and cranial mm, ventral
//! fraction), from end-expiration to end-inspiration of the second breath. With `forced`, the
//! forced scenario too and the forced / quiet ratios of the mean displacements.
//!
//! `cargo run --release --example marker_calibration [forced] [supine] [female] [stature=M]
//! [rg=F dg=F] [frg=F fdg=F] [membrane=F compliance=F joint=F support=F domemem=F betad=F]`:
//! `female` is a 1.63 m, 60 kg woman with breast size 0.4, `stature` replaces the subject's;
//! `rg`, `dg` scale the quiet rib and diaphragm amplitudes, `frg`, `fdg` the forced ones; the
//! others scale the model's constants (membrane and dome-membrane stiffness, abdominal wall
//! compliance, rib-joint stiffness, dome support, the diaphragm's largest contraction).

// Shared helpers of the examples; not every one is used here.
#[allow(dead_code)]
mod common;
use breathing_torso::model::Drive;
use breathing_torso::model::run::{run, summarise};
use common::*;
use nalgebra::Vector3;

fn one(mut drive: Drive, name: &str, prefix: &str) -> (f64, f64) {
    drive.ribs.amplitude =
        (drive.ribs.amplitude * factor_from_args(&format!("{prefix}rg"))).min(1.0);
    drive.diaphragm.amplitude =
        (drive.diaphragm.amplitude * factor_from_args(&format!("{prefix}dg"))).min(1.0);
    let tune = |p: &mut breathing_torso::dynamics::Params| {
        p.membrane_stiffness *= factor_from_args("membrane");
        p.abdominal_wall_compliance *= factor_from_args("compliance");
        p.rib_joint_stiffness *= factor_from_args("joint");
        p.dome_support *= factor_from_args("support");
        p.dome_membrane_stiffness *= factor_from_args("domemem");
        p.beta_max_diaphragm *= factor_from_args("betad");
    };
    let mut t = torso_with(drive, tune);
    let period = 1.0 / drive.frequency;
    let frames = run(&mut t, 3.0 * period, 28.0).unwrap();
    let s = summarise(&frames, period);
    println!(
        "{name} ribs {:.3} dia {:.3}: VT {:.3} rc {:.3} ab {:.3} share {:.1}% exc {:.2} cm dP {:.0} Pa EELV {:.3}",
        drive.ribs.amplitude,
        drive.diaphragm.amplitude,
        s.tidal_volume,
        s.rib_cage_swing,
        s.abdomen_swing,
        100.0 * s.rib_cage_share,
        100.0 * s.dome_excursion,
        s.pressure_swing,
        s.end_expiratory_volume
    );
    let mut t = torso_with(drive, tune);
    let om = t.marker_model().unwrap().skin().landmarks.omphalion_height;
    let rest = t.markers().unwrap().to_vec();
    let (lo, hi) = second_breath(&mut t, &[]);
    let mut m = |st: &[f64]| {
        let tm = t.time();
        t.set_state(tm, st).unwrap();
        t.markers().unwrap().to_vec()
    };
    let (ml, mh) = (m(&lo.state), m(&hi.state));
    let d: Vec<Vector3<f64>> = mh.iter().zip(&ml).map(|(a, b)| (a - b) * 1e3).collect();
    let up: Vec<usize> = (6..18).collect();
    let norms: Vec<f64> = up.iter().map(|&i| d[i].norm()).collect();
    let umean = norms.iter().sum::<f64>() / 12.0;
    println!(
        "  upper chest mean {:.2} max {:.2} min {:.2} mm/L(rc) {:.1}",
        umean,
        norms.iter().cloned().fold(0.0, f64::max),
        norms.iter().cloned().fold(f64::INFINITY, f64::min),
        umean / s.rib_cage_swing
    );
    let mut bs = Vec::new();
    for i in 0..rest.len() {
        let p = rest[i];
        if (p.y - om).hypot(p.z) < 0.05 {
            print!(
                "  m{} v {:.2} c {:.2} ({:.2})",
                i + 1,
                d[i].x,
                d[i].y,
                d[i].x / d[i].norm()
            );
            bs.push(d[i].norm());
        }
    }
    println!();
    (umean, bs.iter().sum::<f64>() / bs.len() as f64)
}

fn main() {
    let q = one(Drive::quiet(), "quiet", "");
    if std::env::args().any(|a| a == "forced") {
        let f = one(Drive::forced(), "forced", "f");
        println!("ratios: upper {:.2} umbilicus {:.2}", f.0 / q.0, f.1 / q.1);
    }
}
