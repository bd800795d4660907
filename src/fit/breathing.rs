//! Breath-by-breath timing of a recording, read off its principal displacement (the motion
//! common to the whole marker set, [`super::principal`]): breath onsets at the minima of the
//! low-passed signal, inspiration to its next maximum, expiration to the next minimum
//! ([`crate::stats::breaths::segment_breaths`]: hysteresis detector on a centred moving
//! average over 0.05 breathing periods). Extrema closer than 0.1 breathing periods are
//! merged, not the detector's default 0.3: with an inspiratory fraction down to 0.2 and
//! breaths down to half the mean period, an inspiration can last 0.1 periods, and the
//! default drops short breaths (seen: a 3.2 s breath of Ti/Ttot 0.42 in a 4.2 s rhythm). Per breath: Ti, Te, Ttot and Ti/Ttot, the indices the
//! SLP validation against pneumotachography compares (Motamedi-Fakhr et al. 2017, Physiol.
//! Rep. 5(3):e13124: breath-by-breath limits of agreement +-0.22 s for Ti, +-0.29 s for Te,
//! +-0.32 s for Ttot), and a depth (the breath's inspiratory swing over the median swing).
//! The median Ti/Ttot over the breaths estimates the drive's inspiratory
//! fraction: the model's lung volume follows its drive's Ti/Ttot within 0.014 over
//! 0.3-0.5 (docs/drive.md).

use crate::stats::breaths::{Breath, BreathDetector, segment_breaths};
use serde::Serialize;

/// The breaths of a recording.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct RecordingBreaths {
    /// Each whole breath (minimum, maximum, next minimum) of the principal displacement;
    /// indices and times are the recording's (times relative to its first frame).
    pub breaths: Vec<Breath>,
    /// Time of each breath's onset (its starting minimum) [s], relative to the first frame.
    pub onsets: Vec<f64>,
    /// Each breath's depth: its inspiratory swing of the principal displacement over the
    /// median swing (1: a median breath).
    pub depths: Vec<f64>,
    /// Median Ti/Ttot over the breaths; NaN without a whole breath.
    pub ti_ttot: f64,
}

/// Median of `x` (sorted in place); NaN when empty.
fn median(x: &mut [f64]) -> f64 {
    x.sort_by(f64::total_cmp);
    let n = x.len();
    match n {
        0 => f64::NAN,
        _ if n % 2 == 1 => x[n / 2],
        _ => 0.5 * (x[n / 2 - 1] + x[n / 2]),
    }
}

/// Segments `signal` (the principal displacement, signed so that inspiration is positive)
/// sampled at `times` into breaths, for a breathing frequency `frequency` [Hz].
pub fn breaths_of_signal(times: &[f64], signal: &[f64], frequency: f64) -> RecordingBreaths {
    let period = 1.0 / frequency;
    let detector = BreathDetector {
        min_distance_s: 0.1 * period,
        ..BreathDetector::for_period(period)
    };
    let breaths = segment_breaths(times, signal, &detector);
    let onsets = breaths.iter().map(|b| times[b.start]).collect();
    let ti_ttot = median(&mut breaths.iter().map(|b| b.ti_ttot).collect::<Vec<_>>());
    let swing = median(&mut breaths.iter().map(|b| b.tidal_volume).collect::<Vec<_>>());
    let depths = breaths.iter().map(|b| b.tidal_volume / swing).collect();
    RecordingBreaths {
        breaths,
        onsets,
        depths,
        ti_ttot,
    }
}
