//! The quasi-static mode frame by frame: lung volume, pleural pressure and the static
//! solver's work, for quiet breathing of the default subject.
//!
//! `cargo run --release --example quasi_static -- [LOD] [RTOL] [SECONDS]`

use breathing_torso::model::{Config, Quantity, Torso};
use breathing_torso::solver::Method;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let lod: u32 = args.get(1).map_or(Ok(1), |s| s.parse())?;
    let rtol: f64 = args.get(2).map_or(Ok(1e-6), |s| s.parse())?;
    let seconds: f64 = args.get(3).map_or(Ok(17.86), |s| s.parse())?;
    let mut config = Config::default();
    config.scene.level_of_detail = lod;
    config.solver.method = Method::QuasiStatic;
    config.solver.rtol = rtol;
    if let Ok(h) = std::env::var("BT_HMAX") {
        config.solver.max_step = h.parse()?;
    }
    config.drive = breathing_torso::model::Drive::quiet();
    if let Ok(f) = std::env::var("BT_PARAM") {
        let mut p = breathing_torso::dynamics::Params::for_posture(config.subject.posture);
        let mut v = serde_json::to_value(&p)?;
        for kv in f.split(',') {
            let (k, x) = kv.split_once('=').ok_or("k=v")?;
            let x: f64 = x.parse()?;
            let old = v[k].as_f64().ok_or("no such param")?;
            v[k] = serde_json::json!(old * x);
        }
        p = serde_json::from_value(v)?;
        config.params = Some(p);
    }
    let mut torso = Torso::new(config)?;
    let frames = (seconds * 56.0).round() as usize;
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for k in 1..=frames {
        let t = k as f64 / 56.0;
        torso.advance_to(t)?;
        let v = torso.read(Quantity::LungVolume)?;
        if k % 28 == 0 {
            let p = torso.read(Quantity::PleuralPressure)?;
            println!("t {t:.3} lung {v:.6} L pleural {:.3} cmH2O", p / 98.0665);
        }
        if t > 4.0 {
            lo = lo.min(v);
            hi = hi.max(v);
        }
    }
    println!("tidal volume {:.4} L", hi - lo);
    println!("{:?}", torso.solver_stats());
    println!("{:?}", torso.statics_stats());
    Ok(())
}
