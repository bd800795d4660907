//! The long stress items of `torso bench stress` and their fast versions in the test suite:
//! square waves of activation in every muscle group, maximal activation held, an hour of quiet
//! breathing with the end-expiratory lung volume of every breath (drift), and communication
//! steps from 1e-5 s to 2 s, fixed and random, against one long run. Each kernel returns
//! plain figures (serialisable); nothing here prints.
//!
//! Bounds are those of the random-scene soak ([`super::LUNG_BOUNDS`],
//! [`super::RELATIVE_VOLUME_BOUNDS`]): a finite state, a lung volume within broad adult
//! limits, and thorax, abdomen and trunk volumes within half and twice their start values (the
//! thorax's widened to the subject's residual volume and total lung capacity where those lie
//! beyond).

use super::{LUNG_BOUNDS, SceneOutcome, set_all_activations};
use crate::model::{AdvanceOptions, Config, Quantity, Torso};
use crate::numeric::rng::Pcg64;
use crate::{Error, Result};
use serde::Serialize;
use std::time::Instant;

/// Solver counters of one stress run.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Work {
    /// Wall time [s] (model build excluded).
    pub wall: f64,
    /// Accepted steps.
    pub steps: u64,
    /// Rejected steps.
    pub rejected: u64,
    /// Right-hand-side evaluations.
    pub rhs_evaluations: u64,
    /// Accepted steps at which the explicit solver's stiffness test fired.
    pub stiff_steps: u64,
}

fn work(torso: &Torso, start: Instant) -> Work {
    let s = torso.solver_stats();
    Work {
        wall: start.elapsed().as_secs_f64(),
        steps: s.steps,
        rejected: s.rejected,
        rhs_evaluations: s.rhs_evaluations,
        stiff_steps: s.stiff_steps,
    }
}

/// Watches a run: after every advance, the state must be finite, the lung volume within
/// [`LUNG_BOUNDS`] and every cavity within its subject's bounds of its start value
/// ([`super::RELATIVE_VOLUME_BOUNDS`], the thorax's widened to the residual volume and total lung
/// capacity).
/// Keeps the extremes seen.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Monitor {
    /// Thorax, abdomen and trunk volumes at the start [L].
    pub start: [f64; 3],
    /// Smallest and largest lung volume seen [L].
    pub lung: (f64, f64),
    /// Smallest and largest ratio of each cavity to its start value (thorax, abdomen, trunk).
    pub ratios: [(f64, f64); 3],
    /// Checks made.
    pub checks: u64,
    /// Bounds of each cavity's ratio (the subject's: `model::bounds::cavity_bounds`).
    pub bounds: [(f64, f64); 3],
}

const CAVITIES: [Quantity; 3] = [
    Quantity::ThoraxVolume,
    Quantity::AbdomenVolume,
    Quantity::TrunkVolume,
];

impl Monitor {
    /// Starts watching `torso` from its current state.
    pub fn new(torso: &mut Torso) -> Result<Monitor> {
        let mut start = [0.0; 3];
        for (s, q) in start.iter_mut().zip(CAVITIES) {
            *s = torso.read(q)?;
        }
        Ok(Monitor {
            start,
            lung: (f64::INFINITY, f64::NEG_INFINITY),
            ratios: [(f64::INFINITY, f64::NEG_INFINITY); 3],
            checks: 0,
            bounds: crate::model::bounds::cavity_bounds(&torso.config().subject),
        })
    }

    /// Checks the current state; `Some(outcome)` on the first violation.
    pub fn check(&mut self, torso: &mut Torso) -> Result<Option<SceneOutcome>> {
        self.checks += 1;
        let time = torso.time();
        let out = |what: String| Ok(Some(SceneOutcome::OutOfBounds { time, what }));
        if torso.state().iter().any(|v| !v.is_finite()) {
            return out("non-finite state".into());
        }
        let lung = torso.read(Quantity::LungVolume)?;
        if !(lung.is_finite() && lung >= LUNG_BOUNDS.0 && lung <= LUNG_BOUNDS.1) {
            return out(format!(
                "LungVolume = {lung} L outside [{}, {}] L",
                LUNG_BOUNDS.0, LUNG_BOUNDS.1
            ));
        }
        self.lung = (self.lung.0.min(lung), self.lung.1.max(lung));
        for (k, q) in CAVITIES.into_iter().enumerate() {
            let v = torso.read(q)?;
            let r = v / self.start[k];
            let (lo, hi) = self.bounds[k];
            if !(r.is_finite() && r >= lo && r <= hi) {
                return out(format!(
                    "{q:?} = {v} L, {r} x its start value {} L, outside [{lo:.3}, {hi:.3}] x",
                    self.start[k]
                ));
            }
            self.ratios[k] = (self.ratios[k].0.min(r), self.ratios[k].1.max(r));
        }
        Ok(None)
    }

    /// Advances `torso` to `t` with the facade's physiological check (the one the FMU and
    /// the C ABI step with: a step it rolls back ends the run out of bounds, as the FMU would
    /// discard it), then checks against the start; a solver failure or a violation ends the
    /// run.
    pub fn advance(&mut self, torso: &mut Torso, t: f64) -> Result<Option<SceneOutcome>> {
        let options = AdvanceOptions {
            check_physiology: true,
        };
        match torso.advance_to_with(t, options) {
            Ok(_) => self.check(torso),
            Err(Error::Unphysiological { at, reason, .. }) => Ok(Some(SceneOutcome::OutOfBounds {
                time: at,
                what: reason,
            })),
            Err(Error::Numerical { time, reason }) => Ok(Some(SceneOutcome::Numerical(format!(
                "t = {time} s: {reason}"
            )))),
            Err(e) => Err(e),
        }
    }

    /// The outcome of a run that ended without violation.
    fn ok(&self) -> SceneOutcome {
        SceneOutcome::Ok {
            min_lung: self.lung.0,
            max_lung: self.lung.1,
        }
    }
}

/// Result of an activation stress run (square waves or a held maximal activation).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ActivationRun {
    /// Simulated seconds under the stress (after the rest period).
    pub seconds: f64,
    /// Lung volume at rest, before the stress [L].
    pub rest_lung: f64,
    /// Lung volume at the end [L] (at the last good time on failure).
    pub end_lung: f64,
    /// How the run ended.
    pub outcome: SceneOutcome,
    /// Extremes seen.
    pub monitor: Monitor,
    /// Solver work of the whole run.
    pub work: Work,
}

/// Rest period before an activation stress starts [s] (the model settles under gravity).
pub const REST: f64 = 0.5;

/// Every muscle group switched between no and full activation at once, a square wave of
/// `frequency` Hz held for `seconds` after [`REST`] s at rest; the state is checked at every
/// switch and at least every `1 / check_rate` s.
pub fn square_waves(
    config: &Config,
    seconds: f64,
    frequency: f64,
    check_rate: f64,
) -> Result<ActivationRun> {
    if !(frequency > 0.0 && frequency.is_finite() && check_rate > 0.0 && seconds > 0.0) {
        return Err(Error::invalid(
            "square wave frequency/check rate/seconds",
            frequency,
            "> 0",
        ));
    }
    let mut torso = Torso::new(config.clone())?;
    let start = Instant::now();
    torso.advance_to(REST)?;
    let rest_lung = torso.read(Quantity::LungVolume)?;
    let mut monitor = Monitor::new(&mut torso)?;
    let half = 0.5 / frequency;
    let switches = (seconds / half).round().max(1.0) as usize;
    let sub = (half * check_rate).ceil().max(1.0) as usize;
    let mut outcome = None;
    'run: for k in 0..switches {
        set_all_activations(&mut torso, if k % 2 == 0 { 1.0 } else { 0.0 })?;
        let t0 = REST + k as f64 * half;
        for j in 1..=sub {
            let t = t0 + half * j as f64 / sub as f64;
            if let Some(o) = monitor.advance(&mut torso, t)? {
                outcome = Some(o);
                break 'run;
            }
        }
    }
    Ok(ActivationRun {
        seconds,
        rest_lung,
        end_lung: torso.read(Quantity::LungVolume)?,
        outcome: outcome.unwrap_or_else(|| monitor.ok()),
        monitor,
        work: work(&torso, start),
    })
}

/// Every muscle group stepped to full activation at once after [`REST`] s and held for
/// `seconds`, checked at `check_rate` Hz.
pub fn held_maximal(config: &Config, seconds: f64, check_rate: f64) -> Result<ActivationRun> {
    if !(check_rate > 0.0 && seconds > 0.0) {
        return Err(Error::invalid("check rate/seconds", check_rate, "> 0"));
    }
    let mut torso = Torso::new(config.clone())?;
    let start = Instant::now();
    torso.advance_to(REST)?;
    let rest_lung = torso.read(Quantity::LungVolume)?;
    let mut monitor = Monitor::new(&mut torso)?;
    set_all_activations(&mut torso, 1.0)?;
    let frames = (seconds * check_rate).round().max(1.0) as usize;
    let mut outcome = None;
    for i in 1..=frames {
        if let Some(o) = monitor.advance(&mut torso, REST + i as f64 / check_rate)? {
            outcome = Some(o);
            break;
        }
    }
    Ok(ActivationRun {
        seconds,
        rest_lung,
        end_lung: torso.read(Quantity::LungVolume)?,
        outcome: outcome.unwrap_or_else(|| monitor.ok()),
        monitor,
        work: work(&torso, start),
    })
}

/// One breath of a long run.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Breath {
    /// Time of the end-expiratory minimum [s].
    pub time: f64,
    /// End-expiratory lung volume [L] (the breath's minimum, refined by a parabola through
    /// the three samples around it).
    pub end_expiratory: f64,
    /// Largest lung volume within the half breath either side [L].
    pub peak: f64,
}

/// The breaths of a long quiet run and the drift of their end-expiratory volume.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Drift {
    /// Simulated seconds.
    pub seconds: f64,
    /// Breathing frequency [Hz].
    pub frequency: f64,
    /// Sampling rate of the lung volume [Hz].
    pub rate: f64,
    /// Every complete breath, in time order.
    pub breaths: Vec<Breath>,
    /// (last - first) / first end-expiratory volume.
    pub first_to_last: f64,
    /// Largest |EEV_k - EEV_first| / EEV_first over all breaths.
    pub max_deviation: f64,
    /// Least-squares slope of the end-expiratory volume, relative to the first, per hour.
    pub slope_per_hour: f64,
    /// How the run ended (bounds are checked at every sample).
    pub outcome: SceneOutcome,
    /// Solver work.
    pub work: Work,
}

/// Minima of `v` (sampled at `rate` Hz) that are the smallest value within half a `period`
/// either side, each refined by a parabola through its neighbours; with the largest value
/// of the same window. Minima closer than a full half-window to either end are skipped.
pub fn breath_minima(v: &[f64], rate: f64, period: f64) -> Vec<Breath> {
    let half = ((0.5 * period * rate).round() as usize).max(1);
    let mut out = Vec::new();
    if v.len() < 2 * half + 1 {
        return out;
    }
    for i in half..v.len() - half {
        let window = &v[i - half..=i + half];
        let is_min = window
            .iter()
            .enumerate()
            .all(|(j, &w)| if j < half { w > v[i] } else { w >= v[i] });
        if !is_min {
            continue;
        }
        let (a, b, c) = (v[i - 1], v[i], v[i + 1]);
        let curvature = a - 2.0 * b + c;
        let (dt, value) = if curvature > 0.0 {
            let shift = 0.5 * (a - c) / curvature;
            (shift, b - 0.125 * (c - a) * (c - a) / curvature)
        } else {
            (0.0, b)
        };
        let peak = window.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        out.push(Breath {
            time: (i as f64 + dt) / rate,
            end_expiratory: value,
            peak,
        });
    }
    out
}

/// Quiet breathing (`config`'s drive) for `seconds`, lung volume sampled at `rate` Hz and
/// checked against the bounds at every sample; the end-expiratory volume of every breath and
/// its drift.
pub fn quiet_drift(config: &Config, seconds: f64, rate: f64) -> Result<Drift> {
    if !(seconds > 0.0 && rate > 0.0 && seconds.is_finite() && rate.is_finite()) {
        return Err(Error::invalid("drift seconds/rate", seconds, "> 0"));
    }
    let frequency = config.drive.frequency;
    let mut torso = Torso::new(config.clone())?;
    let start = Instant::now();
    let mut monitor = Monitor::new(&mut torso)?;
    let frames = (seconds * rate).round() as usize;
    let mut lung = Vec::with_capacity(frames + 1);
    lung.push(torso.read(Quantity::LungVolume)?);
    let mut outcome = None;
    for i in 1..=frames {
        if let Some(o) = monitor.advance(&mut torso, i as f64 / rate)? {
            outcome = Some(o);
            break;
        }
        lung.push(torso.read(Quantity::LungVolume)?);
    }
    let breaths = breath_minima(&lung, rate, 1.0 / frequency);
    let (first_to_last, max_deviation, slope_per_hour) = match (breaths.first(), breaths.last()) {
        (Some(f), Some(l)) if breaths.len() >= 2 => {
            let e0 = f.end_expiratory;
            let max_dev = breaths
                .iter()
                .map(|b| (b.end_expiratory - e0).abs() / e0)
                .fold(0.0, f64::max);
            let n = breaths.len() as f64;
            let mt = breaths.iter().map(|b| b.time).sum::<f64>() / n;
            let mv = breaths.iter().map(|b| b.end_expiratory).sum::<f64>() / n;
            let sxy: f64 = breaths
                .iter()
                .map(|b| (b.time - mt) * (b.end_expiratory - mv))
                .sum();
            let sxx: f64 = breaths.iter().map(|b| (b.time - mt).powi(2)).sum();
            let slope = if sxx > 0.0 { sxy / sxx } else { 0.0 };
            ((l.end_expiratory - e0) / e0, max_dev, slope * 3600.0 / e0)
        }
        _ => (f64::NAN, f64::NAN, f64::NAN),
    };
    Ok(Drift {
        seconds,
        frequency,
        rate,
        breaths,
        first_to_last,
        max_deviation,
        slope_per_hour,
        outcome: outcome.unwrap_or_else(|| monitor.ok()),
        work: work(&torso, start),
    })
}

/// Final state of one stepped run compared with the reference.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SteppedRun {
    /// What the steps were (`"h = 1e-5 s"`, `"random sequence 3"`).
    pub label: String,
    /// Communication steps taken (calls of `advance_to`).
    pub calls: usize,
    /// Smallest and largest step of the sequence [s].
    pub step_range: (f64, f64),
    /// Lung volume at the end [L].
    pub lung: f64,
    /// |lung - reference| / reference.
    pub lung_relative: f64,
    /// Max over the state of |y - y_ref| / (atol + rtol |y_ref|) with the run's tolerances:
    /// 1 is the size of error one solver step is allowed.
    pub state_error: f64,
    /// Solver work.
    pub work: Work,
}

/// Runs `config` to `end` through the communication points `points` (increasing, the last
/// equal to `end`) and compares the final state with `reference` (state vector, lung volume).
fn stepped(
    config: &Config,
    label: String,
    points: &[f64],
    reference: &(Vec<f64>, f64),
) -> Result<SteppedRun> {
    let mut torso = Torso::new(config.clone())?;
    let start = Instant::now();
    let mut previous = 0.0;
    let (mut lo, mut hi) = (f64::INFINITY, 0.0f64);
    for &t in points {
        lo = lo.min(t - previous);
        hi = hi.max(t - previous);
        previous = t;
        torso.advance_to(t)?;
    }
    let lung = torso.read(Quantity::LungVolume)?;
    let (rtol, atol) = (config.solver.rtol, config.solver.atol);
    let state_error = torso
        .state()
        .iter()
        .zip(&reference.0)
        .map(|(y, r)| (y - r).abs() / (atol + rtol * r.abs()))
        .fold(0.0, f64::max);
    Ok(SteppedRun {
        label,
        calls: points.len(),
        step_range: (lo, hi),
        lung,
        lung_relative: (lung - reference.1).abs() / reference.1,
        state_error,
        work: work(&torso, start),
    })
}

/// The reference for [`communication_steps`]: one call from 0 to `end`.
pub fn one_long_run(config: &Config, end: f64) -> Result<(Vec<f64>, f64, Work)> {
    let mut torso = Torso::new(config.clone())?;
    let start = Instant::now();
    torso.advance_to(end)?;
    let lung = torso.read(Quantity::LungVolume)?;
    Ok((torso.state().to_vec(), lung, work(&torso, start)))
}

/// Runs `config` from 0 to `end` with each fixed communication step of `steps` (each must
/// divide `end` to within 1e-9) and compares the final state with one call to `end`.
pub fn communication_steps(config: &Config, end: f64, steps: &[f64]) -> Result<Vec<SteppedRun>> {
    let (state, lung, _) = one_long_run(config, end)?;
    let reference = (state, lung);
    steps
        .iter()
        .map(|&h| {
            let n = (end / h).round();
            if !(h > 0.0 && n >= 1.0 && (n * h - end).abs() <= 1e-9 * end) {
                return Err(Error::invalid(
                    "communication step",
                    h,
                    format!("a divisor of the run's end time {end} s"),
                ));
            }
            let n = n as usize;
            let points: Vec<f64> = (1..=n)
                .map(|i| if i == n { end } else { i as f64 * h })
                .collect();
            stepped(config, format!("h = {h:e} s"), &points, &reference)
        })
        .collect()
}

/// Communication points from 0 to `end` with steps drawn log-uniformly in [`lo`, `hi`]
/// seconds (the last step cut at `end`).
pub fn random_points(rng: &mut Pcg64, end: f64, lo: f64, hi: f64) -> Vec<f64> {
    let (a, b) = (lo.ln(), hi.ln());
    let mut points = Vec::new();
    let mut t = 0.0;
    while t < end {
        let h = (a + (b - a) * rng.uniform()).exp();
        t = (t + h).min(end);
        points.push(t);
    }
    points
}

/// `sequences` runs of `config` from 0 to `end` through random communication points (steps
/// log-uniform in [`lo`, `hi`] s, seeded), each compared with one call to `end`.
pub fn random_steps(
    config: &Config,
    end: f64,
    sequences: usize,
    (lo, hi): (f64, f64),
    seed: u64,
) -> Result<Vec<SteppedRun>> {
    if !(lo > 0.0 && hi >= lo && end > 0.0) {
        return Err(Error::invalid("random step range", lo, "0 < lo <= hi"));
    }
    let (state, lung, _) = one_long_run(config, end)?;
    let reference = (state, lung);
    let mut rng = Pcg64::new(seed, 7);
    (0..sequences)
        .map(|k| {
            let points = random_points(&mut rng, end, lo, hi);
            stepped(config, format!("random sequence {k}"), &points, &reference)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn breath_minima_find_one_refined_minimum_per_period() {
        let rate = 50.0;
        let period = 4.0;
        let v: Vec<f64> = (0..(20.0 * rate) as usize)
            .map(|i| {
                let t = i as f64 / rate;
                3.0 + 0.25 * (1.0 - (2.0 * std::f64::consts::PI * (t - 1.013) / period).cos())
                    + 1e-4 * t
            })
            .collect();
        let b = breath_minima(&v, rate, period);
        // minima at 1.013 + 4k; the first is within half a period of the start: skipped
        let times: Vec<f64> = b.iter().map(|b| b.time).collect();
        assert_eq!(b.len(), 4, "{times:?}");
        for (k, br) in b.iter().enumerate() {
            let t = 1.013 + 4.0 * (k + 1) as f64;
            assert!((br.time - t).abs() < 2e-3, "{} vs {t}", br.time);
            assert!((br.end_expiratory - (3.0 + 1e-4 * t)).abs() < 1e-5);
            assert!((br.peak - 3.5).abs() < 2e-3, "{}", br.peak);
        }
    }

    #[test]
    fn random_points_increase_to_the_end_within_the_range() {
        let mut rng = Pcg64::new(3, 1);
        let p = random_points(&mut rng, 2.0, 1e-5, 0.5);
        assert_eq!(*p.last().expect("points"), 2.0);
        let mut prev = 0.0;
        for &t in &p {
            assert!(t > prev && t - prev <= 0.5 + 1e-12);
            prev = t;
        }
    }
}
