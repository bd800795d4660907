//! Writes the dense finite-difference Jacobian of the right-hand side at a state of quiet
//! breathing, for an eigenvalue analysis of what limits an explicit solver's step
//! (`python/spectrum.py` reads it).
//!
//! `cargo run --release --example jacobian_dump -- LOD TIME FILE`: the default subject at
//! level of detail `LOD`, quiet drive, after `TIME` seconds; `FILE` holds the dimension n
//! (u64, little-endian) then the n x n matrix column by column (f64, little-endian), column j
//! being (f(y + h e_j) - f(y)) / h with h = 1e-7 max(|y_j|, 0.01). Optional trailing
//! `rw=R` sets the abdominal wall's resistance [cmH2O s/L] and `tilt=A` the transverse
//! fraction, to compare spectra with and without them.

use breathing_torso::model::{Drive, Scene};
use breathing_torso::{Config, Torso};
use std::io::Write;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    if args.len() < 4 {
        return Err("usage: jacobian_dump LOD TIME FILE [rw=R] [tilt=A]".into());
    }
    let mut params =
        breathing_torso::dynamics::Params::for_posture(breathing_torso::anatomy::Posture::Standing);
    for a in &args[4..] {
        match a.split_once('=') {
            Some(("rw", v)) => params.abdominal_wall_resistance = v.parse::<f64>()? * 98.0665e3,
            Some(("tilt", v)) => params.transverse_fraction = v.parse()?,
            _ => return Err(format!("unknown option {a}").into()),
        }
    }
    let lod: u32 = args[1].parse()?;
    let t: f64 = args[2].parse()?;
    let config = Config {
        params: Some(params),
        drive: Drive::quiet(),
        scene: Scene {
            level_of_detail: lod,
            ..Scene::default()
        },
        ..Config::default()
    };
    let mut torso = Torso::new(config)?;
    torso.advance_to(t)?;
    let y0 = torso.state().to_vec();
    let n = y0.len();
    let mut f0 = vec![0.0; n];
    torso.rhs(t, &y0, &mut f0)?;
    let mut f = vec![0.0; n];
    let mut y = y0.clone();
    let mut file = std::io::BufWriter::new(std::fs::File::create(&args[3])?);
    file.write_all(&(n as u64).to_le_bytes())?;
    for j in 0..n {
        let h = 1e-7 * y0[j].abs().max(1e-2);
        y[j] = y0[j] + h;
        torso.rhs(t, &y, &mut f)?;
        y[j] = y0[j];
        for i in 0..n {
            file.write_all(&((f[i] - f0[i]) / h).to_le_bytes())?;
        }
    }
    println!("wrote the {n} x {n} Jacobian at t = {t} s to {}", args[3]);
    Ok(())
}
