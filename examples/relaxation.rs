//! The passive respiratory system measured as a physiologist measures it: all muscles off,
//! the airway opening held at a pressure step after step (a ventilator's static inflation,
//! Agostoni & Rahn's relaxation curve), the lungs settled at each step. Prints, per step,
//! the lung volume above rest, the alveolar and pleural pressures and the compliances of the
//! respiratory system (dV / P_ao), the lungs (dV / (P_A - P_pl - P_L0)) and the chest wall
//! (dV / (P_pl + P_L0)), and the flow left at the end of each step.
//!
//! `cargo run --release --example relaxation -- [LOD] [POSTURE] [SECONDS]`
//! (defaults: 1, standing, 8 s per step)

use breathing_torso::anatomy::Posture;
use breathing_torso::model::{Drive, Scene};
use breathing_torso::{Config, Quantity, Torso};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let lod: u32 = args.get(1).map(|s| s.parse()).transpose()?.unwrap_or(1);
    let posture = match args.get(2).map(String::as_str) {
        Some("supine") => Posture::Supine,
        Some("sitting") => Posture::Sitting,
        _ => Posture::Standing,
    };
    let seconds: f64 = args.get(3).map(|s| s.parse()).transpose()?.unwrap_or(8.0);
    let mut config = Config {
        drive: Drive {
            enabled: false,
            ..Drive::quiet()
        },
        scene: Scene {
            level_of_detail: lod,
            ..Scene::default()
        },
        ..Config::default()
    };
    config.subject.posture = posture;
    let mut torso = Torso::new(config)?;
    let cmh2o = 98.0665;
    let rest = torso.read(Quantity::LungVolume)?;
    let p_rest = torso.read(Quantity::PleuralPressure)? / cmh2o;
    println!(
        "level of detail {lod}, {posture:?}: rest lung volume {rest:.4} L, pleural pressure {p_rest:+.2} cmH2O"
    );
    println!(
        "{:>8} {:>10} {:>9} {:>9} {:>9} {:>9} {:>9} {:>11}",
        "P_ao", "dV [L]", "P_A", "P_pl", "C_rs", "C_L", "C_cw", "flow [L/s]"
    );
    let mut t = 0.0;
    for p in [-10.0, -5.0, 2.5, 5.0, 10.0, 15.0, 20.0] {
        torso.set_airway_opening(p * cmh2o)?;
        t += seconds;
        torso.advance_to(t)?;
        let dv = torso.read(Quantity::LungVolume)? - rest;
        let pa = torso.read(Quantity::AlveolarPressure)? / cmh2o;
        let ppl = torso.read(Quantity::PleuralPressure)? / cmh2o;
        let flow = torso.read(Quantity::AirwayFlow)?;
        // Transpulmonary and chest-wall pressures as changes from rest.
        let p_lung = pa - ppl + p_rest;
        let p_wall = ppl - p_rest;
        println!(
            "{p:>8.1} {dv:>+10.4} {pa:>+9.3} {ppl:>+9.3} {:>9.4} {:>9.4} {:>9.4} {flow:>+11.2e}",
            dv / p,
            dv / p_lung,
            dv / p_wall
        );
    }
    Ok(())
}
