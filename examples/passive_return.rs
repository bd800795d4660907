//! The passive return to rest when the drive stops: 2 s of quiet breathing at level of
//! detail 0, then the drive switched off for 10 s; prints the lung volume's swing over the
//! last 2 s and the volume every 2 s, with and without the transverse fraction and the
//! abdominal wall's resistance (docs/dynamics.md).
//!
//! `cargo run --release --example passive_return`

use breathing_torso::anatomy::Posture;
use breathing_torso::dynamics::Params;
use breathing_torso::model::{Drive, Scene};
use breathing_torso::{Config, Quantity, Torso};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    for (tilt, resistance) in [(0.0, 0.0), (0.1, 0.0), (0.0, 1.0), (0.1, 1.0)] {
        let mut params = Params::for_posture(Posture::Standing);
        params.transverse_fraction = tilt;
        params.abdominal_wall_resistance = resistance * 98.0665e3;
        let config = Config {
            params: Some(params),
            drive: Drive::quiet(),
            scene: Scene {
                level_of_detail: 0,
                ..Scene::default()
            },
            ..Config::default()
        };
        let mut torso = Torso::new(config)?;
        torso.advance_to(2.0)?;
        let mut off = Drive::quiet();
        off.ribs.amplitude = 0.0;
        off.diaphragm.amplitude = 0.0;
        off.abdominals.amplitude = 0.0;
        torso.set_drive(off)?;
        let mut lung = Vec::new();
        for k in 1..=100 {
            torso.advance_to(2.0 + 0.1 * k as f64)?;
            lung.push(torso.read(Quantity::LungVolume)?);
        }
        let tail = &lung[80..];
        let swing = tail.iter().cloned().fold(f64::MIN, f64::max)
            - tail.iter().cloned().fold(f64::MAX, f64::min);
        let every: Vec<String> = [19, 39, 59, 79, 99]
            .iter()
            .map(|&i| format!("{:.6}", lung[i]))
            .collect();
        println!(
            "transverse fraction {tilt}, wall resistance {resistance} cmH2O s/L: swing over the last 2 s {swing:.2e} L; lung volume at 4, 6, 8, 10, 12 s: {} L",
            every.join(", ")
        );
    }
    Ok(())
}
