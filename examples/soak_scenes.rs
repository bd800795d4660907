//! Re-runs chosen scenes of the random-scene soak (`torso bench soak`) without the others:
//! the scenes are drawn in order from the same seed, and only the listed indices are
//! simulated, each checked as the soak checks it. Prints the outcome with the smallest and
//! largest lung volume and the lung volumes where the pleural law's barriers stand.
//!
//!     cargo run --release --example soak_scenes -- SEED LOD SECONDS [margin=M] INDEX...
//!     cargo run --release --example soak_scenes -- 2011 0 60 35
//!
//! `margin=M` replaces the default `params.pleural_barrier_margin`.

use breathing_torso::bench::{random_scene, stress_torso};
use breathing_torso::dynamics::Params;
use breathing_torso::model::Torso;
use breathing_torso::numeric::rng::Pcg64;

fn main() -> breathing_torso::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let num = |i: usize, default: f64| {
        args.get(i)
            .and_then(|s| s.parse::<f64>().ok())
            .unwrap_or(default)
    };
    let (seed, lod, seconds) = (num(0, 2011.0) as u64, num(1, 0.0) as u32, num(2, 60.0));
    let wanted: Vec<usize> = args.iter().skip(3).filter_map(|s| s.parse().ok()).collect();
    let margin: Option<f64> = args
        .iter()
        .find_map(|s| s.strip_prefix("margin=").and_then(|m| m.parse().ok()));
    let last = wanted.iter().copied().max().unwrap_or(0);
    let mut rng = Pcg64::new(seed, 6);
    for i in 0..=last {
        let mut config = random_scene(&mut rng, lod)?;
        if !wanted.contains(&i) {
            continue;
        }
        if let Some(m) = margin {
            let mut params = Params::for_posture(config.subject.posture);
            params.pleural_barrier_margin = m;
            config.params = Some(params);
        }
        let start = std::time::Instant::now();
        let mut torso = Torso::new(config.clone())?;
        let model = &torso.compiled().model;
        let litres = 1e3 * config.lung_ratio;
        // as observed: the mesh's thorax less the dome's faceting volume
        let d = model.dome_faceting_volume;
        let (rest, rv, tlc) = (
            (model.thorax_rest_volume - d) * litres,
            (model.pleural.lower - d) * litres,
            (model.pleural.upper - d) * litres,
        );
        let outcome = stress_torso(&mut torso, seconds, 56.0)?;
        let stats = torso.solver_stats();
        println!(
            "scene {i} (seed {seed}, margin {}): {outcome:?}; lung at rest {rest:.3} L, barriers RV {rv:.3} L, TLC {tlc:.3} L; {} steps, {} RHS evaluations, {:.1} s wall\n  {config:?}",
            config
                .params
                .as_ref()
                .map_or(breathing_torso::dynamics::PLEURAL_BARRIER_MARGIN, |p| p
                    .pleural_barrier_margin),
            stats.steps,
            stats.rhs_evaluations,
            start.elapsed().as_secs_f64()
        );
    }
    Ok(())
}
