//! The fit's acceptance sweep: synthetic recordings with known parameters (quiet and forced
//! breathing in the three postures, two subjects, 0.5 mm noise, random camera pose, 18 s by
//! default) fitted back, each compared with its truth: amplitudes (relative error), phase
//! difference, frequency, final cost against the noise floor, evaluations and wall time.
//!
//! The six cases pair each posture with both breathing styles and spread them over the two
//! subjects: the default man (1.75 m, 75 kg) and a woman (1.62 m, 60 kg).

use super::fitting::wrap_angle;
use super::{FitOptions, SynthOptions, Synthetic, TorsoMarkers, fit_recording, synthesize};
use crate::anatomy::{Posture, Sex, Subject};
use crate::model::{Drive, Wave};
use crate::{Config, Error, Result};
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};

/// Acceptance bounds of the fit (issue text): amplitudes within 10 % relative, phase
/// difference within 0.15 rad, final cost within 15 % of the noise floor, frequency within
/// 1 %, at most 120 evaluations.
pub const ACCEPT_AMPLITUDE_REL: f64 = 0.10;
/// See [`ACCEPT_AMPLITUDE_REL`].
pub const ACCEPT_PHASE_RAD: f64 = 0.15;
/// See [`ACCEPT_AMPLITUDE_REL`].
pub const ACCEPT_COST_OVER_FLOOR: f64 = 1.15;
/// See [`ACCEPT_AMPLITUDE_REL`].
pub const ACCEPT_FREQUENCY_REL: f64 = 0.01;
/// See [`ACCEPT_AMPLITUDE_REL`].
pub const ACCEPT_EVALUATIONS: usize = 120;

/// One synthetic recording of the sweep.
#[derive(Clone, Debug, PartialEq)]
pub struct SweepCase {
    /// Short label: subject, posture, breathing.
    pub label: String,
    /// The subject (posture included).
    pub subject: Subject,
    /// Forced (true) or quiet breathing.
    pub forced: bool,
    /// Seed of the recording's noise and camera pose.
    pub seed: u64,
}

/// The sweep's second subject: a woman of 1.62 m and 60 kg.
pub fn subject_b() -> Subject {
    Subject {
        sex: Sex::Female,
        age: 45.0,
        stature: 1.62,
        mass: 60.0,
        breast_size: 0.4,
        ..Subject::default()
    }
}

/// The six cases: each posture with quiet and forced breathing, one of them on each subject.
pub fn default_cases() -> Vec<SweepCase> {
    let a = Subject::default();
    let b = subject_b();
    let plan = [
        ("man", &a, Posture::Standing, false),
        ("woman", &b, Posture::Standing, true),
        ("woman", &b, Posture::Sitting, false),
        ("man", &a, Posture::Sitting, true),
        ("man", &a, Posture::Supine, false),
        ("woman", &b, Posture::Supine, true),
    ];
    plan.iter()
        .enumerate()
        .map(|(i, (who, s, posture, forced))| SweepCase {
            label: format!(
                "{who} {} {}",
                format!("{posture:?}").to_lowercase(),
                if *forced { "forced" } else { "quiet" }
            ),
            subject: Subject {
                posture: *posture,
                ..(*s).clone()
            },
            forced: *forced,
            seed: 101 + i as u64,
        })
        .collect()
}

/// The drive of a case, with the abdominal muscles off (the fit searches the rib-cage and
/// diaphragm waves only, thesis 4.3): quiet is A_ribs 0.2, A_diaphragm 0.25 at 0.25 Hz, the
/// diaphragm 0.1 rad ahead; forced is 0.5 / 0.5 at 0.2 Hz, the ribs 0.1 rad ahead. Both lie
/// in the range the thesis's fits found (Table 4.3) and are fixed here, apart from the
/// model's [`Drive::quiet`] and [`Drive::forced`] scenarios, so the acceptance cases do not
/// move when the scenarios are recalibrated.
pub fn case_drive(forced: bool) -> Drive {
    let (frequency, ribs, diaphragm, phase) = if forced {
        (0.2, 0.5, 0.5, -0.1)
    } else {
        (0.25, 0.2, 0.25, 0.1)
    };
    Drive {
        enabled: true,
        frequency,
        inspiratory_fraction: crate::model::drive::SINE_FRACTION,
        ribs: Wave {
            amplitude: ribs,
            phase: 0.0,
        },
        diaphragm: Wave {
            amplitude: diaphragm,
            phase,
        },
        abdominals: Wave::default(),
    }
}

/// Settings of a sweep.
#[derive(Clone, Debug, PartialEq)]
pub struct SweepOptions {
    /// Recording length [s] (18 in the acceptance).
    pub duration: f64,
    /// Level of detail of the model (synthesis and fit use the same).
    pub level_of_detail: u32,
    /// Solver relative tolerance.
    pub rtol: f64,
    /// The fit's settings.
    pub fit: FitOptions,
    /// Cases run at once (threads).
    pub jobs: usize,
}

impl Default for SweepOptions {
    fn default() -> Self {
        SweepOptions {
            duration: 18.0,
            level_of_detail: 0,
            rtol: 1e-6,
            fit: FitOptions::default(),
            jobs: 1,
        }
    }
}

/// The outcome of one case.
#[derive(Clone, Debug, PartialEq)]
pub struct SweepRow {
    /// The case.
    pub case: SweepCase,
    /// The recording and its truth.
    pub synthetic: Synthetic,
    /// The fitted drive.
    pub fitted: Drive,
    /// Fitted diaphragm minus rib-cage phase [rad].
    pub delta_phase: f64,
    /// Final cost [m].
    pub cost_m: f64,
    /// Evaluations (model runs choosing the parameters).
    pub evaluations: usize,
    /// Whether the optimiser met its tolerances.
    pub converged: bool,
    /// Wall time of the fit [s].
    pub wall_s: f64,
}

impl SweepRow {
    /// Relative error of the rib-cage amplitude.
    pub fn ribs_error(&self) -> f64 {
        rel(
            self.fitted.ribs.amplitude,
            self.synthetic.truth.ribs.amplitude,
        )
    }

    /// Relative error of the diaphragm amplitude.
    pub fn diaphragm_error(&self) -> f64 {
        rel(
            self.fitted.diaphragm.amplitude,
            self.synthetic.truth.diaphragm.amplitude,
        )
    }

    /// True phase difference (diaphragm minus rib cage) [rad].
    pub fn true_delta_phase(&self) -> f64 {
        let t = &self.synthetic.truth;
        wrap_angle(t.diaphragm.phase - t.ribs.phase)
    }

    /// Error of the phase difference [rad], wrapped.
    pub fn phase_error(&self) -> f64 {
        wrap_angle(self.delta_phase - self.true_delta_phase()).abs()
    }

    /// Relative error of the breathing frequency.
    pub fn frequency_error(&self) -> f64 {
        rel(self.fitted.frequency, self.synthetic.truth.frequency)
    }

    /// Final cost over the noise floor.
    pub fn cost_ratio(&self) -> f64 {
        self.cost_m / self.synthetic.noise_floor_m
    }

    /// The acceptance items this case fails (empty: all met).
    pub fn failures(&self) -> Vec<&'static str> {
        let mut f = Vec::new();
        if self.ribs_error() > ACCEPT_AMPLITUDE_REL {
            f.push("A_ribs");
        }
        if self.diaphragm_error() > ACCEPT_AMPLITUDE_REL {
            f.push("A_diaphragm");
        }
        if self.phase_error() > ACCEPT_PHASE_RAD {
            f.push("delta_phase");
        }
        if self.frequency_error() > ACCEPT_FREQUENCY_REL {
            f.push("frequency");
        }
        if self.cost_ratio() > ACCEPT_COST_OVER_FLOOR {
            f.push("cost");
        }
        if self.evaluations > ACCEPT_EVALUATIONS {
            f.push("evaluations");
        }
        f
    }
}

fn rel(a: f64, b: f64) -> f64 {
    if b == 0.0 {
        a.abs()
    } else {
        (a - b).abs() / b.abs()
    }
}

/// The model configuration of a case.
pub fn case_config(case: &SweepCase, options: &SweepOptions) -> Result<Config> {
    let mut c = Config {
        subject: case.subject.clone(),
        drive: case_drive(case.forced),
        ..Config::default()
    };
    c.scene.level_of_detail = options.level_of_detail;
    c.solver.rtol = options.rtol;
    c.validate()?;
    Ok(c)
}

/// Synthesises the recording of `case` (with a fresh model).
pub fn synthesize_case(case: &SweepCase, options: &SweepOptions) -> Result<Synthetic> {
    let mut source = TorsoMarkers::new(case_config(case, options)?)?;
    synthesize(
        &mut source,
        &SynthOptions {
            drive: case_drive(case.forced),
            duration: options.duration,
            seed: case.seed,
            ..SynthOptions::default()
        },
    )
}

/// Fits the recording of `case` with a freshly built model (the fit's wall time includes
/// building it).
pub fn fit_case(
    case: &SweepCase,
    synthetic: Synthetic,
    options: &SweepOptions,
) -> Result<SweepRow> {
    fit_case_with(case, synthetic, options, &mut |_, _| {})
}

/// [`fit_case`] calling `progress(evaluations, best cost)` after each cost evaluation.
pub fn fit_case_with(
    case: &SweepCase,
    synthetic: Synthetic,
    options: &SweepOptions,
    progress: &mut dyn FnMut(usize, f64),
) -> Result<SweepRow> {
    let start = std::time::Instant::now();
    let mut source = TorsoMarkers::new(case_config(case, options)?)?;
    let fit = fit_recording(&mut source, &synthetic.recording, &options.fit, progress)?;
    Ok(SweepRow {
        case: case.clone(),
        synthetic,
        fitted: fit.drive,
        delta_phase: fit.delta_phase,
        cost_m: fit.cost_m,
        evaluations: fit.evaluations,
        converged: fit.converged,
        wall_s: start.elapsed().as_secs_f64(),
    })
}

/// Runs every case (`options.jobs` at a time); `done(row)` is called as each finishes.
/// Rows come back in the order of `cases`.
pub fn run_sweep(
    cases: &[SweepCase],
    options: &SweepOptions,
    done: &(dyn Fn(&SweepRow) + Sync),
) -> Result<Vec<SweepRow>> {
    run_sweep_with(cases, options, done, &|_, _| {})
}

/// [`run_sweep`] calling `progress(case index, evaluations)` after each cost evaluation of
/// a case's fit (from the worker running it).
pub fn run_sweep_with(
    cases: &[SweepCase],
    options: &SweepOptions,
    done: &(dyn Fn(&SweepRow) + Sync),
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<Vec<SweepRow>> {
    if options.jobs == 0 {
        return Err(Error::invalid("--jobs", 0, "at least 1"));
    }
    let next = AtomicUsize::new(0);
    let results: Mutex<Vec<Option<Result<SweepRow>>>> =
        Mutex::new((0..cases.len()).map(|_| None).collect());
    std::thread::scope(|scope| {
        for _ in 0..options.jobs.min(cases.len()) {
            scope.spawn(|| {
                loop {
                    let i = next.fetch_add(1, Ordering::SeqCst);
                    let Some(case) = cases.get(i) else { break };
                    let row = synthesize_case(case, options)
                        .and_then(|s| fit_case_with(case, s, options, &mut |n, _| progress(i, n)));
                    if let Ok(r) = &row {
                        done(r);
                    }
                    if let Ok(mut all) = results.lock() {
                        all[i] = Some(row);
                    }
                }
            });
        }
    });
    let all = results
        .into_inner()
        .map_err(|_| Error::State("fit sweep: a worker panicked".into()))?;
    all.into_iter()
        .zip(cases)
        .map(|(r, c)| {
            r.unwrap_or_else(|| {
                Err(Error::State(format!(
                    "fit sweep: `{}` did not run",
                    c.label
                )))
            })
        })
        .collect()
}

/// The sweep as a Markdown table: truth and fit of each parameter with its error, cost
/// against the noise floor, evaluations, wall time and the failed items.
pub fn table(rows: &[SweepRow]) -> String {
    let mut s = String::from(
        "| case | A_ribs true / fit (err) | A_diaph true / fit (err) | dphi true / fit (err rad) | f true / fit (err) | cost / floor mm (ratio) | evals | wall s | fails |\n|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        let t = &r.synthetic.truth;
        let fails = r.failures();
        s += &format!(
            "| {} | {:.3} / {:.3} ({:.1} %) | {:.3} / {:.3} ({:.1} %) | {:+.3} / {:+.3} ({:.3}) | {:.4} / {:.4} ({:.2} %) | {:.3} / {:.3} ({:.3}) | {}{} | {:.1} | {} |\n",
            r.case.label,
            t.ribs.amplitude,
            r.fitted.ribs.amplitude,
            100.0 * r.ribs_error(),
            t.diaphragm.amplitude,
            r.fitted.diaphragm.amplitude,
            100.0 * r.diaphragm_error(),
            r.true_delta_phase(),
            r.delta_phase,
            r.phase_error(),
            t.frequency,
            r.fitted.frequency,
            100.0 * r.frequency_error(),
            r.cost_m * 1e3,
            r.synthetic.noise_floor_m * 1e3,
            r.cost_ratio(),
            r.evaluations,
            if r.converged { "" } else { "*" },
            r.wall_s,
            if fails.is_empty() {
                "-".to_string()
            } else {
                fails.join(", ")
            }
        );
    }
    s
}
