//! Accuracy and cost of the frame loop: 1000 frames (56 Hz) of quiet breathing, default
//! subject, lung volume and the 60 markers read every frame, at the given tolerance against a
//! reference at rtol 1e-10 (atol 1e-12) of the same model; then the tidal volumes of the first
//! three breaths. With `toe`, the quiet tidal volume with the tension-only law's toe halved
//! and doubled.
//!
//! `cargo run --release --example fast_dynamics -- [LOD] [RTOL] [exact] [toe]`
//! (`exact`: end a step on every frame instead of stepping past them).

use breathing_torso::dynamics::Params;
use breathing_torso::model::{Drive, Scene, SolverConfig};
use breathing_torso::{Config, Quantity, Torso};

/// Lung volumes [L] and marker positions [m] of every frame, the RHS evaluations, steps and
/// rejections, and the wall time of the loop.
struct Run {
    lung: Vec<f64>,
    markers: Vec<Vec<f64>>,
    rhs: f64,
    steps: f64,
    rejected: f64,
    wall: f64,
}

fn config(lod: u32, rtol: f64, atol: f64, past: bool) -> Config {
    // experiments: KEY=FACTOR scales a constant (if, sgaw, toe, zeta, wall, bulk);
    // tilt=F sets the transverse fraction
    let mut params = Params::for_posture(breathing_torso::anatomy::Posture::Standing);
    for a in std::env::args().skip(1) {
        if let Some((k, v)) = a.split_once('=') {
            let f: f64 = v.parse().expect("KEY=FACTOR");
            match k {
                "if" => params.inertia_frequency *= f,
                "sgaw" => params.specific_airway_conductance *= f,
                "toe" => params.tension_toe *= f,
                "tilt" => params.transverse_fraction = f,
                "zeta" => params.damping_ratio *= f,
                "wall" => params.abdominal_wall_compliance *= f,
                "bulk" => params.bulk_modulus *= f,
                _ => panic!("unknown constant {k}"),
            }
        }
    }
    Config {
        params: Some(params),
        drive: Drive::quiet(),
        scene: Scene {
            level_of_detail: lod,
            ..Scene::default()
        },
        solver: SolverConfig {
            rtol,
            atol,
            step_past_outputs: past,
            ..SolverConfig::default()
        },
        ..Config::default()
    }
}

fn run(config: Config, frames: usize) -> Run {
    let mut torso = Torso::new(config).expect("default subject builds");
    // build the marker model outside the timed loop
    torso.markers().expect("markers");
    let start = std::time::Instant::now();
    let mut lung = Vec::with_capacity(frames);
    let mut markers = Vec::with_capacity(frames);
    for i in 1..=frames {
        torso
            .advance_to(i as f64 / 56.0)
            .expect("quiet breathing integrates");
        lung.push(torso.read(Quantity::LungVolume).expect("lung volume"));
        let m: Vec<f64> = torso
            .markers()
            .expect("markers")
            .iter()
            .flat_map(|p| [p.x, p.y, p.z])
            .collect();
        markers.push(m);
    }
    let wall = start.elapsed().as_secs_f64();
    let mut read = |q| torso.read(q).expect("stats");
    Run {
        lung,
        markers,
        rhs: read(Quantity::SolverRhsEvaluations),
        steps: read(Quantity::SolverSteps),
        rejected: read(Quantity::SolverRejectedSteps),
        wall,
    }
}

/// Tidal volumes [L] of the breaths of a 0.25 Hz drive in `lung` (frames at 56 Hz).
fn tidal_volumes(lung: &[f64]) -> Vec<f64> {
    lung.chunks(224)
        .filter(|c| c.len() == 224)
        .map(|c| {
            let (lo, hi) = c
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
                    (a.min(*v), b.max(*v))
                });
            hi - lo
        })
        .collect()
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let lod: u32 = args.first().and_then(|s| s.parse().ok()).unwrap_or(1);
    let rtol: f64 = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(1e-6);
    let past = !args.iter().any(|a| a == "exact");
    if args.iter().any(|a| a == "toe") {
        for factor in [0.5, 1.0, 2.0] {
            let mut c = config(lod, 1e-8, 1e-10, true);
            let mut p = Params::for_posture(c.subject.posture);
            p.tension_toe *= factor;
            c.params = Some(p);
            let r = run(c, 672);
            let tv = tidal_volumes(&r.lung);
            println!("LOD {lod}, toe x{factor}: tidal volumes {tv:.5?} L");
        }
        return;
    }
    let reference = run(config(lod, 1e-10, 1e-12, false), 1000);
    let r = run(config(lod, rtol, rtol * 1e-2, past), 1000);
    let lung_error = r
        .lung
        .iter()
        .zip(&reference.lung)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    let marker_error = r
        .markers
        .iter()
        .zip(&reference.markers)
        .flat_map(|(a, b)| {
            a.chunks(3).zip(b.chunks(3)).map(|(p, q)| {
                ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt()
            })
        })
        .fold(0.0, f64::max);
    println!(
        "LOD {lod}, rtol {rtol:e} ({}): {} RHS evaluations, {} steps (+{} rejected), wall {:.3} s; \
         max lung-volume error {lung_error:.2e} L, max marker error {:.2e} mm \
         (reference rtol 1e-10: {} RHS evaluations)",
        if past {
            "stepping past the frames"
        } else {
            "a step ends on every frame"
        },
        r.rhs,
        r.steps,
        r.rejected,
        r.wall,
        marker_error * 1e3,
        reference.rhs
    );
    let tv = tidal_volumes(&reference.lung);
    println!("tidal volumes of the breaths (reference run): {tv:.4?} L");
    let ends: Vec<f64> = reference.lung.iter().step_by(56).copied().collect();
    println!("lung volume every second: {ends:.4?} L");
}
