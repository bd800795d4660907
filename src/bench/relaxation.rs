//! The relaxation curves of the passive chest wall and of the respiratory system: the static
//! pressure-volume curves of the model with every muscle relaxed, from residual volume to
//! total lung capacity, solved by the quasi-static mode's equilibrium at each volume
//! (`Torso::set_lung_volume`). These are the measurements the compliant-chest-wall work is
//! judged against (Rahn et al. 1946, Am J Physiol 146:161; Agostoni & Mead 1964, Handbook of
//! Physiology, Respiration I, ch. 13): the chest wall's compliance over the tidal range above
//! FRC, the volume at which it relaxes as a fraction of vital capacity, and its stiffening
//! towards residual volume and total lung capacity.
//!
//! The pressures: with the airway shut and the muscles relaxed the chest wall's recoil is
//! the pleural pressure relative to the body surface, P_cw = P_pl; the respiratory system's
//! is the alveolar pressure, P_rs = P_pl + P_L(V_L) (the lungs' recoil). Volumes are the
//! model's own: its rest lung volume is its FRC, its residual volume and total lung
//! capacity are FRC times the subject's ECSC ratios (`dynamics::pleural::capacity_ratios`),
//! where the pleural law's barriers stand.

use crate::dynamics::Params;
use crate::dynamics::pleural::capacity_ratios;
use crate::model::{Config, Drive, Quantity, Torso};
use crate::solver::Method;
use crate::{Error, Result};
use serde::Serialize;

/// Pressure of 1 cmH2O [Pa].
pub const CMH2O: f64 = 98.0665;

/// The tidal range above FRC over which the compliances are taken [L]: a quiet adult breath
/// (0.5 L; Agostoni & Mead 1964 take the chest wall's compliance over the volumes of quiet
/// breathing, where its curve is nearly straight).
pub const TIDAL_RANGE: f64 = 0.5;

/// One point of the curves.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Point {
    /// Lung volume [L].
    pub lung: f64,
    /// Chest wall's recoil, the pleural pressure relative to the body surface [Pa].
    pub chest_wall: f64,
    /// Respiratory system's recoil, the alveolar pressure with the airway shut [Pa].
    pub system: f64,
    /// Volume the rib cage has displaced from rest [L] (`Quantity::RibCageDisplaced`: the
    /// wall above the costal margin, as optoelectronic plethysmography splits it).
    pub rib_cage: f64,
    /// Volume the abdomen has displaced from rest [L] (`Quantity::AbdomenDisplaced`).
    pub abdomen: f64,
    /// Abdominal pressure [Pa], relative to its value at the rest (`Quantity::AbdominalPressure`).
    pub abdominal_pressure: f64,
}

/// The curves of one subject and posture, and the figures read off them.
#[derive(Clone, Debug, Serialize)]
pub struct Relaxation {
    /// The model's rest lung volume, its FRC [L].
    pub frc: f64,
    /// Residual volume [L] (FRC times the subject's ECSC RV/FRC).
    pub rv: f64,
    /// Total lung capacity [L] (FRC times the subject's ECSC TLC/FRC).
    pub tlc: f64,
    /// The points solved, by increasing volume.
    pub points: Vec<Point>,
    /// Volumes where no equilibrium could be solved, with the reason (the curve stops there).
    pub failed: Vec<(f64, String)>,
    /// Chest wall's compliance over FRC to FRC + [`TIDAL_RANGE`] [L/cmH2O]: the slope of a
    /// least-squares line through the points there.
    pub chest_wall_compliance: f64,
    /// Respiratory system's compliance over the same range [L/cmH2O].
    pub system_compliance: f64,
    /// The rib cage's share of the chest wall's compliance over the same range: the slope of
    /// its displaced volume against the pleural pressure [L/cmH2O] (the rib-cage compliance
    /// of Konno & Mead 1968 and Estenne, Yernault & De Troyer 1985, J Appl Physiol 59:1842:
    /// the two compartments' displaced volumes make up the lungs' volume change, so their
    /// compliances against the pleural pressure add up to the chest wall's, less the
    /// abdominal contents' compression).
    pub rib_cage_compliance: f64,
    /// The abdomen's share (the diaphragm-abdomen compliance of Estenne et al. 1985), the
    /// slope of its displaced volume against the pleural pressure [L/cmH2O].
    pub abdomen_compliance: f64,
    /// The share of the pleural pressure's change over the same range that the relaxed
    /// diaphragm carries: minus the slope of the transdiaphragmatic pressure (abdominal less
    /// pleural) against the pleural pressure. Relaxed, people's transdiaphragmatic pressure is
    /// zero at every lung volume (Agostoni & Rahn 1960, J Appl Physiol 15:1087, gastric and
    /// oesophageal balloons in relaxation manoeuvres): a share of 0.
    pub diaphragm_share: f64,
    /// The abdomen's compliance against its own pressure over the same range, the slope of
    /// its displaced volume against the abdominal pressure [L/cmH2O].
    pub abdominal_wall_compliance: f64,
    /// The chest wall's relaxation volume, where its recoil is zero, as a fraction of vital
    /// capacity above RV; `None` if the curve does not cross zero.
    pub chest_wall_relaxation: Option<f64>,
    /// The respiratory system's relaxation volume (the FRC of a relaxed system), as a fraction of
    /// vital capacity above RV.
    pub system_relaxation: Option<f64>,
    /// Chest wall's recoil at FRC [Pa] (the end-expiratory pleural pressure).
    pub pleural_at_frc: f64,
}

/// The relaxation curves of `config`'s subject and posture at `points` volumes spread evenly
/// from RV to TLC, solved outwards from FRC (each equilibrium warm-starts the next). The
/// configuration's solver, drive and airway settings are replaced: quasi-static, every
/// muscle relaxed, the airway shut at the body surface's pressure.
pub fn relaxation(config: &Config, points: usize) -> Result<Relaxation> {
    if points < 8 {
        return Err(Error::invalid(
            "points",
            points as f64,
            "at least 8 volumes from RV to TLC",
        ));
    }
    let c = relaxed(config);
    let mut torso = Torso::new(c.clone())?;
    let frc = torso.read(Quantity::LungVolume)?;
    let (rv_ratio, tlc_ratio) = capacity_ratios(&c.subject);
    let (rv, tlc) = (frc * rv_ratio, frc * tlc_ratio);
    let grid: Vec<f64> = (0..points)
        .map(|i| rv + (tlc - rv) * i as f64 / (points - 1) as f64)
        .collect();
    let mut solved = vec![frc_point(&mut torso, frc)?];
    let mut failed = Vec::new();
    // outwards from FRC on each side, stopping a side at its first failure
    for side in [true, false] {
        let mut t = Torso::new(c.clone())?;
        let volumes: Vec<f64> = if side {
            grid.iter().copied().filter(|&v| v > frc).collect()
        } else {
            grid.iter().rev().copied().filter(|&v| v < frc).collect()
        };
        for v in volumes {
            match at_volume(&mut t, v) {
                Ok(p) => solved.push(p),
                Err(e) => {
                    failed.push((v, e.to_string()));
                    break;
                }
            }
        }
    }
    // the tidal range, densely
    let mut t = Torso::new(c)?;
    for k in 1..=5 {
        let v = frc + TIDAL_RANGE * k as f64 / 5.0;
        if let Ok(p) = at_volume(&mut t, v) {
            solved.push(p);
        }
    }
    solved.sort_by(|a, b| a.lung.total_cmp(&b.lung));
    solved.dedup_by(|a, b| (a.lung - b.lung).abs() < 1e-9);
    let tidal: Vec<&Point> = solved
        .iter()
        .filter(|p| p.lung >= frc - 1e-9 && p.lung <= frc + TIDAL_RANGE + 1e-9)
        .collect();
    let slope = |f: &dyn Fn(&Point) -> f64| compliance(&tidal, f);
    let crossing = |f: &dyn Fn(&Point) -> f64| {
        solved.windows(2).find_map(|w| {
            let (a, b) = (f(&w[0]), f(&w[1]));
            (a <= 0.0 && b > 0.0).then(|| {
                let v = w[0].lung + (w[1].lung - w[0].lung) * (-a) / (b - a);
                (v - rv) / (tlc - rv)
            })
        })
    };
    Ok(Relaxation {
        frc,
        rv,
        tlc,
        chest_wall_compliance: slope(&|p| p.chest_wall),
        system_compliance: slope(&|p| p.system),
        rib_cage_compliance: partial(&tidal, &|p| p.rib_cage),
        abdomen_compliance: partial(&tidal, &|p| p.abdomen),
        diaphragm_share: -line_slope(&tidal, &|p| p.chest_wall, &|p| {
            p.abdominal_pressure - p.chest_wall
        }),
        abdominal_wall_compliance: line_slope(&tidal, &|p| p.abdominal_pressure, &|p| p.abdomen)
            * CMH2O,
        chest_wall_relaxation: crossing(&|p| p.chest_wall),
        system_relaxation: crossing(&|p| p.system),
        pleural_at_frc: solved
            .iter()
            .find(|p| (p.lung - frc).abs() < 1e-9)
            .map_or(f64::NAN, |p| p.chest_wall),
        points: solved,
        failed,
    })
}

/// The point at FRC, the model's rest.
fn frc_point(torso: &mut Torso, frc: f64) -> Result<Point> {
    at_volume(torso, frc)
}

/// The equilibrium holding lung volume `v` [L] and its pressures.
fn at_volume(torso: &mut Torso, v: f64) -> Result<Point> {
    torso.set_lung_volume(0.0, v)?;
    let chest_wall = torso.read(Quantity::PleuralPressure)?;
    let system = torso.read(Quantity::AlveolarPressure)?;
    let lung = torso.read(Quantity::LungVolume)?;
    let rib_cage = torso.read(Quantity::RibCageDisplaced)?;
    let abdomen = torso.read(Quantity::AbdomenDisplaced)?;
    let abdominal_pressure = torso.read(Quantity::AbdominalPressure)?;
    if !(chest_wall.is_finite() && system.is_finite() && lung.is_finite()) {
        // the reason: the same solve, asked through the reduced right-hand side
        let why = match torso.quasi_rate(0.0, v) {
            Err(e) => e.to_string(),
            Ok(_) => "the equilibrium's pressures are not finite".into(),
        };
        return Err(Error::Numerical {
            time: 0.0,
            reason: format!("no equilibrium holds the lungs at {v:.3} L: {why}"),
        });
    }
    Ok(Point {
        lung,
        chest_wall,
        system,
        rib_cage,
        abdomen,
        abdominal_pressure,
    })
}

/// The relaxed chest wall's compliance [L/cmH2O] over FRC to FRC + [`TIDAL_RANGE`] alone (six
/// equilibria: FRC and five volumes above it), as [`relaxation`] measures it.
pub fn tidal_chest_wall_compliance(config: &Config) -> Result<f64> {
    let points = tidal_points(config)?;
    let points: Vec<&Point> = points.iter().collect();
    Ok(compliance(&points, &|p| p.chest_wall))
}

/// The relaxed equilibria at FRC and five volumes evenly above it up to FRC +
/// [`TIDAL_RANGE`], the points the tidal figures are read from.
fn tidal_points(config: &Config) -> Result<Vec<Point>> {
    let mut torso = Torso::new(relaxed(config))?;
    let frc = torso.read(Quantity::LungVolume)?;
    let mut points = vec![frc_point(&mut torso, frc)?];
    for k in 1..=5 {
        points.push(at_volume(&mut torso, frc + TIDAL_RANGE * k as f64 / 5.0)?);
    }
    Ok(points)
}

/// `config` with the solver, drive and airway the curves are measured with: quasi-static,
/// every muscle relaxed (no drive and no tone: the relaxation curve is measured with the
/// subject's muscles relaxed, Rahn et al. 1946).
fn relaxed(config: &Config) -> Config {
    let mut c = config.clone();
    let mut params = config.model_params();
    params.abdominal_tone = 0.0;
    c.params = Some(params);
    c.solver.method = Method::QuasiStatic;
    c.drive = Drive {
        enabled: false,
        ..Drive::default()
    };
    c
}

/// The slope of the least-squares line of `y` against `x` over `points` (in their units).
fn line_slope(points: &[&Point], x: &dyn Fn(&Point) -> f64, y: &dyn Fn(&Point) -> f64) -> f64 {
    let n = points.len() as f64;
    let mx = points.iter().map(|p| x(p)).sum::<f64>() / n;
    let my = points.iter().map(|p| y(p)).sum::<f64>() / n;
    let sxy: f64 = points.iter().map(|p| (x(p) - mx) * (y(p) - my)).sum();
    let sxx: f64 = points.iter().map(|p| (x(p) - mx).powi(2)).sum();
    sxy / sxx
}

/// A compartment's compliance [L/cmH2O] over `points`: the slope of the volume `v` [L] reads
/// off each point against the pleural pressure.
fn partial(points: &[&Point], v: &dyn Fn(&Point) -> f64) -> f64 {
    // L per Pa, to L per cmH2O
    line_slope(points, &|p| p.chest_wall, v) * CMH2O
}

/// Compliance [L/cmH2O] over `points`: the slope of lung volume against the pressure `f` [Pa]
/// reads off each point.
fn compliance(points: &[&Point], f: &dyn Fn(&Point) -> f64) -> f64 {
    line_slope(points, f, &|p| p.lung) * CMH2O
}

/// One evaluation of [`fit_passive_wall`]: the factor tried and the compliance it gave.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct FitStep {
    /// Factor on the passive wall's stiffnesses ([`Params::scale_passive_wall`]).
    pub factor: f64,
    /// Relaxed chest wall's compliance over the tidal range [L/cmH2O].
    pub compliance: f64,
}

/// Fits the factor on the passive chest wall's hand-set constants
/// ([`Params::scale_passive_wall`], applied to `config`'s parameters or its posture's
/// defaults) so that the relaxed chest wall's compliance over the tidal range
/// ([`tidal_chest_wall_compliance`]) is `target` [L/cmH2O]: secant iterations on
/// log C against log factor (C is nearly a power of the factor), from 1 and 0.5, to 0.2 %
/// of the target. Returns the steps, the last the fit.
pub fn fit_passive_wall(config: &Config, target: f64) -> Result<Vec<FitStep>> {
    if !(target.is_finite() && target > 0.0) {
        return Err(Error::invalid("target compliance", target, "> 0 L/cmH2O"));
    }
    let base = config.params.clone().unwrap_or_else(|| {
        Params::unscaled_for_posture_and_law(config.subject.posture, config.muscle_law)
    });
    let eval = |factor: f64| -> Result<FitStep> {
        let mut c = config.clone();
        let mut p = base.clone();
        p.scale_passive_wall(factor);
        c.params = Some(p);
        Ok(FitStep {
            factor,
            compliance: tidal_chest_wall_compliance(&c)?,
        })
    };
    let mut steps = vec![eval(1.0)?, eval(0.5)?];
    for _ in 0..12 {
        let [a, b] = [steps[steps.len() - 2], steps[steps.len() - 1]];
        if (b.compliance / target - 1.0).abs() < 2e-3 {
            return Ok(steps);
        }
        let (la, lb) = (a.factor.ln(), b.factor.ln());
        let (ca, cb) = (a.compliance.ln(), b.compliance.ln());
        let slope = (cb - ca) / (lb - la);
        if !(slope.is_finite() && slope < 0.0) {
            return Err(Error::Numerical {
                time: 0.0,
                reason: format!(
                    "the chest wall's compliance does not fall as the passive wall stiffens \
                     (factor {:.4}: {:.4} L/cmH2O; factor {:.4}: {:.4} L/cmH2O)",
                    a.factor, a.compliance, b.factor, b.compliance
                ),
            });
        }
        // at most a factor 4 per step
        let next = lb + ((target.ln() - cb) / slope).clamp(-4f64.ln(), 4f64.ln());
        steps.push(eval(next.exp())?);
    }
    Err(Error::Numerical {
        time: 0.0,
        reason: format!(
            "the passive wall's fit did not reach {target} L/cmH2O in 14 evaluations (last: \
             factor {:.4}, {:.4} L/cmH2O)",
            steps[steps.len() - 1].factor,
            steps[steps.len() - 1].compliance
        ),
    })
}

/// The relaxed compartments' compliances of young seated adults, rib cage and
/// diaphragm-abdomen [L/cmH2O]: Estenne, Yernault & De Troyer 1985, J Appl Physiol 59:1842
/// (61 adults, weighted spirometer and magnetometers, relaxation; the abstract's means for the
/// 24-39-year-olds, 0.164 +- 0.041 and 0.032 +- 0.012; the default subject is 30). The target
/// of [`fit_compartments`].
pub const SEATED_COMPARTMENTS: [f64; 2] = [0.164, 0.032];

/// The relaxed rib cage's and abdomen's compliances [L/cmH2O] over FRC to FRC +
/// [`TIDAL_RANGE`] alone (six equilibria), as [`relaxation`] measures them: the slopes of
/// their displaced volumes against the pleural pressure.
pub fn tidal_compartments(config: &Config) -> Result<[f64; 2]> {
    let points = tidal_points(config)?;
    let points: Vec<&Point> = points.iter().collect();
    Ok([
        partial(&points, &|p| p.rib_cage),
        partial(&points, &|p| p.abdomen),
    ])
}

/// One evaluation of [`fit_compartments`]: the factors tried and the compliances they gave.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct CompartmentStep {
    /// Factor on the cartilage joints' stiffness ([`Params::scale_compartments`]).
    pub cartilage: f64,
    /// Factor on the abdominal wall's stiffness.
    pub abdominal_wall: f64,
    /// Relaxed rib cage's compliance over the tidal range [L/cmH2O].
    pub rib_cage: f64,
    /// Relaxed diaphragm-abdomen's compliance over the tidal range [L/cmH2O].
    pub abdomen: f64,
}

/// Fits the two factors of [`Params::scale_compartments`] (applied to `config`'s parameters
/// or its posture's and law's wall before the compartments' factors,
/// [`Params::before_compartments`]) so that the relaxed
/// rib cage's and abdomen's compliances over the tidal range ([`tidal_compartments`]) are
/// `target` [L/cmH2O] (rib cage, abdomen): Newton steps on the logarithms (each compliance
/// is nearly a power of each factor; the Jacobian by differences of 0.05 in the log, each
/// step at most a factor 4), to 0.5 % of both targets. With `config.params` unset the base is
/// the posture's own defaults, gravity preloaded. A step into a volume without equilibrium
/// ends the fit with that error (no backtracking). The two compartments are coupled (a
/// stiffer abdominal wall also stiffens the rib cage through the diaphragm and the abdominal
/// pressure on the lower ribs), hence the full Jacobian. Returns the evaluations at the
/// iterates, the last the fit.
pub fn fit_compartments(config: &Config, target: [f64; 2]) -> Result<Vec<CompartmentStep>> {
    if !target.iter().all(|t| t.is_finite() && *t > 0.0) {
        return Err(Error::invalid(
            "target compartments' compliances",
            format!("{target:?}"),
            "both > 0 L/cmH2O",
        ));
    }
    let base = config
        .params
        .clone()
        .unwrap_or_else(|| Params::before_compartments(config.subject.posture, config.muscle_law));
    let eval = |x: [f64; 2]| -> Result<[f64; 2]> {
        let mut c = config.clone();
        let mut p = base.clone();
        p.scale_compartments(x[0].exp(), x[1].exp());
        c.params = Some(p);
        let y = tidal_compartments(&c)?;
        if !y.iter().all(|v| v.is_finite() && *v > 0.0) {
            return Err(Error::Numerical {
                time: 0.0,
                reason: format!(
                    "the compartments' compliances are not positive at factors {:.4} and \
                     {:.4}: rib cage {:.4}, abdomen {:.4} L/cmH2O",
                    x[0].exp(),
                    x[1].exp(),
                    y[0],
                    y[1]
                ),
            });
        }
        Ok([y[0].ln(), y[1].ln()])
    };
    let goal = [target[0].ln(), target[1].ln()];
    let step = |x: [f64; 2], y: [f64; 2]| CompartmentStep {
        cartilage: x[0].exp(),
        abdominal_wall: x[1].exp(),
        rib_cage: y[0].exp(),
        abdomen: y[1].exp(),
    };
    let mut x = [0.0, 0.0];
    let mut y = eval(x)?;
    let mut steps = vec![step(x, y)];
    const H: f64 = 0.05;
    // within 0.5 % of both targets
    let reached = |y: [f64; 2]| (0..2).all(|i| (y[i] - goal[i]).exp_m1().abs() < 5e-3);
    for _ in 0..10 {
        if reached(y) {
            return Ok(steps);
        }
        let y0 = eval([x[0] + H, x[1]])?;
        let y1 = eval([x[0], x[1] + H])?;
        // J[i][j] = d ln C_i / d ln factor_j
        let j = [
            [(y0[0] - y[0]) / H, (y1[0] - y[0]) / H],
            [(y0[1] - y[1]) / H, (y1[1] - y[1]) / H],
        ];
        let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
        if !(det.is_finite() && det.abs() > 1e-9) {
            return Err(Error::Numerical {
                time: 0.0,
                reason: format!(
                    "the compartments' compliances do not depend on the two factors apart at \
                     cartilage {:.4}, abdominal wall {:.4} (Jacobian {j:?})",
                    x[0].exp(),
                    x[1].exp()
                ),
            });
        }
        let r = [goal[0] - y[0], goal[1] - y[1]];
        let dx = [
            (j[1][1] * r[0] - j[0][1] * r[1]) / det,
            (j[0][0] * r[1] - j[1][0] * r[0]) / det,
        ];
        let limit = 4f64.ln();
        x = [
            x[0] + dx[0].clamp(-limit, limit),
            x[1] + dx[1].clamp(-limit, limit),
        ];
        y = eval(x)?;
        steps.push(step(x, y));
    }
    if reached(y) {
        return Ok(steps);
    }
    let last = steps[steps.len() - 1];
    Err(Error::Numerical {
        time: 0.0,
        reason: format!(
            "the compartments' fit did not reach rib cage {} and abdomen {} L/cmH2O in 10 \
             Newton steps (last: cartilage {:.4}, abdominal wall {:.4}: {:.4} and {:.4})",
            target[0], target[1], last.cartilage, last.abdominal_wall, last.rib_cage, last.abdomen
        ),
    })
}

/// The relaxed respiratory system's rest, its FRC under the loads: the lung volume [L] at
/// which the alveolar pressure of the relaxed equilibrium, with the airway shut, is zero (so
/// that with the airway open no air flows), found by secant steps from the model's rest
/// volume to 0.01 Pa. Under [`crate::dynamics::GravityLoads::Preloaded`] that is the rest
/// volume itself (the preloads make the rest the equilibrium); with gravity acting it is
/// where the loads of the posture move it. Returns the volume and the pleural pressure
/// there [Pa]. The rest is an equilibrium; whether it is stable is not checked when the
/// first solve needs no new factorisation (the model already at it, as the preloaded rest
/// and the standing reference under gravity acting are).
pub fn relaxed_frc(config: &Config) -> Result<(f64, f64)> {
    let c = relaxed(config);
    let mut torso = Torso::new(c)?;
    let rest = torso.read(Quantity::LungVolume)?;
    let first = at_volume(&mut torso, rest)?;
    if first.system.abs() < 0.01 {
        return Ok((first.lung, first.chest_wall));
    }
    // a first step with the adult's respiratory-system compliance, 0.1 L/cmH2O, at most 0.5 L
    let step = (-first.system / CMH2O * 0.1).clamp(-0.5, 0.5);
    let mut a = first;
    let mut b = at_volume(&mut torso, rest + step)?;
    for _ in 0..30 {
        if b.system.abs() < 0.01 {
            return Ok((b.lung, b.chest_wall));
        }
        let slope = (b.system - a.system) / (b.lung - a.lung);
        if !(slope.is_finite() && slope > 0.0) {
            return Err(Error::Numerical {
                time: 0.0,
                reason: format!(
                    "the relaxed system's recoil does not rise with volume between {:.4} L \
                     ({:.2} Pa) and {:.4} L ({:.2} Pa)",
                    a.lung, a.system, b.lung, b.system
                ),
            });
        }
        let next = b.lung - (b.system / slope).clamp(-0.5, 0.5);
        a = b;
        b = at_volume(&mut torso, next)?;
    }
    Err(Error::Numerical {
        time: 0.0,
        reason: format!(
            "the relaxed rest was not found in 30 secant steps (last {:.4} L, {:.3} Pa)",
            b.lung, b.system
        ),
    })
}
