//! What sets the passive chest wall: the chest-wall compliance C_cw of the relaxed model
//! (all muscles off) at an airway-opening step, with each passive constant of
//! `dynamics::Params` made softer by a factor in turn (its stiffness times FACTOR; the
//! abdominal wall's compliance divided by it), then all of them together; then the relaxed
//! muscles, whose elements are springs of stiffness F_max / (beta l0) (`dynamics::Model`):
//! with every activation zero, beta enters only that stiffness, so dividing `beta_max` and
//! `beta_max_diaphragm` by FACTOR softens every muscle element by FACTOR. The same
//! measurement as `examples/relaxation`: the airway opening is held at P_ao from rest for
//! SECONDS, and C_cw = dV / (P_pl - P_pl,rest), with dV the lung volume above rest. Prints,
//! per row, dV, C_cw, its ratio to the defaults' C_cw, the respiratory system's C_rs = dV /
//! P_ao and the flow left at the end of the step (settled when it is small against dV /
//! SECONDS).
//!
//! `cargo run --release --example chest_wall_sensitivity -- [LOD] [POSTURE] [P_AO] [FACTOR] [SECONDS]`
//! (defaults: 1, standing, 5 cmH2O, 0.5, 30 s: 8 s leaves the lungs still filling at 1e-3 L/s)

use breathing_torso::anatomy::Posture;
use breathing_torso::dynamics::Params;
use breathing_torso::model::{Drive, Scene};
use breathing_torso::{Config, Quantity, Torso};

/// A passive constant and how to soften it by a factor f (stiffness x f, compliance / f).
type Soften = fn(&mut Params, f64);

const CONSTANTS: [(&str, Soften); 8] = [
    ("rib_joint_stiffness", |p, f| p.rib_joint_stiffness *= f),
    ("cartilage_stiffness", |p, f| p.cartilage_stiffness *= f),
    ("membrane_stiffness", |p, f| p.membrane_stiffness *= f),
    ("dome_membrane_stiffness", |p, f| {
        p.dome_membrane_stiffness *= f
    }),
    ("tendon_stiffness", |p, f| p.tendon_stiffness *= f),
    ("dome_support", |p, f| p.dome_support *= f),
    ("abdominal_wall_compliance (/ f)", |p, f| {
        p.abdominal_wall_compliance /= f
    }),
    ("bulk_modulus", |p, f| p.bulk_modulus *= f),
];

/// Lung volume above rest [L], chest-wall pressure change [cmH2O] and airway flow [L/s] at
/// the end of a step of `p_ao` cmH2O held for `seconds`.
fn step(
    config: Config,
    p_ao: f64,
    seconds: f64,
) -> Result<(f64, f64, f64), Box<dyn std::error::Error>> {
    let cmh2o = 98.0665;
    let mut torso = Torso::new(config)?;
    let rest = torso.read(Quantity::LungVolume)?;
    let p_rest = torso.read(Quantity::PleuralPressure)? / cmh2o;
    torso.set_airway_opening(p_ao * cmh2o)?;
    torso.advance_to(seconds)?;
    let dv = torso.read(Quantity::LungVolume)? - rest;
    let p_wall = torso.read(Quantity::PleuralPressure)? / cmh2o - p_rest;
    let flow = torso.read(Quantity::AirwayFlow)?;
    Ok((dv, p_wall, flow))
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let lod: u32 = args.get(1).map(|s| s.parse()).transpose()?.unwrap_or(1);
    let posture = match args.get(2).map(String::as_str) {
        None | Some("standing") => Posture::Standing,
        Some("supine") => Posture::Supine,
        Some("sitting") => Posture::Sitting,
        Some(other) => return Err(format!("posture {other:?}: standing, sitting or supine").into()),
    };
    let p_ao: f64 = args.get(3).map(|s| s.parse()).transpose()?.unwrap_or(5.0);
    let factor: f64 = args.get(4).map(|s| s.parse()).transpose()?.unwrap_or(0.5);
    let seconds: f64 = args.get(5).map(|s| s.parse()).transpose()?.unwrap_or(30.0);
    if !(p_ao.is_finite() && p_ao != 0.0 && factor > 0.0 && factor.is_finite() && seconds > 0.0) {
        return Err("P_AO must be non-zero, FACTOR and SECONDS > 0".into());
    }
    let mut base = Config {
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
    base.subject.posture = posture;
    let defaults = Params::for_posture(posture);
    println!(
        "level of detail {lod}, {posture:?}, P_ao {p_ao:+} cmH2O held {seconds} s, each constant softened x{factor}"
    );
    // The abdominal contents' bulk modulus against the gas they hold: an isothermal gas
    // volume V_g at atmospheric pressure gives a cavity of volume V0 the modulus p_atm V0 / V_g.
    let abdomen = Torso::new(base.clone())?.read(Quantity::AbdomenVolume)?;
    let p_atm = 101_325.0;
    println!(
        "abdominal cavity at rest {abdomen:.3} L: bulk modulus {:.0} Pa = isothermal gas of {:.2} L at 1 atm",
        defaults.bulk_modulus,
        p_atm * abdomen / defaults.bulk_modulus
    );
    println!(
        "{:<34} {:>10} {:>9} {:>9} {:>9} {:>11}",
        "softened", "dV [L]", "C_cw", "x C_cw", "C_rs", "flow [L/s]"
    );
    let mut rows: Vec<(String, Params)> = vec![("(defaults)".to_string(), defaults.clone())];
    for (name, soften) in CONSTANTS {
        let mut p = defaults.clone();
        soften(&mut p, factor);
        rows.push((name.to_string(), p));
    }
    let mut all = defaults.clone();
    for (_, soften) in CONSTANTS {
        soften(&mut all, factor);
    }
    rows.push(("all eight".to_string(), all.clone()));
    let muscles = |p: &mut Params| {
        p.beta_max /= factor;
        p.beta_max_diaphragm /= factor;
    };
    let mut p = defaults.clone();
    muscles(&mut p);
    rows.push(("relaxed muscles (beta_max / f)".to_string(), p));
    muscles(&mut all);
    rows.push(("all eight and the muscles".to_string(), all));
    let mut c_default = f64::NAN;
    for (name, params) in rows {
        let config = Config {
            params: Some(params),
            ..base.clone()
        };
        let (dv, p_wall, flow) = step(config, p_ao, seconds)?;
        let c_cw = dv / p_wall;
        if c_default.is_nan() {
            c_default = c_cw;
        }
        println!(
            "{name:<34} {dv:>+10.4} {c_cw:>9.4} {:>9.2} {:>9.4} {flow:>+11.2e}",
            c_cw / c_default,
            dv / p_ao
        );
    }
    Ok(())
}
