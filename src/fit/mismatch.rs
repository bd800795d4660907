//! The fit's acceptance under model mismatch: recordings made by a different model than the
//! one that fits them, fitted back and judged against what made them. The truth model is
//! the level of detail 2 torso of a subject 8 % taller and 8 % heavier than the fitting
//! model's default man, breathing a non-sinusoidal quiet drive (Ti/Ttot drawn in 0.38-0.45)
//! with 10 % breath-to-breath variation of depth and period; its recordings carry 0.5 mm
//! noise per coordinate and 2 % dropped points, for three marker sets (the SLP 10 x 6 grid
//! in a camera frame, the 30-marker chest-and-back set and the 89-marker OEP-like set in a
//! laboratory frame). Each recording is fitted at levels of detail 0 and 1 with the default
//! subject, the inspiratory fraction read off the recording and at most 200 evaluations.
//!
//! Per case ([`MismatchRow`]): the fitted lung's tidal volume against the truth's mean over
//! the recording's breaths, the breath-by-breath Ti, Te and Ttot the fit finds on the
//! recording against the drive's breaths, the marker residual against the noise floor plus
//! the model-mismatch floor, and the evaluations.
//!
//! The model-mismatch floor is defined operationally: the residual of the same fit (level of
//! detail, subject, options) of the noise-free recording made by the same truth run (same
//! breaths, camera and dropped points, the noise left out). It is the part of the residual
//! the fitting model cannot explain because it is another model; the noise floor is the
//! part no model can explain. Both, and the residual, are the fit's cost (thesis eq. 3.1):
//! the mean distance between model and recorded points, the measure the synthetic noise
//! floor (mean length of the noise vectors) is stated in.

use super::fitting::{Fit, FitOptions, estimated_noise_floor, fit_recording};
use super::synth::{Camera, SynthOptions, Synthetic, synthesize};
use super::{MarkerSource, TorsoMarkers, Trajectory, fit_any_markers};
use crate::anatomy::Subject;
use crate::anatomy::skin::{MarkerSet, Skin, SkinOptions, SurfaceOptions};
use crate::fit::clinical::BreathReport;
use crate::model::Drive;
use crate::numeric::rng::Pcg64;
use crate::recording::{Markers, Recording, Units};
use crate::stats::breaths::{BreathDetector, segment_breaths};
use crate::{Config, Error, Result, Torso};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};

/// Tidal volume of the fitted lung within 10 % of the truth's mean over breaths (issue 19,
/// deliverable 4).
pub const ACCEPT_TIDAL_VOLUME_REL: f64 = 0.10;
/// Breath-by-breath limits of agreement of SLP against a pneumotachograph for Ti [s]
/// (Motamedi-Fakhr et al. 2017, Physiol. Rep. 5(3):e13124).
pub const LIMIT_TI_S: f64 = 0.22;
/// As [`LIMIT_TI_S`], for Te [s].
pub const LIMIT_TE_S: f64 = 0.29;
/// As [`LIMIT_TI_S`], for Ttot [s].
pub const LIMIT_TTOT_S: f64 = 0.32;
/// The residual may reach 1.3 x the noise floor plus the model-mismatch floor (issue 19,
/// deliverable 4).
pub const ACCEPT_RESIDUAL_NOISE_FACTOR: f64 = 1.3;
/// At most 200 evaluations per fit (issue 19, deliverable 4).
pub const ACCEPT_EVALUATIONS: usize = 200;
/// The truth subject's stature and mass are this much (relative) above the fitting model's
/// (issue 19, deliverable 4: 8 %).
pub const SUBJECT_OFFSET: f64 = 0.08;
/// Range the truth drive's inspiratory fraction Ti/Ttot is drawn from (issue 19,
/// deliverable 4: 0.38-0.45).
pub const TI_TTOT_RANGE: (f64, f64) = (0.38, 0.45);

/// Settings of a mismatch sweep.
#[derive(Clone, Debug, PartialEq)]
pub struct MismatchOptions {
    /// Recording length [s].
    pub duration: f64,
    /// Level of detail of the truth model (2 in the acceptance).
    pub truth_lod: u32,
    /// Levels of detail the recordings are fitted at (0 and 1 in the acceptance).
    pub fit_lods: Vec<u32>,
    /// Marker sets: `grid`, `chest30`, `oep89`.
    pub marker_sets: Vec<String>,
    /// Breath-to-breath variation of depth and period (0.1).
    pub variability: f64,
    /// Noise per coordinate [m] (0.5 mm).
    pub noise: f64,
    /// Probability of a dropped point (0.02).
    pub dropout: f64,
    /// Largest number of evaluations per fit (200).
    pub max_evals: usize,
    /// Solver relative tolerance of truth and fits.
    pub rtol: f64,
    /// Fits (and recordings) run at once (threads).
    pub jobs: usize,
    /// Base seed: marker set k uses `seed + k`.
    pub seed: u64,
    /// Folder for the rest-pose reference grids of a skin fit of the grid
    /// ([`super::fitting::fit_with_skin`], as `torso fit --skin-fit`); None: the grid is
    /// fitted with rigid registration alone, as `torso fit` does by default.
    pub grid_skin_fit: Option<std::path::PathBuf>,
    /// Fit the grid with each marker compared about its own mean
    /// ([`FitOptions::marker_offsets`], as `torso fit --marker-offsets`); the named sets
    /// always are.
    pub grid_marker_offsets: bool,
    /// Estimate the subject's stature and mass from each recording's first frame before
    /// fitting ([`super::size::estimate_size`], as `torso fit --fit-size`).
    pub fit_size: bool,
}

impl Default for MismatchOptions {
    fn default() -> Self {
        MismatchOptions {
            duration: 18.0,
            truth_lod: 2,
            fit_lods: vec![0, 1],
            marker_sets: vec!["grid".into(), "chest30".into(), "oep89".into()],
            variability: 0.1,
            noise: 0.5e-3,
            dropout: 0.02,
            max_evals: ACCEPT_EVALUATIONS,
            rtol: 1e-6,
            jobs: 1,
            seed: 301,
            grid_skin_fit: None,
            grid_marker_offsets: false,
            fit_size: false,
        }
    }
}

impl MismatchOptions {
    /// Checks the fields that the synthesis and the fits do not check themselves.
    pub fn validate(&self) -> Result<()> {
        if self.jobs == 0 {
            return Err(Error::invalid("--jobs", 0, "at least 1"));
        }
        for &l in self.fit_lods.iter().chain([&self.truth_lod]) {
            if l > 2 {
                return Err(Error::invalid("level of detail", l, "0, 1 or 2"));
            }
        }
        if self.fit_lods.is_empty() || self.marker_sets.is_empty() {
            return Err(Error::invalid(
                "mismatch sweep",
                "no case",
                "at least one fitting level of detail and one marker set",
            ));
        }
        for s in &self.marker_sets {
            if !crate::anatomy::skin::BUILTIN_SETS.contains(&s.as_str()) {
                return Err(Error::invalid(
                    "marker set",
                    s,
                    crate::anatomy::skin::BUILTIN_SETS.join(", "),
                ));
            }
        }
        Ok(())
    }
}

/// The truth subject: the default man with stature and mass [`SUBJECT_OFFSET`] higher.
pub fn truth_subject() -> Subject {
    let d = Subject::default();
    Subject {
        stature: d.stature * (1.0 + SUBJECT_OFFSET),
        mass: d.mass * (1.0 + SUBJECT_OFFSET),
        ..d
    }
}

/// A recording made by the truth model, with what the judgement needs.
#[derive(Clone, Debug)]
pub struct MismatchTruth {
    /// The marker set.
    pub marker_set: String,
    /// Labels of a named set (empty for the grid).
    pub labels: Vec<String>,
    /// The drive's inspiratory fraction (drawn in [`TI_TTOT_RANGE`]).
    pub ti_ttot: f64,
    /// The noisy recording and its truth.
    pub synthetic: Synthetic,
    /// The same recording without noise (same breaths, camera and dropped points).
    pub clean: Recording,
    /// The truth lung's tidal volume of each whole breath in the recording [L].
    pub tidal_volumes_l: Vec<f64>,
    /// The drive's breaths in recording time: (onset of rib-cage inspiration [s], period [s]).
    pub breaths: Vec<(f64, f64)>,
    /// Wall time of making it [s].
    pub wall_s: f64,
}

impl MismatchTruth {
    /// Mean tidal volume over the recording's breaths [L] (NaN without a whole breath).
    pub fn mean_tidal_volume_l(&self) -> f64 {
        mean(&self.tidal_volumes_l)
    }
}

fn mean(x: &[f64]) -> f64 {
    if x.is_empty() {
        f64::NAN
    } else {
        x.iter().sum::<f64>() / x.len() as f64
    }
}

/// The truth model's configuration under `drive`.
fn truth_config(o: &MismatchOptions, drive: Drive) -> Result<Config> {
    let mut c = Config {
        subject: truth_subject(),
        drive,
        ..Config::default()
    };
    c.scene.level_of_detail = o.truth_lod;
    c.solver.rtol = o.rtol;
    c.validate()?;
    Ok(c)
}

/// The fitting model's configuration: the default subject at level of detail `lod`, the
/// tolerances of `torso fit` (atol = rtol / 100).
pub fn fit_config(o: &MismatchOptions, lod: u32) -> Result<Config> {
    let mut c = Config::default();
    c.scene.level_of_detail = lod;
    c.solver.rtol = o.rtol;
    c.solver.atol = 1e-2 * o.rtol;
    c.validate()?;
    Ok(c)
}

/// Makes the recording of marker set number `index` of `o.marker_sets` with the truth model.
pub fn make_truth(o: &MismatchOptions, index: usize) -> Result<MismatchTruth> {
    let start = std::time::Instant::now();
    let name = o
        .marker_sets
        .get(index)
        .ok_or_else(|| Error::invalid("marker set index", index, "a listed marker set"))?
        .clone();
    let seed = o.seed + index as u64;
    let (lo, hi) = TI_TTOT_RANGE;
    let ti_ttot = lo + (hi - lo) * Pcg64::new(seed, 11).uniform();
    let mut drive = super::sweep::case_drive(false);
    drive.inspiratory_fraction = ti_ttot;
    let mut torso = Torso::new(truth_config(o, drive)?)?;
    let mut labels = Vec::new();
    if name != "grid" {
        let skin = Skin::for_anatomy(&torso.compiled().anatomy, &SkinOptions::default())?;
        let set = MarkerSet::builtin(&skin, &name)?;
        labels = set.labels.clone();
        torso.set_marker_set(Some(Arc::new(set)));
    }
    let mut model = TorsoMarkers::from_torso(torso)?;
    let synthetic = synthesize(
        &mut model,
        &SynthOptions {
            drive,
            duration: o.duration,
            noise: o.noise,
            seed,
            camera: if name == "grid" {
                Camera::Random
            } else {
                Camera::Lab
            },
            variability: o.variability,
            dropout: o.dropout,
            ..SynthOptions::default()
        },
    )?;
    // The same run again with the lung volume: the noise-free recording (the noisy one's
    // camera and dropped points) and the truth's breaths.
    let times = &synthetic.recording.times;
    let model_times: Vec<f64> = times.iter().map(|t| synthetic.start_time + t).collect();
    let mut traj = Trajectory::default();
    model.run(&synthetic.schedule, &model_times, true, &mut traj)?;
    let clean = Recording {
        frames: traj
            .markers
            .iter()
            .zip(&synthetic.recording.frames)
            .map(|(exact, noisy)| {
                exact
                    .iter()
                    .zip(noisy)
                    .map(|(p, q)| q.map(|_| synthetic.camera.apply(p)))
                    .collect()
            })
            .collect(),
        ..synthetic.recording.clone()
    };
    let period = 1.0 / drive.frequency;
    let detector = BreathDetector {
        min_distance_s: 0.1 * period,
        smoothing_s: 0.0,
        ..BreathDetector::for_period(period)
    };
    let tidal_volumes_l = segment_breaths(times, &traj.lung_volume, &detector)
        .iter()
        .map(|b| b.tidal_volume)
        .collect();
    // Before the schedule's first breath the drive is the nominal one, of period 1/f.
    let mut breaths: Vec<(f64, f64)> = synthetic
        .breaths
        .0
        .first()
        .map(|b| (b.start - synthetic.start_time - period, period))
        .into_iter()
        .collect();
    breaths.extend(
        synthetic
            .breaths
            .0
            .iter()
            .map(|b| (b.start - synthetic.start_time, b.period)),
    );
    Ok(MismatchTruth {
        marker_set: name,
        labels,
        ti_ttot,
        synthetic,
        clean,
        tidal_volumes_l,
        breaths,
        wall_s: start.elapsed().as_secs_f64(),
    })
}

/// Fits `recording` (of `truth`'s marker set: its noisy recording or its noise-free twin) at
/// level of detail `lod`; returns the fit and the fitted model's configuration (with its
/// fitted skin under [`MismatchOptions::grid_skin_fit`]).
pub fn fit_truth_recording(
    o: &MismatchOptions,
    truth: &MismatchTruth,
    recording: &Recording,
    lod: u32,
    progress: &mut dyn FnMut(usize, f64),
) -> Result<(Fit, Config)> {
    let mut config = fit_config(o, lod)?;
    if o.fit_size {
        let size = super::size::estimate_size(
            &config,
            &recording.frames[0],
            truth.labels.is_empty(),
            &SurfaceOptions::default(),
            &super::size::SizeOptions::default(),
        )?;
        config.subject = size.subject;
    }
    let options = FitOptions {
        max_evals: o.max_evals,
        inspiratory_fraction: None,
        threads: 1,
        marker_offsets: truth.labels.is_empty() && o.grid_marker_offsets,
        ..FitOptions::default()
    };
    let mut fitted_config = config.clone();
    let fit = if truth.labels.is_empty() {
        if let Some(dir) = &o.grid_skin_fit {
            // One reference file per level of detail and recording (noisy or noise-free).
            let tag = if std::ptr::eq(recording, &truth.clean) {
                "clean"
            } else {
                "noisy"
            };
            let reference = dir.join(format!(
                "mismatch_{}_lod{lod}_{tag}_reference.csv",
                truth.marker_set
            ));
            let fit =
                super::fitting::fit_with_skin(&config, recording, &reference, &options, progress)?;
            fitted_config.scene.slp_reference = Some(reference);
            fit
        } else {
            let mut source = TorsoMarkers::new(config.clone())?;
            fit_recording(&mut source, recording, &options, progress)?
        }
    } else {
        let markers = Markers {
            labels: truth.labels.clone(),
            times: recording.times.clone(),
            frames: recording.frames.clone(),
            units: Units::Metres,
            format: crate::recording::Format::MarkerCsv,
            provenance: Vec::new(),
        };
        fit_any_markers(
            config.clone(),
            &markers,
            &SurfaceOptions::default(),
            &super::PoseOptions::default(),
            &options,
            progress,
        )?
        .fit
    };
    Ok((fit, fitted_config))
}

/// The worst breath-by-breath timing errors of a fit's recording breaths against the drive's.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TimingErrors {
    /// Whole breaths found on the recording.
    pub found: usize,
    /// Of those, matched to a drive breath (onsets within 0.5 s).
    pub matched: usize,
    /// Worst |error| of Ti [s].
    pub ti_s: f64,
    /// Worst |error| of Te [s].
    pub te_s: f64,
    /// Worst |error| of Ttot [s].
    pub ttot_s: f64,
}

/// Matches each breath found on the recording with the drive breath of nearest onset (the
/// drive's Ti is its inspiratory fraction times its period) and keeps the worst errors;
/// a found breath more than 0.5 s from every drive onset is left unmatched.
pub fn timing_errors(fit: &Fit, truth: &[(f64, f64)], ti_ttot: f64) -> TimingErrors {
    let mut e = TimingErrors {
        found: fit.breathing.breaths.len(),
        ..TimingErrors::default()
    };
    for (b, &onset) in fit.breathing.breaths.iter().zip(&fit.breathing.onsets) {
        let Some(&(start, period)) = truth
            .iter()
            .min_by(|a, c| (a.0 - onset).abs().total_cmp(&(c.0 - onset).abs()))
        else {
            continue;
        };
        if (start - onset).abs() > 0.5 {
            continue;
        }
        e.matched += 1;
        let ti = ti_ttot * period;
        e.ti_s = e.ti_s.max((b.ti - ti).abs());
        e.te_s = e.te_s.max((b.te - (period - ti)).abs());
        e.ttot_s = e.ttot_s.max((b.ttot - period).abs());
    }
    e
}

/// The outcome of one case: a marker set fitted at one level of detail.
#[derive(Clone, Debug, PartialEq)]
pub struct MismatchRow {
    /// Marker set.
    pub marker_set: String,
    /// Level of detail of the fit.
    pub fit_lod: u32,
    /// Truth drive's Ti/Ttot.
    pub true_ti_ttot: f64,
    /// Fitted Ti/Ttot (read off the recording).
    pub fitted_ti_ttot: f64,
    /// Truth lung's mean tidal volume over the recording's breaths [L].
    pub true_tidal_volume_l: f64,
    /// Fitted lung's mean tidal volume over its breaths in the recording's span [L].
    pub fitted_tidal_volume_l: f64,
    /// Breath timing against the drive's breaths.
    pub timing: TimingErrors,
    /// Residual of the fit (mean marker distance) [m].
    pub residual_m: f64,
    /// Noise floor of the recording (mean length of the noise added) [m].
    pub noise_floor_m: f64,
    /// Noise floor estimated from the recording alone [m].
    pub noise_floor_estimate_m: f64,
    /// Model-mismatch floor: residual of the same fit of the noise-free recording [m].
    pub mismatch_floor_m: f64,
    /// Evaluations of the fit.
    pub evaluations: usize,
    /// Evaluations of the noise-free fit.
    pub floor_evaluations: usize,
    /// Wall time of the fit [s].
    pub wall_s: f64,
    /// The fitted drive.
    pub fitted: Drive,
    /// The fitting model's stature [m] and mass [kg] (estimated from the recording under
    /// [`MismatchOptions::fit_size`], otherwise the default subject's).
    pub fitted_subject: (f64, f64),
}

impl MismatchRow {
    /// Relative error of the fitted tidal volume.
    pub fn tidal_volume_error(&self) -> f64 {
        (self.fitted_tidal_volume_l - self.true_tidal_volume_l) / self.true_tidal_volume_l
    }

    /// The residual's bound: 1.3 x noise floor + mismatch floor [m].
    pub fn residual_bound_m(&self) -> f64 {
        ACCEPT_RESIDUAL_NOISE_FACTOR * self.noise_floor_m + self.mismatch_floor_m
    }

    /// Pass (true) of each criterion: tidal volume, Ti, Te, Ttot, residual, evaluations.
    /// The timing criteria fail when no breath was matched.
    pub fn verdicts(&self) -> [(&'static str, bool); 6] {
        let t = &self.timing;
        let timed = t.matched > 0;
        [
            (
                "VT",
                self.tidal_volume_error().abs() <= ACCEPT_TIDAL_VOLUME_REL,
            ),
            ("Ti", timed && t.ti_s <= LIMIT_TI_S),
            ("Te", timed && t.te_s <= LIMIT_TE_S),
            ("Ttot", timed && t.ttot_s <= LIMIT_TTOT_S),
            ("residual", self.residual_m <= self.residual_bound_m()),
            ("evaluations", self.evaluations <= ACCEPT_EVALUATIONS),
        ]
    }

    /// The failed criteria (empty: all met).
    pub fn failures(&self) -> Vec<&'static str> {
        self.verdicts()
            .iter()
            .filter(|v| !v.1)
            .map(|v| v.0)
            .collect()
    }

    /// The row as JSON.
    pub fn json(&self) -> serde_json::Value {
        let t = &self.timing;
        serde_json::json!({
            "marker_set": self.marker_set,
            "fit_level_of_detail": self.fit_lod,
            "ti_ttot": {"truth": self.true_ti_ttot, "fitted": self.fitted_ti_ttot},
            "tidal_volume_l": {
                "truth_mean_over_breaths": self.true_tidal_volume_l,
                "fitted": self.fitted_tidal_volume_l,
                "error_rel": self.tidal_volume_error(),
                "limit_rel": ACCEPT_TIDAL_VOLUME_REL,
            },
            "breath_timing": {
                "breaths_found": t.found,
                "breaths_matched": t.matched,
                "worst_abs_error_s": {"ti": t.ti_s, "te": t.te_s, "ttot": t.ttot_s},
                "limits_s": {"ti": LIMIT_TI_S, "te": LIMIT_TE_S, "ttot": LIMIT_TTOT_S},
            },
            "residual": {
                "measure": "mean distance between model and recorded points (the fit's cost)",
                "residual_m": self.residual_m,
                "noise_floor_m": self.noise_floor_m,
                "noise_floor_estimate_m": self.noise_floor_estimate_m,
                "mismatch_floor_m": self.mismatch_floor_m,
                "bound_m": self.residual_bound_m(),
            },
            "evaluations": self.evaluations,
            "floor_fit_evaluations": self.floor_evaluations,
            "wall_s": self.wall_s,
            "fitted": super::report::drive_fmi(&self.fitted),
            "fitted_subject": {"stature_m": self.fitted_subject.0, "mass_kg": self.fitted_subject.1},
            "pass": self.verdicts().iter().map(|(k, v)| (k.to_string(), serde_json::json!(v))).collect::<serde_json::Map<_, _>>(),
            "failures": self.failures(),
        })
    }
}

/// Runs `f` over `items`, `jobs` at a time; results in the order of `items`.
fn parallel<T: Sync, R: Send>(
    items: &[T],
    jobs: usize,
    f: &(dyn Fn(usize, &T) -> Result<R> + Sync),
) -> Result<Vec<R>> {
    let next = AtomicUsize::new(0);
    let results: Mutex<Vec<Option<Result<R>>>> =
        Mutex::new((0..items.len()).map(|_| None).collect());
    std::thread::scope(|scope| {
        for _ in 0..jobs.clamp(1, items.len().max(1)) {
            scope.spawn(|| {
                loop {
                    let i = next.fetch_add(1, Ordering::SeqCst);
                    let Some(item) = items.get(i) else { break };
                    let r = f(i, item);
                    if let Ok(mut all) = results.lock() {
                        all[i] = Some(r);
                    }
                }
            });
        }
    });
    results
        .into_inner()
        .map_err(|_| Error::State("mismatch sweep: a worker panicked".into()))?
        .into_iter()
        .map(|r| {
            r.unwrap_or_else(|| Err(Error::State("mismatch sweep: a task did not run".into())))
        })
        .collect()
}

/// Runs the sweep: every marker set's recording, then each fitted at every level of detail
/// together with its noise-free twin. `done(message)` is called as each step finishes.
/// Rows come back by marker set, then level of detail.
pub fn run_mismatch(
    o: &MismatchOptions,
    done: &(dyn Fn(&str) + Sync),
) -> Result<(Vec<MismatchTruth>, Vec<MismatchRow>)> {
    o.validate()?;
    let sets: Vec<usize> = (0..o.marker_sets.len()).collect();
    let truths = parallel(&sets, o.jobs, &|_, &k| {
        let t = make_truth(o, k)?;
        done(&format!(
            "{}: recording made at level of detail {} in {:.1} s (Ti/Ttot {:.3}, {} drive breaths, truth tidal volume {:.3} L over {} breaths)",
            t.marker_set,
            o.truth_lod,
            t.wall_s,
            t.ti_ttot,
            t.breaths.len(),
            t.mean_tidal_volume_l(),
            t.tidal_volumes_l.len()
        ));
        Ok(t)
    })?;
    // Tasks: (set, lod, noise-free?), the slower levels of detail first.
    let mut tasks = Vec::new();
    let mut lods = o.fit_lods.clone();
    lods.sort_unstable_by(|a, b| b.cmp(a));
    for &lod in &lods {
        for k in 0..truths.len() {
            for clean in [false, true] {
                tasks.push((k, lod, clean));
            }
        }
    }
    let fits = parallel(&tasks, o.jobs, &|_, &(k, lod, clean)| {
        let t = &truths[k];
        let recording = if clean {
            &t.clean
        } else {
            &t.synthetic.recording
        };
        let start = std::time::Instant::now();
        let (fit, config) = fit_truth_recording(o, t, recording, lod, &mut |_, _| {})?;
        let fitted_vt = if clean {
            f64::NAN
        } else {
            let report = BreathReport::of_fit(&config, &fit)?;
            mean(
                &report
                    .breaths
                    .iter()
                    .map(|b| b.tidal_volume_l)
                    .collect::<Vec<_>>(),
            )
        };
        let wall = start.elapsed().as_secs_f64();
        done(&format!(
            "{} at level of detail {lod}{}: {} evaluations, {:.1} s, residual {:.3} mm, subject {:.3} m {:.1} kg",
            t.marker_set,
            if clean { " (noise-free)" } else { "" },
            fit.evaluations,
            wall,
            fit.cost_m * 1e3,
            config.subject.stature,
            config.subject.mass
        ));
        let subject = (config.subject.stature, config.subject.mass);
        Ok((fit, fitted_vt, wall, subject))
    })?;
    let mut rows = Vec::new();
    for (k, t) in truths.iter().enumerate() {
        for &lod in &o.fit_lods {
            let find = |clean: bool| {
                tasks
                    .iter()
                    .position(|&x| x == (k, lod, clean))
                    .map(|i| &fits[i])
                    .ok_or_else(|| Error::State("mismatch sweep: a fit is missing".into()))
            };
            let (fit, fitted_vt, wall, subject) = find(false)?;
            let (floor, _, _, _) = find(true)?;
            rows.push(MismatchRow {
                marker_set: {
                    let grid = t.labels.is_empty();
                    let how: Vec<&str> = [
                        (grid && o.grid_skin_fit.is_some(), "skin fit"),
                        (grid && o.grid_marker_offsets, "offsets"),
                        (o.fit_size, "size fitted"),
                    ]
                    .into_iter()
                    .filter_map(|(on, name)| on.then_some(name))
                    .collect();
                    if how.is_empty() {
                        t.marker_set.clone()
                    } else {
                        format!("{} ({})", t.marker_set, how.join(", "))
                    }
                },
                fit_lod: lod,
                true_ti_ttot: t.ti_ttot,
                fitted_ti_ttot: fit.drive.inspiratory_fraction,
                true_tidal_volume_l: t.mean_tidal_volume_l(),
                fitted_tidal_volume_l: *fitted_vt,
                timing: timing_errors(fit, &t.breaths, t.ti_ttot),
                residual_m: fit.cost_m,
                noise_floor_m: t.synthetic.noise_floor_m,
                noise_floor_estimate_m: estimated_noise_floor(&fit.times, &fit.recorded),
                mismatch_floor_m: floor.cost_m,
                evaluations: fit.evaluations,
                floor_evaluations: floor.evaluations,
                wall_s: *wall,
                fitted: fit.drive,
                fitted_subject: *subject,
            });
        }
    }
    Ok((truths, rows))
}

/// The sweep as a Markdown table.
pub fn table(rows: &[MismatchRow]) -> String {
    let mut s = String::from(
        "| marker set | fit LOD | Ti/Ttot true / fit | VT true / fit L (err) | breaths matched / found | worst Ti / Te / Ttot err s | residual / noise floor (est.) / mismatch floor mm | bound mm | evals | wall s | result |\n|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        let t = &r.timing;
        let fails = r.failures();
        s += &format!(
            "| {} | {} | {:.3} / {:.3} | {:.3} / {:.3} ({:+.1} %) | {} / {} | {:.3} / {:.3} / {:.3} | {:.3} / {:.3} ({:.3}) / {:.3} | {:.3} | {} | {:.0} | {} |\n",
            r.marker_set,
            r.fit_lod,
            r.true_ti_ttot,
            r.fitted_ti_ttot,
            r.true_tidal_volume_l,
            r.fitted_tidal_volume_l,
            100.0 * r.tidal_volume_error(),
            t.matched,
            t.found,
            t.ti_s,
            t.te_s,
            t.ttot_s,
            r.residual_m * 1e3,
            r.noise_floor_m * 1e3,
            r.noise_floor_estimate_m * 1e3,
            r.mismatch_floor_m * 1e3,
            r.residual_bound_m() * 1e3,
            r.evaluations,
            r.wall_s,
            if fails.is_empty() {
                "PASS".to_string()
            } else {
                format!("FAIL: {}", fails.join(", "))
            }
        );
    }
    s
}
