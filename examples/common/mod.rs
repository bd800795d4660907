//! Shared by the diagnostic examples: their command-line words and the second breath's
//! end-expiratory and end-inspiratory states.

use breathing_torso::dynamics::Params;
use breathing_torso::model::Drive;
use breathing_torso::{Config, Quantity, Torso};

/// The scenario named on the command line: `forced`, else quiet breathing.
pub fn drive_from_args() -> Drive {
    if std::env::args().any(|a| a == "forced") {
        Drive::forced()
    } else {
        Drive::quiet()
    }
}

/// The factor given as `<name>=<factor>` on the command line, 1 if absent.
pub fn factor_from_args(name: &str) -> f64 {
    let prefix = format!("{name}=");
    std::env::args()
        .find_map(|a| a.strip_prefix(&prefix).and_then(|f| f.parse().ok()))
        .unwrap_or(1.0)
}

/// The default subject upright with `drive`, its constants changed by `tune`.
pub fn torso_with(drive: Drive, tune: impl FnOnce(&mut Params)) -> Torso {
    let mut config = Config::default();
    if std::env::args().any(|a| a == "supine") {
        config.subject.posture = breathing_torso::anatomy::Posture::Supine;
    }
    if std::env::args().any(|a| a == "female") {
        config.subject.sex = breathing_torso::anatomy::Sex::Female;
        config.subject.stature = 1.63;
        config.subject.mass = 60.0;
        config.subject.breast_size = 0.4;
    }
    if let Some(s) = std::env::args().find_map(|a| a.strip_prefix("stature=")?.parse().ok()) {
        config.subject.stature = s;
    }
    let mut params = Params::for_posture(config.subject.posture);
    tune(&mut params);
    let config = Config {
        drive,
        params: Some(params),
        ..config
    };
    Torso::new(config).unwrap()
}

/// One end of a breath: lung volume [L], state, and the extra quantities asked for.
#[derive(Clone)]
pub struct BreathEnd {
    pub lung: f64,
    pub state: Vec<f64>,
    pub reads: Vec<f64>,
}

/// End-expiration (smallest lung volume) and end-inspiration (largest) of the second breath,
/// sampled at 56 Hz, with `reads` read at both.
pub fn second_breath(torso: &mut Torso, reads: &[Quantity]) -> (BreathEnd, BreathEnd) {
    let period = 1.0 / torso.config().drive.frequency;
    let rate = 56.0;
    let frames = (2.0 * period * rate).round() as usize;
    let end = |lung: f64| BreathEnd {
        lung,
        state: Vec::new(),
        reads: Vec::new(),
    };
    let (mut lo, mut hi) = (end(f64::INFINITY), end(f64::NEG_INFINITY));
    for i in 1..=frames {
        let t = i as f64 / rate;
        torso.advance_to(t).unwrap();
        if t < period - 1e-9 {
            continue;
        }
        let v = torso.read(Quantity::LungVolume).unwrap();
        let (low, high) = (v < lo.lung, v > hi.lung);
        if low || high {
            let here = BreathEnd {
                lung: v,
                state: torso.state().to_vec(),
                reads: reads.iter().map(|&q| torso.read(q).unwrap()).collect(),
            };
            if low {
                lo = here.clone();
            }
            if high {
                hi = here;
            }
        }
    }
    (lo, hi)
}
