//! Public recordings of human breathing with chest markers, made by other laboratories
//! (data/real/README.md): read through the library's recording reader and checked for what
//! their sources state (marker count and labels, unit, frame rate, duration, a spectral peak
//! in the breathing band), then fitted by `torso fit` with its defaults.
//!
//! What a fit of a real recording must do regardless of its figures (issue 33, deliverable
//! 7): read the file, bind the markers in the right pose (the front markers on the model's
//! front), complete, and report the variance explained. Those are asserted. The figures
//! themselves (variance explained, tidal volume, breath timing against a breath detection
//! independent of the fit) are printed, not bounded: the issue asks for them "whatever the
//! figures are"; docs/recordings.md ("Real recordings") lists them with this command:
//!
//!     cargo test --release --test real_recordings -- --nocapture

use breathing_torso::recording::Units;
use breathing_torso::recording::{Format, Markers, ReadOptions};
use nalgebra::{Matrix3, Vector3};
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::Command;

/// The breathing band the spectral checks use: 0.1-0.7 Hz (6-42 breaths per minute), wide
/// around the adult resting rate of 12-20 breaths per minute.
const BAND_HZ: (f64, f64) = (0.1, 0.7);

/// Motion slower than this is drift or sway, not breathing, and is left out of the spectrum
/// (below the band's lower edge by a factor of two).
const DRIFT_HZ: f64 = 0.05;

/// The fewest markers `torso fit` registers to the skin (`MIN_SURFACE_MARKERS`).
const MIN_MARKERS: usize = 12;

fn real_file(rel: &str) -> PathBuf {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("data/real")
        .join(rel);
    assert!(
        path.is_file(),
        "{} is absent (data/real/README.md says how it was made)",
        path.display()
    );
    path
}

fn read(path: &Path) -> Markers {
    Markers::read(path, &ReadOptions::default())
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// Runs `torso fit` with its defaults at level of detail 0 on one thread; the exit status,
/// stderr and stdout, and the result JSON when the fit completed.
fn fit_with_defaults(path: &Path, name: &str) -> (bool, String, Option<Value>) {
    let dir = std::env::temp_dir().join(format!("real_recordings_{}_{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let json = dir.join("result.json");
    let out = Command::new(env!("CARGO_BIN_EXE_torso"))
        .arg("fit")
        .arg("--slp")
        .arg(path)
        .args(["--lod", "0", "--threads", "1", "--out"])
        .arg(&json)
        .output()
        .expect("run torso fit");
    let text =
        String::from_utf8_lossy(&out.stderr).into_owned() + &String::from_utf8_lossy(&out.stdout);
    let result = out.status.success().then(|| {
        serde_json::from_str(&std::fs::read_to_string(&json).expect("result JSON written"))
            .expect("result JSON parses")
    });
    (out.status.success(), text, result)
}

fn num(v: &Value, path: &[&str]) -> f64 {
    let mut x = v;
    for k in path {
        x = &x[*k];
    }
    x.as_f64()
        .unwrap_or_else(|| panic!("result JSON: {} is not a number: {x}", path.join(".")))
}

/// Power of the linearly detrended coordinate series, summed over every marker coordinate,
/// at frequencies from `DRIFT_HZ` to 2 Hz in steps of 1/(4 x duration); missing samples are
/// left out of the sums (a direct, non-uniform DFT at the frame times).
fn motion_spectrum(m: &Markers) -> Vec<(f64, f64)> {
    let t = &m.times;
    let duration = m.duration();
    let step = 0.25 / duration;
    let top = 2.0_f64.min(0.5 * m.rate());
    let freqs: Vec<f64> = (0..)
        .map(|k| DRIFT_HZ + k as f64 * step)
        .take_while(|f| *f <= top)
        .collect();
    let mut power = vec![0.0; freqs.len()];
    for k in 0..m.markers() {
        for axis in 0..3 {
            let samples: Vec<(f64, f64)> = m
                .frames
                .iter()
                .zip(t)
                .filter_map(|(f, &ti)| f[k].map(|p| (ti, p[axis])))
                .collect();
            let n = samples.len() as f64;
            let tm = samples.iter().map(|s| s.0).sum::<f64>() / n;
            let ym = samples.iter().map(|s| s.1).sum::<f64>() / n;
            let stt = samples.iter().map(|s| (s.0 - tm).powi(2)).sum::<f64>();
            let sty = samples.iter().map(|s| (s.0 - tm) * (s.1 - ym)).sum::<f64>();
            let slope = sty / stt;
            for (j, f) in freqs.iter().enumerate() {
                let w = 2.0 * std::f64::consts::PI * f;
                let (mut re, mut im) = (0.0, 0.0);
                for &(ti, yi) in &samples {
                    let r = yi - ym - slope * (ti - tm);
                    re += r * (w * ti).cos();
                    im += r * (w * ti).sin();
                }
                power[j] += (re * re + im * im) / (n * n);
            }
        }
    }
    freqs.into_iter().zip(power).collect()
}

/// Frequency of the largest spectral peak and the fraction of the power (above `DRIFT_HZ`)
/// that lies in the breathing band.
fn breathing_peak(m: &Markers) -> (f64, f64) {
    let spectrum = motion_spectrum(m);
    let (f_peak, _) = spectrum
        .iter()
        .copied()
        .fold((0.0, f64::MIN), |a, b| if b.1 > a.1 { b } else { a });
    let total: f64 = spectrum.iter().map(|s| s.1).sum();
    let band: f64 = spectrum
        .iter()
        .filter(|s| s.0 >= BAND_HZ.0 && s.0 <= BAND_HZ.1)
        .map(|s| s.1)
        .sum();
    (f_peak, band / total)
}

/// Largest peak-to-peak range [m] of any marker coordinate over the recording.
fn largest_excursion(m: &Markers) -> f64 {
    let mut best: f64 = 0.0;
    for k in 0..m.markers() {
        for axis in 0..3 {
            let v: Vec<f64> = m
                .frames
                .iter()
                .filter_map(|f| f[k].map(|p| p[axis]))
                .collect();
            let (lo, hi) = v
                .iter()
                .fold((f64::MAX, f64::MIN), |(a, b), &x| (a.min(x), b.max(x)));
            best = best.max(hi - lo);
        }
    }
    best
}

/// One breath of a breathing signal: onset (end-expiratory minimum) [s], inspiratory time
/// (to the next maximum) and expiratory time (to the next minimum) [s].
#[derive(Clone, Copy, Debug)]
struct Breath {
    onset: f64,
    ti: f64,
    te: f64,
}

impl Breath {
    fn ttot(&self) -> f64 {
        self.ti + self.te
    }
}

/// Breaths of a scalar signal that rises on inspiration, detected on their own, independently
/// of the fit: the signal smoothed by a centred moving average of `smooth_s`, then its
/// alternating extremes with hysteresis (a maximum is taken once the signal has fallen by
/// `hysteresis` of its 5-95 % range below it, a minimum once it has risen that much above
/// it). Extremes within half a smoothing window of either end are left out (a recording's
/// ends are not turning points); a breath runs from a minimum through a maximum to the next
/// minimum.
fn detect_breaths(t: &[f64], s: &[f64], smooth_s: f64, hysteresis: f64) -> Vec<Breath> {
    let n = s.len();
    let dt = (t[n - 1] - t[0]) / (n - 1) as f64;
    let half = ((0.5 * smooth_s / dt).round() as usize).max(1);
    let sm: Vec<f64> = (0..n)
        .map(|i| {
            let (a, b) = (i.saturating_sub(half), (i + half).min(n - 1));
            s[a..=b].iter().sum::<f64>() / (b - a + 1) as f64
        })
        .collect();
    let mut sorted = sm.clone();
    sorted.sort_by(f64::total_cmp);
    let h = hysteresis * (sorted[n * 95 / 100] - sorted[n * 5 / 100]);
    // (index, is maximum)
    let mut extremes: Vec<(usize, bool)> = Vec::new();
    let (mut lo, mut hi) = (0, 0);
    let mut looking: Option<bool> = None; // Some(true): looking for a maximum
    let mut ext = 0;
    for i in 1..n {
        match looking {
            None => {
                if sm[i] < sm[lo] {
                    lo = i;
                }
                if sm[i] > sm[hi] {
                    hi = i;
                }
                if sm[i] - sm[lo] > h {
                    extremes.push((lo, false));
                    looking = Some(true);
                    ext = i;
                } else if sm[hi] - sm[i] > h {
                    extremes.push((hi, true));
                    looking = Some(false);
                    ext = i;
                }
            }
            Some(true) => {
                if sm[i] > sm[ext] {
                    ext = i;
                } else if sm[ext] - sm[i] > h {
                    extremes.push((ext, true));
                    looking = Some(false);
                    ext = i;
                }
            }
            Some(false) => {
                if sm[i] < sm[ext] {
                    ext = i;
                } else if sm[i] - sm[ext] > h {
                    extremes.push((ext, false));
                    looking = Some(true);
                    ext = i;
                }
            }
        }
    }
    extremes.retain(|&(i, _)| i > half && i + half < n - 1);
    extremes
        .windows(3)
        .filter(|w| !w[0].1 && w[1].1 && !w[2].1)
        .map(|w| Breath {
            onset: t[w[0].0],
            ti: t[w[1].0] - t[w[0].0],
            te: t[w[2].0] - t[w[1].0],
        })
        .collect()
}

fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len() as f64
}

/// Area [m^2] of a closed polygon of points projected on the horizontal (x, y) plane.
fn horizontal_area(points: &[Vector3<f64>]) -> f64 {
    let n = points.len();
    0.5 * (0..n)
        .map(|i| {
            let (a, b) = (points[i], points[(i + 1) % n]);
            a.x * b.y - b.x * a.y
        })
        .sum::<f64>()
        .abs()
}

/// The fitted model's breaths from the result JSON.
fn fitted_breaths(result: &Value) -> Vec<Breath> {
    result["breaths"]
        .as_array()
        .expect("result JSON: breaths")
        .iter()
        .map(|b| Breath {
            onset: num(b, &["onset_s"]),
            ti: num(b, &["ti_s"]),
            te: num(b, &["te_s"]),
        })
        .collect()
}

/// Prints the independent breaths, the fitted ones, and for each independent breath the
/// fitted breath whose onset is nearest (onset, Ti, Te and Ttot differences, fit minus
/// independent). Returns the mean absolute differences of Ti, Te and Ttot.
fn compare_timing(name: &str, independent: &[Breath], fitted: &[Breath]) -> [f64; 3] {
    eprintln!("{name}: independent breaths (onset, Ti, Te, Ttot [s]):");
    for b in independent {
        eprintln!(
            "  {:7.2} {:6.2} {:6.2} {:6.2}",
            b.onset,
            b.ti,
            b.te,
            b.ttot()
        );
    }
    eprintln!("{name}: fitted breaths (onset, Ti, Te, Ttot [s]):");
    for b in fitted {
        eprintln!(
            "  {:7.2} {:6.2} {:6.2} {:6.2}",
            b.onset,
            b.ti,
            b.te,
            b.ttot()
        );
    }
    let mut diffs = [Vec::new(), Vec::new(), Vec::new()];
    for b in independent {
        let f = fitted
            .iter()
            .min_by(|x, y| {
                (x.onset - b.onset)
                    .abs()
                    .total_cmp(&(y.onset - b.onset).abs())
            })
            .expect("a fitted breath");
        eprintln!(
            "{name}: breath at {:.2} s: nearest fitted onset {:+.2} s, Ti {:+.2} s, Te {:+.2} s, Ttot {:+.2} s",
            b.onset,
            f.onset - b.onset,
            f.ti - b.ti,
            f.te - b.te,
            f.ttot() - b.ttot()
        );
        diffs[0].push((f.ti - b.ti).abs());
        diffs[1].push((f.te - b.te).abs());
        diffs[2].push((f.ttot() - b.ttot()).abs());
    }
    let d = diffs.map(|v| mean(&v));
    eprintln!(
        "{name}: mean |fit - independent|: Ti {:.2} s, Te {:.2} s, Ttot {:.2} s over {} breaths",
        d[0],
        d[1],
        d[2],
        independent.len()
    );
    d
}

/// Prints what the fit reports of the variance explained and asserts it is reported.
fn report_variance(name: &str, result: &Value) {
    let q = &result["quality"]["variance_explained"];
    let overall = num(q, &["overall"]);
    let above = num(q, &["above_noise"]);
    let (sway, drift, drive) = (
        num(q, &["split", "sway"]),
        num(q, &["split", "drift"]),
        num(q, &["split", "drive"]),
    );
    let per_marker: Vec<f64> = q["per_marker"]
        .as_array()
        .expect("per-marker variance explained")
        .iter()
        .map(|v| v.as_f64().expect("a number"))
        .collect();
    for v in [overall, above, sway, drift, drive]
        .iter()
        .chain(&per_marker)
    {
        assert!(v.is_finite() && *v <= 1.0, "{name}: variance explained {v}");
    }
    assert_eq!(
        per_marker.len(),
        num(result, &["marker_set", "markers_bound"]) as usize,
        "{name}: one variance explained per bound marker"
    );
    assert!(
        result["quality"]["explains_recording"].is_boolean(),
        "{name}: the report says whether the model explains the recording"
    );
    let (lo, hi) = per_marker
        .iter()
        .fold((f64::MAX, f64::MIN), |(a, b), &x| (a.min(x), b.max(x)));
    eprintln!(
        "{name}: variance explained overall {:.1} % ({:.1} % above the noise); sway {:.1} % of the recorded motion, drift {:.1} % of the rest, drive {:.1} % of what is left; per marker {:.1} to {:.1} %; explains the recording: {}",
        100.0 * overall,
        100.0 * above,
        100.0 * sway,
        100.0 * drift,
        100.0 * drive,
        100.0 * lo,
        100.0 * hi,
        result["quality"]["explains_recording"]
    );
}

/// ChestVolume 1.0.1 `sample_data` (Kwong 2025, MIT): 30 markers M01-M30 in millimetres,
/// 2309 frames without a stated rate (converted at an assumed 100 Hz, recorded in the file
/// as `rate_assumed`).
#[test]
fn chestvolume_sample_is_the_published_recording() {
    let path = real_file("chestvolume/chestvolume_sample.csv");
    let m = read(&path);
    assert_eq!(m.format, Format::MarkerCsv);
    assert_eq!(m.units, Units::Millimetres);
    // The package's documentation: "2309 time frames and 30 markers", labelled M01..M30.
    assert_eq!(m.markers(), 30);
    let expected: Vec<String> = (1..=30).map(|k| format!("M{k:02}")).collect();
    assert_eq!(m.labels, expected);
    assert_eq!(m.times.len(), 2309);
    assert_eq!(m.missing_per_marker(), vec![0; 30]);
    // The rate is the assumed one written by the converter, and the duration follows.
    let assumed: f64 = m
        .provenance_value("rate_assumed")
        .and_then(|v| v.split_whitespace().next())
        .and_then(|v| v.parse().ok())
        .expect("rate_assumed provenance line");
    assert!(
        (m.rate() - assumed).abs() < 1e-9 * assumed,
        "rate {}",
        m.rate()
    );
    assert!((m.duration() - 2308.0 / assumed).abs() < 1e-9);
    // Millimetres read as metres: a laboratory volume of a few metres, not kilometres.
    let far = m
        .frames
        .iter()
        .flatten()
        .flatten()
        .map(|p| p.coords.amax())
        .fold(0.0, f64::max);
    assert!(far < 5.0, "a coordinate {far} m from the lab origin");
    let (f_peak, in_band) = breathing_peak(&m);
    eprintln!(
        "chestvolume: peak {f_peak:.3} Hz at the assumed {assumed} Hz, {:.0} % of the motion power in {}-{} Hz, largest excursion {:.1} mm",
        100.0 * in_band,
        BAND_HZ.0,
        BAND_HZ.1,
        1e3 * largest_excursion(&m)
    );
    assert!(
        (BAND_HZ.0..=BAND_HZ.1).contains(&f_peak),
        "the largest motion peak is at {f_peak:.3} Hz, outside the breathing band {BAND_HZ:?}"
    );
    assert!(
        in_band > 0.5,
        "only {:.0} % of the marker motion lies in the breathing band",
        100.0 * in_band
    );
}

/// The ChestVolume markers stand in ten vertical lines of three (`M01-M03`, `M04-M06`, ...,
/// each top to bottom) around the trunk; the package names `M01`-`M18` (lines 1 to 6) the
/// left half, so lines 1 and 6 are the midlines and lines 2-5 the subject's left. With the
/// laboratory's Z vertical (head up), the subject's front is left x up. Returns (front, up)
/// in the recording's frame, from the first frame, without the breathing motion.
fn chestvolume_front_and_up(m: &Markers) -> (Vector3<f64>, Vector3<f64>) {
    let centroid = |lines: std::ops::RangeInclusive<usize>| -> Vector3<f64> {
        let pts: Vec<Vector3<f64>> = lines
            .flat_map(|line| (0..3).map(move |j| 3 * (line - 1) + j))
            .map(|k| m.frames[0][k].expect("tracked in the first frame").coords)
            .collect();
        pts.iter().sum::<Vector3<f64>>() / pts.len() as f64
    };
    let mut left = centroid(2..=5) - centroid(7..=10);
    left.z = 0.0;
    let up = Vector3::z();
    (left.cross(&up).normalize(), up)
}

/// Breaths of the ChestVolume recording found independently of the fit: in the summed
/// horizontal cross-section areas of the three rings of markers (the top, middle and bottom
/// marker of each line, in line order), a chest-wall expansion signal unaffected by the
/// trunk's translation, by [`detect_breaths`] (0.5 s smoothing, hysteresis a tenth of the
/// signal's range: the recording's first breaths are a fifth as deep as its last).
fn chestvolume_breaths(m: &Markers) -> Vec<Breath> {
    let area: Vec<f64> = m
        .frames
        .iter()
        .map(|f| {
            (0..3)
                .map(|row| {
                    let ring: Vec<Vector3<f64>> = (0..10)
                        .map(|line| f[3 * line + row].expect("tracked").coords)
                        .collect();
                    horizontal_area(&ring)
                })
                .sum()
        })
        .collect();
    let breaths = detect_breaths(&m.times, &area, 0.5, 0.1);
    assert!(!breaths.is_empty(), "no breath found in the ring areas");
    breaths
}

/// `torso fit` with its defaults on the ChestVolume recording: it reads, binds at least the
/// 12 markers a fit needs in the right pose (the front on the model's front, the head end
/// up), completes and reports the variance explained. The figures are printed.
#[test]
fn chestvolume_fit_with_defaults_binds_the_front_to_the_front() {
    let path = real_file("chestvolume/chestvolume_sample.csv");
    let m = read(&path);
    let (ok, text, result) = fit_with_defaults(&path, "chestvolume");
    assert!(ok, "torso fit failed:\n{text}");
    eprintln!("{text}");
    let r = result.unwrap();
    let bound = num(&r, &["marker_set", "markers_bound"]) as usize;
    assert!(
        bound >= MIN_MARKERS,
        "{bound} markers bound, a fit needs {MIN_MARKERS}"
    );
    // The pose: the model's axes are x anterior, y superior (src/fit/orient.rs).
    let rows: Vec<Vec<f64>> = r["marker_set"]["transform"]["rotation_matrix"]
        .as_array()
        .expect("rotation matrix")
        .iter()
        .map(|row| {
            row.as_array()
                .unwrap()
                .iter()
                .map(|v| v.as_f64().unwrap())
                .collect()
        })
        .collect();
    let rot = Matrix3::from_fn(|i, j| rows[i][j]);
    let (front, up) = chestvolume_front_and_up(&m);
    let (front_m, up_m) = (rot * front, rot * up);
    let front_deg = front_m.x.clamp(-1.0, 1.0).acos().to_degrees();
    let up_deg = up_m.y.clamp(-1.0, 1.0).acos().to_degrees();
    eprintln!(
        "chestvolume: the recording's front lands {front_deg:.1} deg from the model's front, its up {up_deg:.1} deg from the model's up"
    );
    // Within 45 degrees: half the quarter turn between the discrete alternatives, as in
    // tests/fit_orientation.rs.
    assert!(
        front_deg < 45.0 && up_deg < 45.0,
        "wrong pose: front {front_deg:.1} deg, up {up_deg:.1} deg from the model's"
    );
    report_variance("chestvolume", &r);
    eprintln!(
        "chestvolume: fitted tidal volume {:.3} L (no spirometry in the source), breathing frequency {:.4} Hz",
        num(&r, &["fitted_breath", "tidal_volume_l"]),
        num(&r, &["frequency", "hz"])
    );
    let independent = chestvolume_breaths(&m);
    compare_timing("chestvolume", &independent, &fitted_breaths(&r));
}

/// ExtMarker sequence 201205101522 (Krilavicius et al. 2015, CC BY 4.0): three markers on
/// the chest and abdomen, "sampled at approximately 10Hz", the file names' duration tag 138 s.
#[test]
fn extmarker_sequence_is_the_published_recording() {
    let path = real_file("extmarker/extmarker_201205101522.csv");
    let m = read(&path);
    assert_eq!(m.units, Units::Millimetres);
    assert_eq!(m.labels, vec!["LAC", "UAC", "UCC"]);
    assert_eq!(m.missing_per_marker(), vec![0; 3]);
    assert!(
        (9.5..=10.5).contains(&m.rate()),
        "rate {} Hz, the source says about 10 Hz",
        m.rate()
    );
    // Timestamps jitter between 100 and 117 ms in the source; no frame is dropped.
    let gaps: Vec<f64> = m.times.windows(2).map(|w| w[1] - w[0]).collect();
    let widest = gaps.iter().copied().fold(0.0, f64::max);
    assert!(widest < 0.125, "a gap of {widest} s between frames");
    assert!(
        (137.0..=139.0).contains(&m.duration()),
        "duration {} s, the file names say 138 s",
        m.duration()
    );
    let (f_peak, in_band) = breathing_peak(&m);
    eprintln!(
        "extmarker: peak {f_peak:.3} Hz, {:.0} % of the motion power in {}-{} Hz, largest excursion {:.1} mm",
        100.0 * in_band,
        BAND_HZ.0,
        BAND_HZ.1,
        1e3 * largest_excursion(&m)
    );
    assert!(
        (BAND_HZ.0..=BAND_HZ.1).contains(&f_peak),
        "the largest motion peak is at {f_peak:.3} Hz, outside the breathing band {BAND_HZ:?}"
    );
    assert!(
        in_band > 0.5,
        "only {:.0} % of the marker motion lies in the breathing band",
        100.0 * in_band
    );
}

/// `torso fit` with its defaults on the three ExtMarker markers: fewer than the 12 a fit
/// registers to the skin, so it stops with an error naming the count and the allowed range
/// (small landmark sets are left to a later issue). The breaths found independently in the
/// markers' antero-posterior coordinate are printed.
#[test]
fn extmarker_fit_is_refused_naming_the_marker_count() {
    let path = real_file("extmarker/extmarker_201205101522.csv");
    let m = read(&path);
    let (ok, text, _) = fit_with_defaults(&path, "extmarker");
    eprintln!("extmarker: {}", text.trim());
    assert!(!ok, "a fit of 3 markers completed:\n{text}");
    assert!(
        text.contains("3 tracked markers") && text.contains("at least 12 markers"),
        "the error does not name the count and the allowed range:\n{text}"
    );
    // z is the antero-posterior axis (it carries most of the motion; data/real/README.md).
    let z: Vec<f64> = m
        .frames
        .iter()
        .map(|f| f.iter().map(|p| p.expect("tracked").z).sum())
        .collect();
    let breaths = detect_breaths(&m.times, &z, 0.5, 0.1);
    let ttot: Vec<f64> = breaths.iter().map(Breath::ttot).collect();
    let sd = (ttot.iter().map(|x| (x - mean(&ttot)).powi(2)).sum::<f64>()
        / (ttot.len() - 1) as f64)
        .sqrt();
    eprintln!(
        "extmarker: {} breaths found independently, Ttot {:.2} +- {:.2} s ({:.1} breaths/min), rise {:.2} s, fall {:.2} s on average",
        breaths.len(),
        mean(&ttot),
        sd,
        60.0 / mean(&ttot),
        mean(&breaths.iter().map(|b| b.ti).collect::<Vec<_>>()),
        mean(&breaths.iter().map(|b| b.te).collect::<Vec<_>>())
    );
    assert!(breaths.len() > 10, "{} breaths in 138 s", breaths.len());
}

/// The breath timing of the fit against the breaths found independently, within the limits
/// of agreement of structured-light plethysmography that issue 33 states for its synthetic
/// acceptance (Ti +-0.22 s, Te +-0.29 s, Ttot +-0.32 s), applied here to the mean absolute
/// difference per breath. Missed (issue 33): measured Ti 1.60 s, Te 1.05 s, Ttot 2.08 s over
/// the recording's 3 complete breaths (3.3, 4.0 and 6.8 s long), which one periodic drive of
/// 6.72 s cannot follow; breath-by-breath drives are left to a later issue.
#[test]
#[ignore = "issue 33: the fitted breath timing misses the SLP limits on the ChestVolume recording (Ti 1.60, Te 1.05, Ttot 2.08 s against 0.22, 0.29, 0.32 s)"]
fn chestvolume_breath_timing_within_the_slp_limits() {
    let path = real_file("chestvolume/chestvolume_sample.csv");
    let m = read(&path);
    let (ok, text, result) = fit_with_defaults(&path, "chestvolume_timing");
    assert!(ok, "torso fit failed:\n{text}");
    let d = compare_timing(
        "chestvolume",
        &chestvolume_breaths(&m),
        &fitted_breaths(&result.unwrap()),
    );
    assert!(
        d[0] <= 0.22 && d[1] <= 0.29 && d[2] <= 0.32,
        "mean |fit - independent| Ti {:.2} s, Te {:.2} s, Ttot {:.2} s against the SLP limits 0.22, 0.29, 0.32 s",
        d[0],
        d[1],
        d[2]
    );
}
