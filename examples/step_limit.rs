//! What moves the explicit solver's step limit: 1000 frames (56 Hz) of quiet breathing with
//! Dormand-Prince at rtol 1e-6, default subject, with the model's constants or masses scaled
//! (experiments, not model options). Prints RHS evaluations, steps and the lung volume's range.
//!
//! `cargo run --release --example step_limit -- [LOD]`

use breathing_torso::anatomy::{Anatomy, VertexRole};
use breathing_torso::dynamics::{Model, Params};
use breathing_torso::model::{Compiled, Drive, Scene};
use breathing_torso::{Config, Quantity, Torso};
use std::sync::Arc;

/// One run: `tendon` scales the central tendon's stiffness, `dome` and `wall` the masses of
/// the dome's and the wall's free vertices, `bones` the masses (and so the inertias) of the
/// ribs and the sternum.
fn run(
    lod: u32,
    tendon: f64,
    dome: f64,
    wall: f64,
    bones: f64,
) -> Result<(), Box<dyn std::error::Error>> {
    let config = Config {
        drive: Drive::quiet(),
        scene: Scene {
            level_of_detail: lod,
            ..Scene::default()
        },
        ..Config::default()
    };
    let mut anatomy = Anatomy::build(&config.subject, lod)?;
    for (m, role) in anatomy.abdomen.mass.iter_mut().zip(&anatomy.abdomen.roles) {
        *m *= match role {
            VertexRole::Dome => dome,
            _ => wall,
        };
    }
    for rib in &mut anatomy.ribs {
        for (_, m) in &mut rib.mass_points {
            *m *= bones;
        }
    }
    anatomy.sternum.mass *= bones;
    let mut params = Params::for_posture(config.subject.posture);
    params.tendon_stiffness *= tendon;
    let model = Model::compile(&anatomy, params);
    let compiled = Compiled::from_model(anatomy, model);
    let mut torso = Torso::with_compiled(config, Arc::new(compiled))?;
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for i in 1..=1000 {
        torso.advance_to(i as f64 / 56.0)?;
        let v = torso.read(Quantity::LungVolume)?;
        (lo, hi) = (lo.min(v), hi.max(v));
    }
    let s = torso.solver_stats();
    println!(
        "LOD {lod}, tendon x{tendon}, dome mass x{dome}, wall mass x{wall}, rib and sternum mass x{bones}: {} RHS evaluations, {} steps (+{} rejected), lung volume range {:.3} L",
        s.rhs_evaluations,
        s.steps,
        s.rejected,
        hi - lo
    );
    Ok(())
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let lod: u32 = std::env::args()
        .nth(1)
        .map(|s| s.parse())
        .transpose()?
        .unwrap_or(1);
    for (tendon, dome, wall, bones) in [
        (1.0, 1.0, 1.0, 1.0),
        (0.25, 1.0, 1.0, 1.0),
        (0.0625, 1.0, 1.0, 1.0),
        (1.0, 4.0, 1.0, 1.0),
        (1.0, 4.0, 4.0, 1.0),
        (1.0, 1.0, 1.0, 4.0),
        (1.0, 4.0, 1.0, 4.0),
    ] {
        run(lod, tendon, dome, wall, bones)?;
    }
    Ok(())
}
