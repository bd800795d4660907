//! Public recordings of human breathing with chest markers (data/real/README.md), read
//! through the library's recording reader, checked for what their sources state
//! independently of the model: marker count and labels, unit, frame rate, duration, and that
//! the markers move with a spectral peak in the breathing band.
//!
//! The recordings are not shipped with the project: the user obtains each source file from
//! its publisher and converts it with `python/real_recordings.py` (data/real/README.md). The
//! tests are therefore ignored by default; run them on the converted files with
//!
//!     cargo test --release --test real_recordings -- --ignored
//!
//! which reads `data/real/` or the directory named by `TORSO_REAL_DATA`, and fails, naming
//! the file and how to make it, when a recording is absent.

use breathing_torso::recording::Units;
use breathing_torso::recording::{Format, Markers, ReadOptions};
use std::path::{Path, PathBuf};

/// The breathing band the checks use: 0.1-0.7 Hz (6-42 breaths per minute), the band the
/// acceptance of issue 33 names for a real recording's breathing peak.
const BAND_HZ: (f64, f64) = (0.1, 0.7);

/// Motion slower than this is drift or sway, not breathing, and is left out of the spectrum
/// (below the band's lower edge by a factor of two).
const DRIFT_HZ: f64 = 0.05;

fn real_file(rel: &str, how: &str) -> PathBuf {
    let dir = std::env::var_os("TORSO_REAL_DATA")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("data/real"));
    let path = dir.join(rel);
    assert!(
        path.is_file(),
        "{} is absent: {how} (data/real/README.md)",
        path.display()
    );
    path
}

fn read(path: &Path) -> Markers {
    Markers::read(path, &ReadOptions::default())
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
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

/// ChestVolume 1.0.1 `sample_data` (Kwong 2025, MIT): 30 markers M01-M30 in millimetres,
/// 2309 frames without a stated rate (converted at an assumed 100 Hz, recorded in the file
/// as `rate_assumed`).
#[test]
#[ignore = "needs data/real/chestvolume/chestvolume_sample.csv (data/real/README.md)"]
fn chestvolume_sample_is_the_published_recording() {
    let path = real_file(
        "chestvolume/chestvolume_sample.csv",
        "convert ChestVolume's inst/extdata/sample_data.xlsx with `python3 python/real_recordings.py chestvolume --rate 100`",
    );
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

/// ExtMarker sequence 201205101522 (Krilavicius et al. 2015, CC BY 4.0): three markers on
/// the chest and abdomen, "sampled at approximately 10Hz", the file names' duration tag 138 s.
#[test]
#[ignore = "needs data/real/extmarker/extmarker_201205101522.csv (data/real/README.md)"]
fn extmarker_sequence_is_the_published_recording() {
    let path = real_file(
        "extmarker/extmarker_201205101522.csv",
        "convert the three 201205101522-*.csv files of ExtMarker's `Original data` with `python3 python/real_recordings.py extmarker --sequence 201205101522`",
    );
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
