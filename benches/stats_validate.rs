//! Benchmark of a full validation: an 18 s pair (1,000 samples at 56 Hz against a 100 Hz
//! spirogram) including the three BARS chains of 2,200 iterations each. Prints the median
//! wall time of the validation alone and with all outputs (JSON, CSV, PNG and SVG plots).
//!
//! Run: `cargo bench --bench stats_validate` (target: median under 2 s).

use breathing_torso::stats::io::Series;
use breathing_torso::stats::prepare::SpiroKind;
use breathing_torso::stats::synth::{SpiroSynthOptions, VolumeSource, synth_spirometry};
use breathing_torso::stats::validation::{ValidationOptions, validate, write_outputs};
use std::f64::consts::PI;
use std::time::Instant;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let fs = 56.0;
    let n = 1000;
    let time: Vec<f64> = (0..n).map(|i| i as f64 / fs).collect();
    let values: Vec<f64> = time
        .iter()
        .map(|&t| {
            let a = 2.0 * PI * 0.27 * t;
            2.5 + 0.25 * (1.0 - a.cos()) + 0.03 * (2.0 * a).sin()
        })
        .collect();
    let sim = Series {
        time,
        values,
        column: "lung_volume".into(),
        source: "simulated curve".into(),
    };
    let spiro = synth_spirometry(
        &VolumeSource::Curve(sim.clone()),
        &SpiroSynthOptions {
            noise_sd: 0.01,
            drift_l_per_s: 0.002,
            start_offset_s: 0.3,
            scale: 1.04,
            ..Default::default()
        },
    )
    .expect("synthetic spirogram");
    let opts = ValidationOptions::default();
    assert_eq!(opts.bars.burn_in + opts.bars.samples, 2200);
    let dir = std::env::temp_dir().join(format!("torso-bench-validate-{}", std::process::id()));
    let runs = 7;
    let (mut core, mut full) = (Vec::new(), Vec::new());
    for _ in 0..runs {
        let t0 = Instant::now();
        let v = validate(&sim, &spiro, SpiroKind::Volume, &opts).expect("validation");
        let t1 = Instant::now();
        write_outputs(&v, &dir).expect("outputs");
        let t2 = Instant::now();
        core.push((t1 - t0).as_secs_f64());
        full.push((t2 - t0).as_secs_f64());
    }
    std::fs::remove_dir_all(&dir).ok();
    println!(
        "validate (1000 samples, BARS 3 x 2200 iterations): median {:.3} s over {runs} runs",
        median(core)
    );
    println!(
        "validate + outputs (JSON, CSV, 4 PNG + 4 SVG):      median {:.3} s over {runs} runs",
        median(full)
    );
}
