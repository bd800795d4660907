//! Marker benchmarks of the default subject (10 x 6 grid, level of detail 1):
//!
//! - marker model build (skin around the anatomy, bone-heat weights, grid binding), median
//!   of 3 (issue target: weights under 2 s);
//! - 60 markers per frame: handle poses from the state, influence motions, blend of the
//!   bound points, median over 2,000 states of a quiet breath (target under 20 us);
//! - whole-skin deformation per frame, median over 200 states (target under 1 ms);
//! - a 1000-frame quiet run at 56 Hz reading the volumes only, against the same run also
//!   reading the 60 markers' 180 coordinates (the ratio shows what markers add).
//!
//! Run: `cargo bench --bench markers`.

use breathing_torso::model::Drive;
use breathing_torso::observe::markers::{MarkerModel, MarkerScene};
use breathing_torso::{Config, Quantity, Torso};
use std::hint::black_box;
use std::time::Instant;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn quiet() -> Config {
    Config {
        drive: Drive::quiet(),
        ..Config::default()
    }
}

fn run(frames: usize, markers: bool) -> f64 {
    let mut torso = Torso::new(quiet()).expect("default model");
    if markers {
        torso.marker_model().expect("marker model"); // built once, outside the timing
    }
    let start = Instant::now();
    let mut sum = 0.0;
    for i in 1..=frames {
        torso.advance_to(i as f64 / 56.0).expect("quiet run");
        for q in [
            Quantity::LungVolume,
            Quantity::ThoraxVolume,
            Quantity::AbdomenVolume,
            Quantity::RibCageDisplaced,
            Quantity::AbdomenDisplaced,
        ] {
            sum += torso.read(q).expect("volume");
        }
        if markers {
            for index in 0..60u16 {
                for axis in 0..3u8 {
                    sum += torso
                        .read(Quantity::Marker { index, axis })
                        .expect("marker");
                }
            }
        }
    }
    black_box(sum);
    start.elapsed().as_secs_f64()
}

fn main() {
    let torso = Torso::new(quiet()).expect("default model");
    let compiled = torso.compiled().clone();
    let mut builds = Vec::new();
    let mut model = None;
    for _ in 0..3 {
        let t = Instant::now();
        model = Some(
            MarkerModel::build(&compiled.anatomy, &compiled.model, &MarkerScene::default())
                .expect("marker model"),
        );
        builds.push(t.elapsed().as_secs_f64());
    }
    let model = model.expect("built");
    println!(
        "marker model build (skin, weights of {} handles in {} influences, grid): median {:.0} ms of 3",
        model.handles().len(),
        model.skinning().influences().len(),
        median(builds) * 1e3
    );

    // States of a quiet breath.
    let mut torso = Torso::new(quiet()).expect("default model");
    let mut states = Vec::new();
    for i in 1..=224 {
        torso.advance_to(i as f64 / 56.0).expect("quiet run");
        states.push(torso.state().to_vec());
    }
    let mut scratch = Default::default();
    let mut out = Vec::new();
    let mut per_frame = Vec::new();
    for k in 0..2000 {
        let t = Instant::now();
        model
            .markers(&states[k % states.len()], &mut scratch, &mut out)
            .expect("markers");
        per_frame.push(t.elapsed().as_secs_f64());
        black_box(&out);
    }
    println!(
        "60 markers per frame: median {:.2} us",
        median(per_frame) * 1e6
    );
    let mut whole = Vec::new();
    for k in 0..200 {
        let t = Instant::now();
        model
            .skin_vertices(&states[k % states.len()], &mut scratch, &mut out)
            .expect("skin");
        whole.push(t.elapsed().as_secs_f64());
        black_box(&out);
    }
    println!(
        "whole skin ({} vertices) per frame: median {:.1} us",
        out.len(),
        median(whole) * 1e6
    );

    let frames = 1000;
    let plain = (0..3).map(|_| run(frames, false)).fold(f64::MAX, f64::min);
    let with = (0..3).map(|_| run(frames, true)).fold(f64::MAX, f64::min);
    println!(
        "{frames} frames at 56 Hz (best of 3): volumes only {:.3} s, volumes + 60 markers {:.3} s, ratio {:.3}",
        plain,
        with,
        with / plain
    );
}
