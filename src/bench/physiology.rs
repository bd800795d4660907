//! The physiological figures the chest wall is judged by (issue 35), measured on the default
//! subject by the experiments a respiratory physiologist would run, each with its cited range:
//!
//! - respiratory-system compliance from a 10 cmH2O step of the airway-opening pressure on the
//!   relaxed system, and the pleural pressure swing of quiet breathing;
//! - the compartments' shares of quiet tidal volume, upright and supine (optoelectronic
//!   plethysmography's split at the costal margin, the library's own displaced volumes);
//! - diaphragm excursion per litre in quiet breathing, and the cranio-caudal excursion of a
//!   point of the posterior right dome (where M-mode ultrasound aims) in a full inspiratory
//!   effort;
//! - the volume a full inspiratory effort with the airway open adds to FRC;
//! - the maximal inspiratory mouth pressure against an occluded airway;
//! - the paralysed hemidiaphragm's motion and its side's share of tidal volume.
//!
//! All but one are measured through the FMU's instance ([`Instance`], the object every
//! `fmi2*` call of the shared library acts on) with its own inputs, parameters and outputs,
//! the maximal inspiratory pressure with its `airway.occluded` input and `pressure.mouth`
//! output. The exception says so in its [`Figure::through`]: the dome point of the M-mode
//! excursion is no FMU output (it is read off the facade's state).
//!
//! Nothing here prints; `torso bench physiology` (`src/cli/bench_physiology.rs`) formats the
//! figures, and `tests/physiology_figures.rs` asserts each cited bound.

use super::relaxation::CMH2O;
use crate::anatomy::{MuscleGroup, Posture, Sex, Subject};
use crate::dynamics::GravityLoads;
use crate::dynamics::muscle::MuscleLaw;
use crate::dynamics::pleural::capacity_ratios;
use crate::dynamics::{Data, Layout, kinematics};
use crate::fmi::instance::Instance;
use crate::fmi::variables::ScalarType;
use crate::fmi::{FMI2, Status, table};
use crate::model::run::{Frame, summarise};
use crate::model::{Config, Drive, Quantity, Torso};
use crate::{Error, Result};
use serde::Serialize;

/// The inspiratory muscle groups a maximal inspiratory effort activates: the diaphragm, the
/// external intercostals and the scalenes (the model's internal intercostals are its
/// expiratory group; De Troyer & Estenne 1988, J Appl Physiol 65:2319, on the inspiratory
/// action of the diaphragm, external intercostals and scalenes), and the sternocleidomastoids,
/// the accessory inspiratory muscles that maximal efforts recruit: silent in quiet breathing,
/// active as the lung volume approaches total lung capacity and in maximal static efforts
/// (Raper, Thompson, Shapiro & Patterson 1966, J Appl Physiol 21:497); in static inspiratory
/// ramps their activity rises with the pressure from 20 to 100 % of the maximal inspiratory
/// pressure (Hudson, Gandevia & Butler 2007, J Physiol 584:261).
pub const INSPIRATORY: [MuscleGroup; 4] = [
    MuscleGroup::Diaphragm,
    MuscleGroup::ExternalIntercostals,
    MuscleGroup::Scalenes,
    MuscleGroup::Sternocleidomastoids,
];

/// The airway-opening pressure step of the compliance measurement [cmH2O] (issue 35: a 10
/// cmH2O step on the relaxed system, as a ventilator's inspiratory hold gives).
pub const PRESSURE_STEP: f64 = 10.0;

/// Respiratory-system compliance of an adult [L/cmH2O]: about 0.1 (0.08-0.12, the range issue
/// 35 states; Agostoni & Mead 1964, Handbook of Physiology, Respiration I, ch. 13: the lungs'
/// and the chest wall's 0.2 L/cmH2O each in series).
pub const SYSTEM_COMPLIANCE: (f64, f64) = (0.08, 0.12);

/// Pleural pressure swing of quiet breathing [cmH2O]: 1.5-4 (issue 35's range; West & Luks,
/// Respiratory Physiology: The Essentials, 10th ed. 2016, ch. 7: from about -5 at FRC to
/// about -7.5 cmH2O at the end of a quiet inspiration).
pub const PLEURAL_SWING: (f64, f64) = (1.5, 4.0);

/// Upright rib-cage share of quiet tidal volume: at least half (upright quiet breathing is
/// rib-cage dominant; Verschakelen & Demedts 1995, Am J Respir Crit Care Med 151:399).
pub const UPRIGHT_RIB_CAGE_SHARE: (f64, f64) = (0.5, 1.0);

/// Supine abdominal share of quiet tidal volume: 63 +- 11 % (mean +- SD; Aliverti et al.
/// 2001, J Appl Physiol 90:1821, optoelectronic plethysmography, split at the costal margin).
pub const SUPINE_ABDOMINAL_SHARE: (f64, f64) = (0.52, 0.74);

/// Diaphragm excursion per litre of quiet tidal volume [cm/L]: 1.66 +- 0.48 (Houston et al.
/// 1994, Clin Radiol 49:95; the range issue 35 states).
pub const EXCURSION_PER_LITRE: (f64, f64) = (1.18, 2.14);

/// M-mode excursion of the posterior right hemidiaphragm in a deep breath, men [cm]: the lower
/// limit of normal 4.7 (Boussuges et al. 2009, Chest 135:391: 7.0 +- 1.1 cm in men).
pub const DEEP_EXCURSION_MEN: (f64, f64) = (4.7, f64::INFINITY);

/// The difference between the excursions of a more posterior and a more anterior third of the
/// dome in a deep breath [cm]: positive. In 10 healthy volunteers breathing near their vital
/// capacity, the excursion increased from anterior to middle to posterior points of sagittal
/// planes (P < .05-.001, paired t test; Gierada et al. 1995, Radiology 194:879, fast
/// gradient-recalled-echo MR imaging); the abstract gives no regional magnitudes (only the
/// domes' absolute excursion, 4.4 cm right and 4.2 cm left), so only the sign is the bound.
pub const REGIONAL_GRADIENT: (f64, f64) = (0.0, f64::INFINITY);

/// The rotations of the right ribs 3 and 7 from FRC to TLC, pump-handle (about the
/// transverse axis) and bucket-handle (about the antero-posterior axis) [deg]: 11 and 13 for
/// rib 3, 7 and 10 for rib 7 (Wilson, Rehder, Krayer, Hoffman, Whitney & Rodarte 1987, J Appl
/// Physiol 62:1872: CT of two relaxed supine men at FRC and at TLC held with the glottis
/// closed; means without a spread, as the project's physiology reference gives them). A weak
/// bound, two subjects lying down against the bench's standing subject: the full inspiratory
/// activation adds less than the inspiratory capacity, so each rotation is bounded above by
/// its mean at TLC, and below by 0 (an inspiratory turn).
pub const RIB_ROTATION_TO_TLC: [(u32, f64, f64); 2] = [(3, 11.0, 13.0), (7, 7.0, 10.0)];

/// Volume a full inspiratory effort with the airway open adds to FRC, default subject [L]:
/// 2.9-4.3 (issue 35's range for the default man's inspiratory capacity; ECSC 1993, Quanjer
/// et al., Eur Respir J 6 Suppl 16:5, TLC less FRC).
pub const INSPIRATORY_CAPACITY: (f64, f64) = (2.9, 4.3);

/// The transdiaphragmatic pressure of a maximal sniff [cmH2O], lower bound: in six healthy
/// adults it fell with lung volume, linearly from 163 (SD 18) at RV up to 85 % of TLC, and to
/// 68 (SD 15) at 95 % of TLC, below that line (Wanke, Schenz, Zwick, Popp, Ritschka & Flicker
/// 1990, Thorax 45:352). It falls as the volume rises, and a sniff from FRC starts below 95 %
/// of TLC, so a healthy one exceeds 68 - 2 x 15 = 38.
pub const SNIFF_TRANSDIAPHRAGMATIC: (f64, f64) = (38.0, f64::INFINITY);

/// The paralysed hemidiaphragm's side takes under 40 % of tidal volume (issue 35).
pub const PARALYSED_SIDE_SHARE: (f64, f64) = (0.0, 0.4);

/// Maximal inspiratory mouth pressure, magnitude [cmH2O], predicted for the subject's sex,
/// age, mass and stature by the Baltimore Longitudinal Study of Aging's healthy adults
/// (Harik-Khan, Wise & Fozard 1998, Am J Respir Crit Care Med 158:1459, doi
/// 10.1164/ajrccm.158.5.9712006; docs/respiratory_muscles.md, row E7): men 126 - 1.028 age +
/// 0.343 mass [kg], women 171 - 0.694 age + 0.861 mass - 0.743 stature [cm]. The abstract read
/// does not state the lung volume of the manoeuvre; it is taken as RV, where the ATS/ERS
/// statement on respiratory muscle testing (2002, Am J Respir Crit Care Med 166:518) has
/// inspiratory efforts made.
pub fn pimax_predicted(subject: &Subject) -> f64 {
    let (age, mass, cm) = (subject.age, subject.mass, 100.0 * subject.stature);
    match subject.sex {
        Sex::Male => 126.0 - 1.028 * age + 0.343 * mass,
        Sex::Female => 171.0 - 0.694 * age + 0.861 * mass - 0.743 * cm,
    }
}

/// The reference range of the maximal inspiratory mouth pressure, magnitude [cmH2O]: the
/// prediction of [`pimax_predicted`] +- 1.96 standard errors of its estimate, 22.4 cmH2O in
/// men and 18.5 in women (Harik-Khan, Wise & Fozard 1998), the interval that holds 95 % of
/// healthy adults.
pub fn pimax_range(subject: &Subject) -> (f64, f64) {
    let see = match subject.sex {
        Sex::Male => 22.4,
        Sex::Female => 18.5,
    };
    let p = pimax_predicted(subject);
    (p - 1.96 * see, p + 1.96 * see)
}

/// One measured figure.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Figure {
    /// What was measured.
    pub name: String,
    /// The measured value, in `unit`.
    pub value: f64,
    /// Unit of `value` and `range`.
    pub unit: &'static str,
    /// The cited range (inclusive; an open end is infinite, written `null` in JSON).
    pub range: (f64, f64),
    /// Whether the measured value lies within the cited range.
    pub met: bool,
    /// Where the range comes from.
    pub source: &'static str,
    /// How it was measured: through the FMU's instance, or through the facade and why.
    pub through: &'static str,
}

/// Through the FMU's instance.
const FMU: &str = "FMU";

/// An FMU instance stepped from Rust.
struct Fmu {
    inst: Instance,
    t: f64,
}

fn vr(name: &str) -> Result<(u32, ScalarType)> {
    table()
        .by_name(name)
        .map(|v| (v.vr, v.ty))
        .ok_or_else(|| Error::State(format!("no FMI variable {name}")))
}

fn check(status: Status, what: &str, inst: &Instance) -> Result<()> {
    if status == Status::Ok {
        Ok(())
    } else {
        Err(Error::State(format!(
            "FMU instance at t = {} s: {what} returned {status:?}",
            inst.time()
        )))
    }
}

impl Fmu {
    /// An instance at its start values but for `parameters` (by FMI name; integers and
    /// booleans as reals), initialised.
    fn new(parameters: &[(&str, f64)]) -> Result<Fmu> {
        let mut inst = Instance::new(&FMI2, "physiology", None, None, false);
        let s = inst.setup_experiment("fmi2SetupExperiment", None, 0.0, None);
        check(s, "fmi2SetupExperiment", &inst)?;
        let s = inst.enter_initialization_mode();
        check(s, "fmi2EnterInitializationMode", &inst)?;
        let mut fmu = Fmu { inst, t: 0.0 };
        for &(name, value) in parameters {
            fmu.set(name, value)?;
        }
        let s = fmu
            .inst
            .exit_initialization_mode("fmi2ExitInitializationMode");
        check(s, "fmi2ExitInitializationMode", &fmu.inst)?;
        Ok(fmu)
    }

    /// Sets one variable by FMI name.
    fn set(&mut self, name: &str, value: f64) -> Result<()> {
        let (v, ty) = vr(name)?;
        let s = match ty {
            ScalarType::Real => self.inst.set_real("fmi2SetReal", &[v], &[value]),
            ScalarType::Integer => self
                .inst
                .set_integer("fmi2SetInteger", &[v], &[value as i32]),
            ScalarType::Boolean => {
                self.inst
                    .set_boolean("fmi2SetBoolean", &[v], &[i32::from(value != 0.0)])
            }
            ScalarType::String => {
                return Err(Error::State(format!("{name} is a string variable")));
            }
        };
        check(s, &format!("setting {name} to {value}"), &self.inst)
    }

    /// Reads real outputs by FMI name.
    fn get(&mut self, names: &[&str]) -> Result<Vec<f64>> {
        let vrs = names
            .iter()
            .map(|n| vr(n).map(|v| v.0))
            .collect::<Result<Vec<u32>>>()?;
        let mut out = vec![0.0; vrs.len()];
        let s = self.inst.get_real("fmi2GetReal", &vrs, &mut out);
        check(s, "fmi2GetReal", &self.inst)?;
        Ok(out)
    }

    /// One communication step of `h` seconds.
    fn step(&mut self, h: f64) -> Result<()> {
        let s = self.inst.do_step("fmi2DoStep", self.t, h);
        check(s, "fmi2DoStep", &self.inst)?;
        self.t += h;
        Ok(())
    }
}

/// The laws an experiment runs under: the muscle law (the FMU's `muscle_law`), how gravity
/// loads the model (`gravity_loads`) and whether the posture's tone is applied
/// (`postural_tone`). A muscle law alone means gravity preloaded and the tone on, the
/// defaults.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct Laws {
    /// The muscle law.
    pub muscle: MuscleLaw,
    /// How gravity loads the model.
    pub gravity_loads: GravityLoads,
    /// Whether the posture's tonic activity is applied ([`Config::postural_tone`]).
    pub postural_tone: bool,
}

impl From<MuscleLaw> for Laws {
    fn from(muscle: MuscleLaw) -> Self {
        Laws {
            muscle,
            gravity_loads: GravityLoads::default(),
            postural_tone: true,
        }
    }
}

impl Laws {
    /// The FMU's parameters that select these laws.
    fn parameters(self) -> [(&'static str, f64); 3] {
        [
            ("muscle_law", f64::from(self.muscle.code())),
            ("gravity_loads", f64::from(self.gravity_loads.code())),
            (
                "postural_tone",
                f64::from(crate::model::postural_tone_code(self.postural_tone)),
            ),
        ]
    }
}

/// The FMU's parameters for `posture` at level of detail `lod` under `laws`, the drive off.
fn relaxed(posture: Posture, lod: u32, laws: Laws) -> Vec<(&'static str, f64)> {
    let mut p = vec![
        ("posture", f64::from(posture.code())),
        ("scene.level_of_detail", f64::from(lod)),
        ("drive.enabled", 0.0),
    ];
    p.extend(laws.parameters());
    p
}

/// Steps `fmu` by `h` until `duration` has passed, then until the lung volume changes by less
/// than `tolerance` [L] over a second (at most `limit` seconds more), and returns the lung
/// volume.
fn settle(fmu: &mut Fmu, duration: f64, tolerance: f64, limit: f64) -> Result<f64> {
    let h = 0.05;
    let mut history = Vec::new();
    let t0 = fmu.t;
    loop {
        fmu.step(h)?;
        let v = fmu.get(&["volume.lung"])?[0];
        history.push(v);
        let elapsed = fmu.t - t0;
        if elapsed >= duration && history.len() > 20 {
            let second_ago = history[history.len() - 21];
            if (v - second_ago).abs() < tolerance {
                return Ok(v);
            }
        }
        if elapsed > duration + limit {
            return Err(Error::Numerical {
                time: fmu.t,
                reason: format!(
                    "the lung volume did not settle within {:.1} s (last {v:.4} L)",
                    duration + limit
                ),
            });
        }
    }
}

/// The response of the relaxed system to the airway-opening pressure step.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct PressureStep {
    /// Lung volume at rest, airway open [L] (the relaxed system's FRC).
    pub rest: f64,
    /// Lung volume settled under the step [L].
    pub held: f64,
    /// Respiratory-system compliance, (held - rest) / step [L/cmH2O].
    pub compliance: f64,
}

/// The respiratory-system compliance of the relaxed default subject in `posture`: the drive
/// off, the airway-opening pressure stepped from 0 to [`PRESSURE_STEP`] and the lung volume
/// left to settle, through the FMU.
pub fn pressure_step(posture: Posture, lod: u32, law: impl Into<Laws>) -> Result<PressureStep> {
    let mut fmu = Fmu::new(&relaxed(posture, lod, law.into()))?;
    let rest = fmu.get(&["volume.lung"])?[0];
    fmu.set("pressure.airway_opening", PRESSURE_STEP * CMH2O)?;
    let held = settle(&mut fmu, 3.0, 1e-4, 20.0)?;
    Ok(PressureStep {
        rest,
        held,
        compliance: (held - rest) / PRESSURE_STEP,
    })
}

/// Quiet breathing's figures, over two breaths after a settling one.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct QuietBreath {
    /// Tidal volume, peak to trough [L].
    pub tidal_volume: f64,
    /// Pleural pressure swing, peak to trough [cmH2O].
    pub pleural_swing: f64,
    /// Rib-cage share of the displaced volume, as [`crate::model::run::BreathSummary`]
    /// computes it (rib-cage swing over the sum of the rib-cage and abdominal swings).
    pub rib_cage_share: f64,
    /// Diaphragm dome's excursion per litre of tidal volume [cm/L].
    pub excursion_per_litre: f64,
    /// The left and right hemidiaphragms' displacements (cranial positive) from the end of
    /// expiration to the end of inspiration [cm].
    pub hemidiaphragm_motion: [f64; 2],
    /// The left lung's share of the tidal volume, the left lung's volume change from the end
    /// of expiration to the end of inspiration over the whole lungs'.
    pub left_share: f64,
    /// Correlation over the analysed breaths of the left hemidiaphragm's cranial displacement
    /// with the lung volume (positive: it rises as the lungs fill, the paralysed side's
    /// paradox; negative: it descends with them).
    pub left_correlation: f64,
}

/// Pearson correlation of two series.
fn correlation(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len() as f64;
    let (ma, mb) = (a.iter().sum::<f64>() / n, b.iter().sum::<f64>() / n);
    let (mut sab, mut saa, mut sbb) = (0.0, 0.0, 0.0);
    for (x, y) in a.iter().zip(b) {
        sab += (x - ma) * (y - mb);
        saa += (x - ma).powi(2);
        sbb += (y - mb).powi(2);
    }
    sab / (saa * sbb).sqrt()
}

/// Quiet breathing (the quiet drive for `law`, [`Drive::quiet_for`]: calibrated under the
/// thesis's law, the FMU's start drive; at cited fractions of maximum under the hill law) of the default subject in `posture` with the left
/// hemidiaphragm's gain `left_diaphragm_gain` (1 healthy, 0 paralysed; the FMU's
/// `gain.diaphragm.left`), through the FMU, sampled at 28 Hz.
pub fn quiet_breath(
    posture: Posture,
    lod: u32,
    law: impl Into<Laws>,
    left_diaphragm_gain: f64,
) -> Result<QuietBreath> {
    let laws = law.into();
    let drive = Drive::quiet_for(laws.muscle);
    let mut params = vec![
        ("posture", f64::from(posture.code())),
        ("scene.level_of_detail", f64::from(lod)),
        ("gain.diaphragm.left", left_diaphragm_gain),
        ("drive.ribs.amplitude", drive.ribs.amplitude),
        ("drive.diaphragm.amplitude", drive.diaphragm.amplitude),
        ("drive.abdominals.amplitude", drive.abdominals.amplitude),
    ];
    params.extend(laws.parameters());
    let mut fmu = Fmu::new(&params)?;
    let period = 1.0 / drive.frequency;
    let rate = 28.0;
    let names = [
        "volume.lung",
        "volume.abdomen",
        "volume.rib_cage_displaced",
        "volume.abdomen_displaced",
        "pressure.abdomen",
        "diaphragm.displacement",
        "pressure.pleural",
        "diaphragm.displacement.right",
        "diaphragm.displacement.left",
        "volume.lung.left",
    ];
    let mut frames = Vec::new();
    let mut extra = Vec::new();
    let n = (3.0 * period * rate).round() as usize;
    for k in 0..=n {
        if k > 0 {
            fmu.step(1.0 / rate)?;
        }
        let v = fmu.get(&names)?;
        frames.push(Frame {
            time: fmu.t,
            lung: v[0],
            abdomen: v[1],
            rib_cage_displaced: v[2],
            abdomen_displaced: v[3],
            pressure: v[4],
            diaphragm: v[5],
            ..Frame::default()
        });
        extra.push((fmu.t, v[6], v[7], v[8], v[9]));
    }
    let s = summarise(&frames, period);
    let sel: Vec<usize> = (0..frames.len())
        .filter(|&i| frames[i].time >= period - 1e-9)
        .collect();
    let pleural: Vec<f64> = sel.iter().map(|&i| extra[i].1).collect();
    let (lo, hi) = pleural
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
            (lo.min(*p), hi.max(*p))
        });
    // the end of expiration and of inspiration: the smallest and largest lung volumes
    let by_lung = |a: &&usize, b: &&usize| frames[**a].lung.total_cmp(&frames[**b].lung);
    let trough = *sel.iter().min_by(by_lung).expect("analysed frames");
    let peak = *sel.iter().max_by(by_lung).expect("analysed frames");
    let lungs: Vec<f64> = sel.iter().map(|&i| frames[i].lung).collect();
    let left: Vec<f64> = sel.iter().map(|&i| extra[i].3).collect();
    Ok(QuietBreath {
        tidal_volume: s.tidal_volume,
        pleural_swing: (hi - lo) / CMH2O,
        rib_cage_share: s.rib_cage_share,
        excursion_per_litre: 100.0 * s.dome_excursion / s.tidal_volume,
        hemidiaphragm_motion: [
            100.0 * (extra[peak].3 - extra[trough].3),
            100.0 * (extra[peak].2 - extra[trough].2),
        ],
        left_share: (extra[peak].4 - extra[trough].4) / (frames[peak].lung - frames[trough].lung),
        left_correlation: correlation(&left, &lungs),
    })
}

/// A sniff's inspiratory activation rises and falls over this time [s] each way: a sniff is a
/// short, sharp voluntary inspiration of about 0.5 s (ATS/ERS statement on respiratory muscle
/// testing 2002, section 2).
pub const SNIFF_HALF: f64 = 0.25;

/// The hemidiaphragms' motion in a sniff.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Sniff {
    /// Lung volume inspired at the sniff's peak [L].
    pub inspired: f64,
    /// The left and right hemidiaphragms' displacements (cranial positive) from the start to
    /// the sniff's largest lung volume [cm].
    pub hemidiaphragm_motion: [f64; 2],
    /// The largest transdiaphragmatic pressure of the sniff, `pressure.abdomen` less
    /// `pressure.pleural` [cmH2O].
    pub transdiaphragmatic: f64,
}

/// A sniff of the default subject in `posture` with the left hemidiaphragm's gain
/// `left_diaphragm_gain` (the FMU's `gain.diaphragm.left`): the drive off, the
/// [`INSPIRATORY`] groups' activation inputs raised from 0 to 1 and back to 0 over
/// [`SNIFF_HALF`] each way, the airway open, through the FMU sampled every 10 ms.
pub fn sniff(
    posture: Posture,
    lod: u32,
    law: impl Into<Laws>,
    left_diaphragm_gain: f64,
) -> Result<Sniff> {
    let mut params = relaxed(posture, lod, law.into());
    params.push(("gain.diaphragm.left", left_diaphragm_gain));
    let mut fmu = Fmu::new(&params)?;
    let names = [
        "volume.lung",
        "diaphragm.displacement.left",
        "diaphragm.displacement.right",
        "pressure.abdomen",
        "pressure.pleural",
    ];
    let start = fmu.get(&names)?;
    let mut peak = start.clone();
    let mut transdiaphragmatic = (start[3] - start[4]) / CMH2O;
    let h = 0.01;
    while fmu.t < 2.0 * SNIFF_HALF + 0.25 {
        let t = fmu.t + h;
        let a = (1.0 - (t - SNIFF_HALF).abs() / SNIFF_HALF).max(0.0);
        for g in INSPIRATORY {
            fmu.set(&format!("activation.{}", g.name()), a)?;
        }
        fmu.step(h)?;
        let v = fmu.get(&names)?;
        transdiaphragmatic = transdiaphragmatic.max((v[3] - v[4]) / CMH2O);
        if v[0] > peak[0] {
            peak = v;
        }
    }
    Ok(Sniff {
        inspired: peak[0] - start[0],
        hemidiaphragm_motion: [100.0 * (peak[1] - start[1]), 100.0 * (peak[2] - start[2])],
        transdiaphragmatic,
    })
}

/// A full inspiratory effort with the airway open.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FullInspiration {
    /// Lung volume at rest [L].
    pub rest: f64,
    /// Lung volume settled under full inspiratory activation [L].
    pub inspired: f64,
    /// The volume added, inspired - rest [L] (through the FMU).
    pub added: f64,
    /// Caudal excursion of the posterior right dome along the M-mode line, rest to full
    /// inspiration [cm] (through the facade): the fall of the place where the fixed line
    /// ([`FullInspiration::m_mode_line`]) crosses the dome's upper surface, whichever tissue is
    /// on the line at each instant, as an M-mode trace follows the surface's echo along a
    /// fixed beam. The line is cranio-caudal (issue 35's definition); Boussuges et al. 2009
    /// aim the beam perpendicular to the posterior third, which there is about 30 degrees off
    /// horizontal at level 1, so a beam along its normal would read a different figure.
    pub m_mode_excursion: f64,
    /// Caudal excursion of the material point of the dome that the M-mode line crosses at
    /// rest, along the cranio-caudal axis [cm] (through the facade): the same place followed
    /// with the tissue rather than with the beam.
    pub posterior_point_excursion: f64,
    /// Caudal excursions of the right dome's surface along cranio-caudal lines through the
    /// middles of its posterior, middle and anterior thirds, half its right half-width from
    /// the midline, rest to full inspiration [cm] (through the facade; the posterior one is
    /// [`FullInspiration::m_mode_excursion`]): the three points of a sagittal plane at which
    /// Gierada et al. 1995 measured the regional excursion. `None` when a line misses the
    /// dome at rest or at full inspiration.
    pub regional_excursion: Option<[f64; 3]>,
    /// Where that line stands, (x, z) [m] (x anterior, z right).
    pub m_mode_line: [f64; 2],
    /// Caudal displacement of the dome as a whole (its swept volume over its area, the FMU's
    /// `diaphragm.displacement`), rest to full inspiration [cm] (through the facade).
    pub dome_excursion: f64,
    /// Each right rib's rotation about its rib-neck axis, rest to full inspiration, split
    /// into its pump-handle (about the transverse axis) and bucket-handle (about the
    /// antero-posterior axis) parts [deg], ribs 1-12 (through the facade): the rotation
    /// (positive inspiratory, the axis's orientation) times the magnitudes of the axis's
    /// transverse and antero-posterior components, as Wilson et al. 1987 split the ribs'
    /// motion; an expiratory turn is negative.
    pub rib_rotation: Vec<(f64, f64)>,
}

/// Time over which the inspiratory activations rise from 0 to 1 [s]: a deep inspiration to
/// TLC takes 1-2 s; a ramp also keeps the inertial dynamics off the physiological bounds.
pub const EFFORT_RAMP: f64 = 1.0;

/// The activation of the inspiratory groups at `t` seconds into the effort.
fn effort(t: f64) -> f64 {
    (t / EFFORT_RAMP).clamp(0.0, 1.0)
}

/// The M-mode line: a cranio-caudal line through the posterior third of the right
/// hemidiaphragm (Boussuges et al. 2009 aim the beam perpendicular to the posterior third of
/// the right hemidiaphragm), at the middle of that region: a sixth of the dome's
/// antero-posterior extent from its back, half its right half-width from the midline. Returns
/// its (x, z) [m] (x anterior, z right), from the dome's rest vertices.
fn m_mode_line(torso: &Torso) -> (f64, f64) {
    right_dome_line(torso, 1.0 / 6.0)
}

/// The cranio-caudal line through the right dome at the fraction `from_back` of its
/// antero-posterior extent from its back, half its right half-width from the midline: (x, z)
/// [m], from the dome's rest vertices.
fn right_dome_line(torso: &Torso, from_back: f64) -> (f64, f64) {
    let a = &torso.compiled().anatomy;
    let ab = &a.abdomen;
    let (mut xmin, mut xmax, mut zmax) = (f64::INFINITY, f64::NEG_INFINITY, 0.0f64);
    for (t, _) in ab.triangles.iter().zip(&ab.dome).filter(|(_, d)| **d) {
        for &v in t {
            let p = a.anchors[ab.anchor[v as usize] as usize].rest;
            (xmin, xmax, zmax) = (xmin.min(p.x), xmax.max(p.x), zmax.max(p.z));
        }
    }
    (xmin + from_back * (xmax - xmin), 0.5 * zmax)
}

/// Where the right dome's thirds are sampled, as fractions of its antero-posterior extent from
/// its back: the middles of the posterior, middle and anterior thirds.
const THIRDS: [f64; 3] = [1.0 / 6.0, 0.5, 5.0 / 6.0];

/// The heights [m] at which the cranio-caudal `lines` cross the dome's upper surface in the
/// facade's current state.
fn crossings(torso: &Torso, lines: &[(f64, f64)]) -> Result<Vec<f64>> {
    let pos = positions(torso);
    lines
        .iter()
        .map(|&l| Ok(DomePoint::on_line(torso, l)?.height(&pos)))
        .collect()
}

/// Current anchor positions of the facade's state.
fn positions(torso: &Torso) -> Vec<nalgebra::Point3<f64>> {
    let model = &torso.compiled().model;
    let mut data = Data::new(model);
    kinematics::positions_and_velocities(model, &mut data, &Layout::new(model), torso.state());
    data.pos
}

/// A material point of the diaphragm dome: three anchors and the weights that place the point
/// among them.
#[derive(Clone, Copy, Debug)]
struct DomePoint {
    anchors: [usize; 3],
    weights: [f64; 3],
}

impl DomePoint {
    /// The material point of the dome that the cranio-caudal line through (x, z) crosses in
    /// the facade's current state (the highest crossing, the dome's upper surface; linear
    /// within each triangle). An error if the line misses the dome.
    fn on_line(torso: &Torso, (x, z): (f64, f64)) -> Result<DomePoint> {
        let ab = &torso.compiled().anatomy.abdomen;
        let pos = positions(torso);
        let mut best: Option<(f64, DomePoint)> = None;
        for (t, _) in ab.triangles.iter().zip(&ab.dome).filter(|(_, d)| **d) {
            let anchors = t.map(|v| ab.anchor[v as usize] as usize);
            let [p, q, r] = anchors.map(|a| pos[a]);
            // barycentric coordinates of (x, z) in the triangle's projection on the x-z plane
            let det = (q.x - p.x) * (r.z - p.z) - (r.x - p.x) * (q.z - p.z);
            if det.abs() < 1e-15 {
                continue;
            }
            let u = ((x - p.x) * (r.z - p.z) - (r.x - p.x) * (z - p.z)) / det;
            let w = ((q.x - p.x) * (z - p.z) - (x - p.x) * (q.z - p.z)) / det;
            if u >= 0.0 && w >= 0.0 && u + w <= 1.0 {
                let point = DomePoint {
                    anchors,
                    weights: [1.0 - u - w, u, w],
                };
                let y = point.height(&pos);
                if best.is_none_or(|(b, _)| y > b) {
                    best = Some((y, point));
                }
            }
        }
        best.map(|(_, p)| p).ok_or_else(|| {
            Error::State(format!(
                "the cranio-caudal line at x = {x:.3} m, z = {z:.3} m misses the diaphragm dome"
            ))
        })
    }

    /// The point's height (cranial) [m] among anchor positions `pos`.
    fn height(&self, pos: &[nalgebra::Point3<f64>]) -> f64 {
        (0..3)
            .map(|k| self.weights[k] * pos[self.anchors[k]].y)
            .sum()
    }
}

/// A full inspiratory effort of the default subject in `posture` with the airway open: the
/// drive off, the [`INSPIRATORY`] groups' activation inputs ramped to 1 over
/// [`EFFORT_RAMP`] and held until the lung volume settles. The volume added is measured
/// through the FMU, the posterior dome point's excursion through the facade (the same model
/// and method, the default explicit integrator), since no FMU output reports that point.
pub fn full_inspiration(
    posture: Posture,
    lod: u32,
    law: impl Into<Laws>,
) -> Result<FullInspiration> {
    let laws = law.into();
    let mut fmu = Fmu::new(&relaxed(posture, lod, laws))?;
    let rest = fmu.get(&["volume.lung"])?[0];
    let h = 0.05;
    while fmu.t < EFFORT_RAMP - 1e-9 {
        for g in INSPIRATORY {
            fmu.set(&format!("activation.{}", g.name()), effort(fmu.t + h))?;
        }
        fmu.step(h)?;
    }
    let inspired = settle(&mut fmu, 3.0, 1e-3, 20.0)?;

    let mut config = Config::default();
    config.subject.posture = posture;
    config.scene.level_of_detail = lod;
    config.muscle_law = laws.muscle;
    config.gravity_loads = laws.gravity_loads;
    config.postural_tone = laws.postural_tone;
    config.drive.enabled = false;
    let mut torso = Torso::new(config)?;
    let line = m_mode_line(&torso);
    let point = DomePoint::on_line(&torso, line)?;
    let y0 = point.height(&positions(&torso));
    let lines = THIRDS.map(|f| right_dome_line(&torso, f));
    let rest_heights = crossings(&torso, &lines).ok();
    let dome0 = torso.read(Quantity::DiaphragmDisplacement)?;
    let theta0 = torso.state().to_vec();
    let mut t = 0.0;
    let mut last = f64::NAN;
    let mut settled = false;
    // steps of h, the lung volume compared once a second (every 20th step) after 3 s held
    for k in 1..=((EFFORT_RAMP + 23.0) / h).round() as u32 {
        for g in INSPIRATORY {
            torso.set_activation(g, effort(t + h))?;
        }
        t = f64::from(k) * h;
        torso.advance_to(t)?;
        if t > EFFORT_RAMP + 3.0 && k % 20 == 0 {
            let v = torso.read(Quantity::LungVolume)?;
            if (v - last).abs() < 1e-3 {
                settled = true;
                break;
            }
            last = v;
        }
    }
    if !settled {
        return Err(Error::Numerical {
            time: t,
            reason: "the facade's full inspiration did not settle".into(),
        });
    }
    let end = positions(&torso);
    let m_mode = DomePoint::on_line(&torso, line)?.height(&end);
    let regional_excursion = rest_heights
        .zip(crossings(&torso, &lines).ok())
        .map(|(r, e)| [0, 1, 2].map(|k| 100.0 * (r[k] - e[k])));
    let layout = Layout::new(&torso.compiled().model);
    let theta1 = torso.state();
    let rib_rotation = torso
        .compiled()
        .anatomy
        .ribs
        .iter()
        .filter(|r| r.side.sign() > 0.0)
        .enumerate()
        .map(|(k, rib)| {
            let turn = (theta1[layout.theta + k] - theta0[layout.theta + k]).to_degrees();
            (turn * rib.axis.z.abs(), turn * rib.axis.x.abs())
        })
        .collect();
    Ok(FullInspiration {
        rest,
        inspired,
        added: inspired - rest,
        m_mode_excursion: 100.0 * (y0 - m_mode),
        posterior_point_excursion: 100.0 * (y0 - point.height(&end)),
        regional_excursion,
        m_mode_line: [line.0, line.1],
        dome_excursion: 100.0 * (dome0 - torso.read(Quantity::DiaphragmDisplacement)?),
        rib_rotation,
    })
}

/// The expiratory muscle groups a maximal expiration activates: the internal intercostals
/// (the model's expiratory intercostal group, the drive's counterpart of the external ones)
/// and the four abdominal muscles (the expiratory muscles of the abdominal wall; De Troyer &
/// Estenne 1988, J Appl Physiol 65:2319, on the respiratory muscles' actions).
pub const EXPIRATORY: [MuscleGroup; 5] = [
    MuscleGroup::InternalIntercostals,
    MuscleGroup::TransversusAbdominis,
    MuscleGroup::RectusAbdominis,
    MuscleGroup::ExternalObliques,
    MuscleGroup::InternalObliques,
];

/// How long the maximal inspiratory effort against the occlusion is held after its ramp [s]:
/// at least 1.5 s, so that the largest pressure sustained over 1 s can be read (ATS/ERS
/// statement on respiratory muscle testing 2002, Am J Respir Crit Care Med 166:518, section
/// 2, volitional tests: maximal static mouth pressures).
pub const OCCLUDED_HOLD: f64 = 2.0;

/// How long the relaxed system is held against the occlusion after the expiratory muscles'
/// release, before the inspiratory effort [s] (the relaxation pressure is read at its end).
pub const RELAXED_HOLD: f64 = 1.0;

/// The window of the sustained mouth pressure [s]: the largest mean over 1 s (ATS/ERS 2002).
pub const SUSTAINED_WINDOW: f64 = 1.0;

/// The maximal inspiratory effort against an occluded airway, through the FMU.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Occluded {
    /// The lung volume at rest (FRC, muscles relaxed, airway open) [L].
    pub rest: f64,
    /// The subject's residual volume where the reference places the manoeuvre: the ECSC
    /// ratio RV/FRC times the rest volume [L] ([`capacity_ratios`]).
    pub residual_volume: f64,
    /// The lung volume at the moment of occlusion, after the maximal expiration [L].
    pub volume: f64,
    /// The lung volume at the end of the occluded effort [L]: more than `volume` by the
    /// gas's rarefaction under the suction.
    pub volume_end: f64,
    /// The mouth pressure with every muscle relaxed against the occlusion before the effort
    /// [cmH2O]: the relaxed respiratory system's recoil at that volume (a point of the
    /// relaxation curve, Rahn et al. 1946), part of what the effort's mouth pressure holds.
    pub relaxed_pressure: f64,
    /// The lungs' share of it, `pressure.mouth` less `pressure.pleural` (the lungs' recoil,
    /// transpulmonary pressure) at the same instant [cmH2O].
    pub relaxed_lung_recoil: f64,
    /// The largest mean mouth pressure over [`SUSTAINED_WINDOW`] of the effort [cmH2O]
    /// (negative: suction).
    pub mouth_pressure: f64,
    /// The most negative mouth pressure sampled [cmH2O].
    pub peak: f64,
    /// Boyle's law checked on the FMU's outputs: (P_B - P_H2O + P_mouth) V_lung at the end of
    /// the effort over its value at occlusion (1 when no gas passed).
    pub gas_ratio: f64,
    /// The largest airflow read while occluded [L/s] (0: no gas passes).
    pub occluded_flow: f64,
}

/// The maximal inspiratory effort of the default subject in `posture` against an occluded
/// airway, through the FMU and its `airway.occluded` input: the drive off; a maximal
/// expiration with the airway open (the [`EXPIRATORY`] groups ramped to 1 over
/// [`EFFORT_RAMP`] and held until the lung volume settles), as a subject empties the lungs
/// towards RV before the manoeuvre; the airway occluded there; the expiratory groups released
/// over [`EFFORT_RAMP`] and the relaxed mouth pressure read after [`RELAXED_HOLD`]; then the
/// [`INSPIRATORY`] groups ramped to 1 over [`EFFORT_RAMP`] (the full
/// inspiratory activation of [`full_inspiration`]) and held for [`OCCLUDED_HOLD`], sampled
/// every 0.05 s. The figure is the largest mean of `pressure.mouth` over
/// [`SUSTAINED_WINDOW`] (ATS/ERS 2002).
pub fn occluded_inspiration(posture: Posture, lod: u32, law: impl Into<Laws>) -> Result<Occluded> {
    let mut fmu = Fmu::new(&relaxed(posture, lod, law.into()))?;
    let rest = fmu.get(&["volume.lung"])?[0];
    let mut subject = Config::default().subject;
    subject.posture = posture;
    let (rv_ratio, _) = capacity_ratios(&subject);
    let h = 0.05;
    let t0 = fmu.t;
    while fmu.t - t0 < EFFORT_RAMP - 1e-9 {
        for g in EXPIRATORY {
            fmu.set(&format!("activation.{}", g.name()), effort(fmu.t - t0 + h))?;
        }
        fmu.step(h)?;
    }
    let volume = settle(&mut fmu, 3.0, 1e-3, 20.0)?;
    fmu.set("airway.occluded", 1.0)?;
    let [v0, p0]: [f64; 2] = fmu
        .get(&["volume.lung", "pressure.mouth"])?
        .try_into()
        .map_err(|_| Error::State("two outputs expected".into()))?;
    let dry = crate::dynamics::airway::DRY_GAS_PRESSURE;
    let mut occluded_flow: f64 = 0.0;
    let t1 = fmu.t;
    while fmu.t - t1 < EFFORT_RAMP + RELAXED_HOLD - 1e-9 {
        for g in EXPIRATORY {
            fmu.set(
                &format!("activation.{}", g.name()),
                1.0 - effort(fmu.t - t1 + h),
            )?;
        }
        fmu.step(h)?;
        occluded_flow = occluded_flow.max(fmu.get(&["flow.airway"])?[0].abs());
    }
    let relaxed = fmu.get(&["pressure.mouth", "pressure.pleural"])?;
    let relaxed_pressure = relaxed[0] / CMH2O;
    let relaxed_lung_recoil = (relaxed[0] - relaxed[1]) / CMH2O;
    let t2 = fmu.t;
    let mut samples = Vec::new();
    let (mut v_end, mut p_end) = (v0, p0);
    while fmu.t - t2 < EFFORT_RAMP + OCCLUDED_HOLD - 1e-9 {
        for g in INSPIRATORY {
            fmu.set(&format!("activation.{}", g.name()), effort(fmu.t - t2 + h))?;
        }
        fmu.step(h)?;
        let o = fmu.get(&["pressure.mouth", "volume.lung", "flow.airway"])?;
        samples.push(o[0] / CMH2O);
        occluded_flow = occluded_flow.max(o[2].abs());
        (p_end, v_end) = (o[0], o[1]);
    }
    let n = (SUSTAINED_WINDOW / h).round() as usize;
    let sustained = samples
        .windows(n)
        .map(|w| w.iter().sum::<f64>() / n as f64)
        .fold(f64::INFINITY, f64::min);
    Ok(Occluded {
        rest,
        residual_volume: rest * rv_ratio,
        volume,
        volume_end: v_end,
        relaxed_pressure,
        relaxed_lung_recoil,
        mouth_pressure: sustained,
        peak: samples.iter().copied().fold(f64::INFINITY, f64::min),
        gas_ratio: ((dry + p_end) * v_end) / ((dry + p0) * v0),
        occluded_flow,
    })
}

/// Every figure of the default subject at level of detail `lod`, with the measurements they
/// came from.
#[derive(Clone, Debug, Serialize)]
pub struct Physiology {
    /// Level of detail.
    pub level_of_detail: u32,
    /// The muscle law (the FMU's `muscle_law`).
    pub muscle_law: MuscleLaw,
    /// How gravity loads the model (the FMU's `gravity_loads`).
    pub gravity_loads: GravityLoads,
    /// Whether the posture's tone is applied (the FMU's `postural_tone`).
    pub postural_tone: bool,
    /// The figures against their cited ranges.
    pub figures: Vec<Figure>,
    /// Figures that could not be measured, with the reason.
    pub failed: Vec<(String, String)>,
}

/// Measures every figure of the default subject at level of detail `lod` (a failed
/// measurement is listed in [`Physiology::failed`], not an error).
pub fn physiology(lod: u32, law: impl Into<Laws>) -> Result<Physiology> {
    let law = law.into();
    if lod > 2 {
        return Err(Error::invalid("level of detail", lod, "0, 1 or 2"));
    }
    let mut figures = Vec::new();
    let mut failed = Vec::new();
    let mut fig = |name: String, value: f64, unit, range: (f64, f64), source, through| {
        figures.push(Figure {
            name,
            value,
            unit,
            range,
            met: value >= range.0 && value <= range.1,
            source,
            through,
        })
    };
    let name = |p: Posture| format!("{p:?}").to_lowercase();
    for posture in [Posture::Standing, Posture::Supine] {
        match pressure_step(posture, lod, law) {
            Ok(s) => fig(
                format!(
                    "respiratory-system compliance, {} ({PRESSURE_STEP} cmH2O airway-opening step)",
                    name(posture)
                ),
                s.compliance,
                "L/cmH2O",
                SYSTEM_COMPLIANCE,
                "Agostoni & Mead 1964",
                FMU,
            ),
            Err(e) => failed.push((format!("compliance, {}", name(posture)), e.to_string())),
        }
    }
    match quiet_breath(Posture::Standing, lod, law, 1.0) {
        Ok(q) => {
            fig(
                "pleural pressure swing, quiet breathing standing".into(),
                q.pleural_swing,
                "cmH2O",
                PLEURAL_SWING,
                "West & Luks 2016",
                FMU,
            );
            fig(
                "rib-cage share of quiet tidal volume, standing".into(),
                100.0 * q.rib_cage_share,
                "%",
                (
                    100.0 * UPRIGHT_RIB_CAGE_SHARE.0,
                    100.0 * UPRIGHT_RIB_CAGE_SHARE.1,
                ),
                "Verschakelen & Demedts 1995",
                FMU,
            );
            fig(
                "diaphragm excursion per litre, quiet breathing standing".into(),
                q.excursion_per_litre,
                "cm/L",
                EXCURSION_PER_LITRE,
                "Houston et al. 1994",
                FMU,
            );
        }
        Err(e) => failed.push(("quiet breathing, standing".into(), e.to_string())),
    }
    match quiet_breath(Posture::Supine, lod, law, 1.0) {
        Ok(q) => fig(
            "abdominal share of quiet tidal volume, supine".into(),
            100.0 * (1.0 - q.rib_cage_share),
            "%",
            (
                100.0 * SUPINE_ABDOMINAL_SHARE.0,
                100.0 * SUPINE_ABDOMINAL_SHARE.1,
            ),
            "Aliverti et al. 2001",
            FMU,
        ),
        Err(e) => failed.push(("quiet breathing, supine".into(), e.to_string())),
    }
    match full_inspiration(Posture::Standing, lod, law) {
        Ok(f) => {
            fig(
                "volume added by full inspiratory activation, airway open, standing".into(),
                f.added,
                "L",
                INSPIRATORY_CAPACITY,
                "ECSC 1993 (inspiratory capacity)",
                FMU,
            );
            fig(
                "M-mode excursion of the posterior right dome, full inspiration standing".into(),
                f.m_mode_excursion,
                "cm",
                DEEP_EXCURSION_MEN,
                "Boussuges et al. 2009",
                "facade (no FMU output reports a dome point)",
            );
            for (rib, pump, bucket) in RIB_ROTATION_TO_TLC {
                let (p, b) = f.rib_rotation[rib as usize - 1];
                for (kind, value, cited) in [("pump", p, pump), ("bucket", b, bucket)] {
                    fig(
                        format!(
                            "right rib {rib}'s {kind}-handle rotation, full inspiration standing"
                        ),
                        value,
                        "deg",
                        (0.0, cited),
                        "Wilson et al. 1987 (FRC to TLC)",
                        "facade (no FMU output reports a rib)",
                    );
                }
            }
            if let Some([posterior, middle, anterior]) = f.regional_excursion {
                fig(
                    "right dome's excursion, posterior less middle third, full inspiration standing"
                        .into(),
                    posterior - middle,
                    "cm",
                    REGIONAL_GRADIENT,
                    "Gierada et al. 1995",
                    "facade (no FMU output reports a dome point)",
                );
                fig(
                    "right dome's excursion, middle less anterior third, full inspiration standing"
                        .into(),
                    middle - anterior,
                    "cm",
                    REGIONAL_GRADIENT,
                    "Gierada et al. 1995",
                    "facade (no FMU output reports a dome point)",
                );
            } else {
                failed.push((
                    "right dome's regional excursion, full inspiration standing".into(),
                    "a cranio-caudal line through one of the right dome's thirds misses the dome"
                        .into(),
                ));
            }
        }
        Err(e) => failed.push(("full inspiration, standing".into(), e.to_string())),
    }
    let range = pimax_range(&Config::default().subject);
    match occluded_inspiration(Posture::Standing, lod, law) {
        Ok(o) => fig(
            format!(
                "maximal inspiratory mouth pressure, occluded at {:.2} L after a maximal \
                 expiration (RV {:.2} L), standing, 1-s sustained (magnitude)",
                o.volume, o.residual_volume
            ),
            -o.mouth_pressure,
            "cmH2O",
            range,
            "Harik-Khan, Wise & Fozard 1998; ATS/ERS 2002",
            FMU,
        ),
        Err(e) => failed.push((
            "maximal inspiratory pressure, occluded".into(),
            e.to_string(),
        )),
    }
    match quiet_breath(Posture::Standing, lod, law, 0.0) {
        Ok(q) => {
            fig(
                "paralysed left hemidiaphragm's motion in inspiration, quiet standing (cranial +)"
                    .into(),
                q.hemidiaphragm_motion[0],
                "cm",
                (0.0, f64::INFINITY),
                "sniff test paradox (Alexander 1966)",
                FMU,
            );
            fig(
                "healthy right hemidiaphragm's motion in inspiration, same breath (cranial +)"
                    .into(),
                q.hemidiaphragm_motion[1],
                "cm",
                (f64::NEG_INFINITY, 0.0),
                "sniff test paradox (Alexander 1966)",
                FMU,
            );
            fig(
                "paralysed side's share of tidal volume, quiet standing".into(),
                100.0 * q.left_share,
                "%",
                (
                    100.0 * PARALYSED_SIDE_SHARE.0,
                    100.0 * PARALYSED_SIDE_SHARE.1,
                ),
                "issue 35",
                FMU,
            );
        }
        Err(e) => failed.push(("paralysed left hemidiaphragm".into(), e.to_string())),
    }
    match sniff(Posture::Standing, lod, law, 0.0) {
        Ok(q) => {
            fig(
                "paralysed left hemidiaphragm's motion in a sniff, standing (cranial +)".into(),
                q.hemidiaphragm_motion[0],
                "cm",
                (0.0, f64::INFINITY),
                "sniff test paradox (Alexander 1966)",
                FMU,
            );
            fig(
                "healthy right hemidiaphragm's motion in the same sniff (cranial +)".into(),
                q.hemidiaphragm_motion[1],
                "cm",
                (f64::NEG_INFINITY, 0.0),
                "sniff test paradox (Alexander 1966)",
                FMU,
            );
        }
        Err(e) => failed.push(("sniff, paralysed left hemidiaphragm".into(), e.to_string())),
    }
    match sniff(Posture::Standing, lod, law, 1.0) {
        Ok(q) => fig(
            "largest transdiaphragmatic pressure of a sniff from FRC, standing".into(),
            q.transdiaphragmatic,
            "cmH2O",
            SNIFF_TRANSDIAPHRAGMATIC,
            "Wanke et al. 1990",
            FMU,
        ),
        Err(e) => failed.push(("sniff".into(), e.to_string())),
    }
    Ok(Physiology {
        level_of_detail: lod,
        muscle_law: law.muscle,
        gravity_loads: law.gravity_loads,
        postural_tone: law.postural_tone,
        figures,
        failed,
    })
}
