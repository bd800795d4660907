//! Marker recordings in C3D, TRC and CSV: write -> read round trips, missing samples stay
//! missing, malformed files give errors naming file, row and column, provenance survives.

use breathing_torso::recording::{
    Format, Markers, ReadOptions, parse_named_csv, parse_trc, read_c3d,
};
use breathing_torso::recording::{Recording, Units};
use nalgebra::Point3;
use std::path::PathBuf;

fn tmp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("recording_formats_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

/// Three markers over 20 frames at 100 Hz, every 7th sample missing, with provenance.
fn sample(units: Units) -> Markers {
    let labels = vec![
        "STRN".to_string(),
        "marker[2]".to_string(),
        "T10 back".to_string(),
    ];
    let frames = (0..20)
        .map(|i| {
            (0..3)
                .map(|k| {
                    ((i * 3 + k) % 7 != 3).then(|| {
                        Point3::new(
                            0.123_456_7 * k as f64 - 0.05,
                            1.234_567 + 0.001 * i as f64,
                            -0.2 + 0.000_37 * (i * k) as f64,
                        )
                    })
                })
                .collect()
        })
        .collect();
    Markers {
        labels,
        times: (0..20).map(|i| i as f64 / 100.0).collect(),
        frames,
        units,
        format: Format::MarkerCsv,
        provenance: vec![
            ("lod".to_string(), "0".to_string()),
            ("subject.sex".to_string(), "female".to_string()),
        ],
    }
}

fn assert_same(a: &Markers, b: &Markers, tol: f64) {
    assert_eq!(a.labels, b.labels);
    assert_eq!(a.times.len(), b.times.len());
    for (x, y) in a.times.iter().zip(&b.times) {
        assert!((x - y).abs() < 1e-6, "time {x} vs {y}");
    }
    for (fa, fb) in a.frames.iter().zip(&b.frames) {
        for (pa, pb) in fa.iter().zip(fb) {
            match (pa, pb) {
                (None, None) => {}
                (Some(p), Some(q)) => {
                    for (u, v) in p.coords.iter().zip(q.coords.iter()) {
                        assert!((u - v).abs() <= tol * u.abs().max(1e-3), "{u} vs {v}");
                    }
                }
                _ => panic!("missing sample changed: {pa:?} vs {pb:?}"),
            }
        }
    }
    for (k, v) in &a.provenance {
        assert_eq!(b.provenance_value(k), Some(v.as_str()), "provenance {k}");
    }
}

#[test]
fn csv_round_trip_keeps_missing_and_provenance() {
    let m = sample(Units::Millimetres);
    let path = tmp("named.csv");
    m.write(&path).unwrap();
    let back = Markers::read(&path, &ReadOptions::default()).unwrap();
    assert_eq!(back.format, Format::MarkerCsv);
    assert_same(&m, &back, 1e-12);
    assert_eq!(back.missing_per_marker(), m.missing_per_marker());
    assert!(m.missing_per_marker().iter().all(|&c| c > 0));
}

#[test]
fn trc_round_trip_keeps_missing_and_provenance() {
    let m = sample(Units::Millimetres);
    let path = tmp("markers.trc");
    m.write(&path).unwrap();
    let back = Markers::read(&path, &ReadOptions::default()).unwrap();
    assert_eq!(back.format, Format::Trc);
    assert_eq!(back.units, Units::Millimetres);
    assert_same(&m, &back, 1e-12);
}

#[test]
fn c3d_round_trip_is_exact_in_float32() {
    for units in [Units::Millimetres, Units::Metres] {
        let m = sample(units);
        let path = tmp("markers.c3d");
        m.write(&path).unwrap();
        let back = Markers::read(&path, &ReadOptions::default()).unwrap();
        assert_eq!(back.format, Format::C3d);
        assert_eq!(back.units, units);
        assert_same(&m, &back, 1e-6);
        // Bit for bit within float32: each coordinate is the f32 of the file's value.
        let s = 1.0 / units.to_metres();
        for (fa, fb) in m.frames.iter().zip(&back.frames) {
            for (p, q) in fa.iter().zip(fb) {
                if let (Some(p), Some(q)) = (p, q) {
                    for (u, v) in p.coords.iter().zip(q.coords.iter()) {
                        assert_eq!((u * s) as f32, (v * s) as f32);
                    }
                }
            }
        }
        assert_eq!(back.missing_per_marker(), m.missing_per_marker());
    }
}

#[test]
fn grid_csv_reads_unchanged_and_converts() {
    let rec = Recording::read(std::path::Path::new("data/recordings/demo_quiet.csv")).unwrap();
    let m = Markers::read(
        std::path::Path::new("data/recordings/demo_quiet.csv"),
        &ReadOptions::default(),
    )
    .unwrap();
    assert_eq!(m.format, Format::GridCsv);
    assert_eq!(m.markers(), 60);
    let back = m.to_recording((10, 6)).unwrap();
    assert_eq!(back.frames, rec.frames);
    assert_eq!(back.times, rec.times);
    // The same markers through C3D and TRC come back as the grid recording.
    for ext in ["c3d", "trc"] {
        let mut mm = m.clone();
        mm.units = Units::Millimetres;
        let path = tmp(&format!("grid.{ext}"));
        mm.write(&path).unwrap();
        let read = Markers::read(&path, &ReadOptions::default()).unwrap();
        let r = read.to_recording((10, 6)).unwrap();
        assert_eq!(r.grid, (10, 6));
        for (fa, fb) in rec.frames.iter().zip(&r.frames) {
            for (p, q) in fa.iter().zip(fb) {
                assert!((p.unwrap() - q.unwrap()).norm() < 1e-6);
            }
        }
    }
    let err = sample(Units::Metres)
        .to_recording((10, 6))
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("not the model's 10x6 grid")
            && err.contains("STRN")
            && err.contains("marker[1]"),
        "{err}"
    );
}

#[test]
fn named_csv_variants_units_and_rate() {
    let text = "Frame,Time,STRN X,STRN Y,STRN Z,xiph.x,xiph.y,xiph.z\n1,0,1,2,3,4,5,6\n2,0.01,NaN,2,3,,,\n3,0.02,1,2,3,4,5,6\n";
    let err = parse_named_csv(text, "a.csv", &ReadOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        err.starts_with("a.csv:1:1:") && err.contains("--units mm|cm|m"),
        "{err}"
    );
    let opts = ReadOptions {
        units: Some(Units::Centimetres),
        rate: None,
    };
    let m = parse_named_csv(text, "a.csv", &opts).unwrap();
    assert_eq!(m.labels, ["STRN", "xiph"]);
    assert_eq!(m.frames[1], vec![None, None]);
    assert_eq!(m.frames[0][1], Some(Point3::new(0.04, 0.05, 0.06)));
    let no_time = "# units: mm\nA_x,A_y,A_z\n1,2,3\n1,2,4\n";
    let err = parse_named_csv(no_time, "b.csv", &ReadOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        err.starts_with("b.csv:2:1:") && err.contains("--rate HZ"),
        "{err}"
    );
    let m = parse_named_csv(
        no_time,
        "b.csv",
        &ReadOptions {
            units: None,
            rate: Some(50.0),
        },
    )
    .unwrap();
    assert_eq!(m.times, [0.0, 0.02]);
    let clash = parse_named_csv(
        no_time,
        "b.csv",
        &ReadOptions {
            units: Some(Units::Metres),
            rate: Some(50.0),
        },
    );
    assert!(clash.unwrap_err().to_string().contains("--units says m"));
}

fn err_of(r: breathing_torso::Result<Markers>) -> String {
    r.expect_err("a malformed file must not read").to_string()
}

#[test]
fn malformed_csv_names_file_row_and_column() {
    let o = ReadOptions {
        units: Some(Units::Millimetres),
        rate: None,
    };
    let e = err_of(parse_named_csv(
        "time,A X,A Y,A Z\n0,1,2,3\n0.1,1,two,3\n",
        "m.csv",
        &o,
    ));
    assert!(
        e.starts_with("m.csv:3:7:")
            && e.contains("column 3 `A Y`")
            && e.contains("`two` is not a number"),
        "{e}"
    );
    let e = err_of(parse_named_csv(
        "time,A X,A Y,A Z,B X\n0,1,2,3,4\n",
        "m.csv",
        &o,
    ));
    assert!(
        e.starts_with("m.csv:1:") && e.contains("marker `B` has no y column"),
        "{e}"
    );
    let e = err_of(parse_named_csv(
        "time,A X,A Y,A Z,speed\n0,1,2,3,4\n",
        "m.csv",
        &o,
    ));
    assert!(
        e.starts_with("m.csv:1:18:") && e.contains("column 5 `speed`"),
        "{e}"
    );
    let e = err_of(parse_named_csv(
        "time,A X,A Y,A Z\n0,1,2,3\n0.1,1,2\n",
        "m.csv",
        &o,
    ));
    assert!(e.starts_with("m.csv:3:") && e.contains("ragged row"), "{e}");
    let e = err_of(parse_named_csv(
        "time,A X,A Y,A Z\n0,1,2,3\n0,1,2,3\n",
        "m.csv",
        &o,
    ));
    assert!(
        e.starts_with("m.csv:3:1:") && e.contains("does not increase"),
        "{e}"
    );
    let e = err_of(parse_named_csv(
        "time,A X,A Y,A Z\n0,1,2,3\n0.1,inf,2,3\n",
        "m.csv",
        &o,
    ));
    assert!(e.starts_with("m.csv:3:5:") && e.contains("`A X`"), "{e}");
}

const TRC_HEAD: &str = "PathFileType\t4\t(X/Y/Z)\tt.trc\nDataRate\tCameraRate\tNumFrames\tNumMarkers\tUnits\tOrigDataRate\tOrigDataStartFrame\tOrigNumFrames\n100\t100\t2\t2\tmm\t100\t1\t2\nFrame#\tTime\tA\t\t\tB\t\t\n\t\tX1\tY1\tZ1\tX2\tY2\tZ2\n\n";

#[test]
fn trc_missing_cells_and_errors() {
    let ok = format!("{TRC_HEAD}1\t0\t1\t2\t3\t\t\t\n2\t0.01\t1\t2\t3\t4\t5\t6\n");
    let m = parse_trc(&ok, "t.trc").unwrap();
    assert_eq!(m.frames[0][1], None);
    assert_eq!(m.frames[1][1], Some(Point3::new(0.004, 0.005, 0.006)));
    let e = err_of(parse_trc(
        &format!("{TRC_HEAD}1\t0\t1\t2\t3\t4\t5\t6\n2\t0.01\t1\tx\t3\t4\t5\t6\n"),
        "t.trc",
    ));
    assert!(
        e.starts_with("t.trc:8:")
            && e.contains("column 4 `A Y`")
            && e.contains("`x` is not a number"),
        "{e}"
    );
    let e = err_of(parse_trc(&ok.replace("\tmm\t", "\tinch\t"), "t.trc"));
    assert!(
        e.starts_with("t.trc:3:") && e.contains("Units: `inch`"),
        "{e}"
    );
    let e = err_of(parse_trc(
        &ok.replace("100\t100\t2\t2", "100\t100\t3\t2"),
        "t.trc",
    ));
    assert!(e.contains("2 frames of data, NumFrames says 3"), "{e}");
    let e = err_of(parse_trc("hello\n", "t.trc"));
    assert!(
        e.starts_with("t.trc:1:1:") && e.contains("PathFileType"),
        "{e}"
    );
}

#[test]
fn c3d_errors_name_the_file() {
    let e = err_of(read_c3d(&[0u8; 100], "bad.c3d"));
    assert!(
        e.starts_with("bad.c3d:") && e.contains("not a readable C3D file"),
        "{e}"
    );
    let e = err_of(Markers::read(
        std::path::Path::new("x.mat"),
        &ReadOptions::default(),
    ));
    assert!(e.contains(".c3d, .trc or .csv"), "{e}");
}

// ---------------------------------------------------------------------------------------
// The binary: synth into each format, inspect, fit, provenance and the level of detail.

fn torso(dir: &std::path::Path, args: &[&str]) -> (bool, String, String) {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_torso"))
        .args(args)
        .current_dir(dir)
        .output()
        .expect("torso runs");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn workdir(name: &str) -> PathBuf {
    let d = tmp(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The fitted amplitudes' relative errors (ribs, diaphragm) against the truth JSON.
fn amplitude_errors(dir: &std::path::Path, result: &str) -> [f64; 2] {
    let read = |f: &str| -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(dir.join(f)).unwrap()).unwrap()
    };
    let (fit, truth) = (read(result), read("truth.json"));
    ["drive.ribs.amplitude", "drive.diaphragm.amplitude"].map(|k| {
        let t = truth[k].as_f64().unwrap();
        (fit[k].as_f64().unwrap() - t).abs() / t
    })
}

#[test]
fn c3d_synth_with_dropped_samples_fits_as_well_as_csv() {
    let dir = workdir("fit_c3d");
    let synth = |out: &str| {
        let (ok, _, err) = torso(
            &dir,
            &[
                "synth",
                "--lod",
                "0",
                "--duration",
                "8",
                "--rate",
                "30",
                "--dropout",
                "0.02",
                "--seed",
                "3",
                "--out",
                out,
                "--truth",
                "truth.json",
            ],
        );
        assert!(ok, "{err}");
    };
    synth("rec.c3d");
    synth("rec.csv");
    let (ok, info, err) = torso(&dir, &["inspect", "rec.c3d"]);
    assert!(ok, "{err}");
    for want in [
        "format: C3D",
        "markers: 60",
        "frames: 241",
        "units: mm",
        "scene.level_of_detail: 0",
        "subject.stature: 1.75",
        "marker[60]\t",
    ] {
        assert!(info.contains(want), "inspect lacks `{want}`:\n{info}");
    }
    let dropped: usize = info
        .lines()
        .find_map(|l| l.strip_prefix("missing samples: "))
        .and_then(|l| l.split(' ').next())
        .and_then(|n| n.parse().ok())
        .expect("a missing-sample count");
    assert!(
        (150..=400).contains(&dropped),
        "2 % of 14,460 samples dropped, got {dropped}"
    );
    let mut errors = Vec::new();
    for rec in ["rec.c3d", "rec.csv"] {
        let out = format!("{rec}.fit/result.json");
        let (ok, stdout, err) = torso(
            &dir,
            &["fit", "--slp", rec, "--out", &out, "--threads", "1"],
        );
        assert!(ok, "{err}");
        assert!(stdout.contains("cost"), "{stdout}");
        assert!(err.contains("fitting at level of detail 0"), "{err}");
        errors.push(amplitude_errors(&dir, &out));
    }
    let (c3d, csv) = (errors[0], errors[1]);
    for k in 0..2 {
        assert!(c3d[k] < 0.03, "C3D fit off the truth: {c3d:?}");
        // float32 millimetres against 0.1 um text: the same optimum within 0.1 %.
        assert!(c3d[k] <= csv[k] + 1e-3, "C3D {c3d:?} against CSV {csv:?}");
    }
}

#[test]
fn provenance_sets_the_level_of_detail_and_warns_on_a_different_model() {
    let dir = workdir("provenance");
    for out in ["rec.trc", "rec.csv"] {
        let (ok, _, err) = torso(
            &dir,
            &[
                "synth",
                "--lod",
                "0",
                "--duration",
                "4",
                "--rate",
                "20",
                "--stature",
                "1.62",
                "--sex",
                "female",
                "--out",
                out,
                "--truth",
                "truth.json",
            ],
        );
        assert!(ok, "{err}");
        let fit = |extra: &[&str]| {
            let mut args = vec![
                "fit",
                "--slp",
                out,
                "--out",
                "f/r.json",
                "--max-evals",
                "10",
                "--threads",
                "1",
            ];
            args.extend_from_slice(extra);
            torso(&dir, &args)
        };
        // Same model: the level of detail comes from the file, no warning.
        let (ok, _, err) = fit(&["--stature", "1.62", "--sex", "female"]);
        assert!(ok, "{err}");
        assert!(err.contains("note: fitting at level of detail 0"), "{err}");
        assert!(!err.contains("warning"), "{err}");
        // An explicit --lod wins, with one warning line naming the difference.
        let (ok, _, err) = fit(&["--lod", "1", "--stature", "1.62", "--sex", "female"]);
        assert!(ok, "{err}");
        let warnings: Vec<&str> = err.lines().filter(|l| l.starts_with("warning:")).collect();
        assert_eq!(warnings.len(), 1, "{err}");
        assert!(
            warnings[0].contains("scene.level_of_detail 0 (fit: 1)"),
            "{err}"
        );
        assert!(!err.contains("note: fitting at level"), "{err}");
        // Another subject: the warning lists each difference.
        let (ok, _, err) = fit(&[]);
        assert!(ok, "{err}");
        assert!(
            err.contains("subject.sex female (fit: male)")
                && err.contains("subject.stature 1.62 (fit: 1.75)"),
            "{err}"
        );
    }
}

#[test]
fn fit_of_too_few_named_markers_names_the_file_and_the_minimum() {
    let dir = workdir("other_set");
    std::fs::write(
        dir.join("lab.csv"),
        "# units: mm\ntime,STRN X,STRN Y,STRN Z,XIPH X,XIPH Y,XIPH Z\n0,1,2,3,4,5,6\n0.01,1,2,3,4,5,6\n",
    )
    .unwrap();
    let (ok, _, err) = torso(&dir, &["fit", "--slp", "lab.csv", "--out", "f/r.json"]);
    assert!(!ok);
    // Other labels are a marker set registered to the skin, which needs a dozen markers.
    assert!(
        err.contains("lab.csv") && err.contains("2 tracked markers") && err.contains("at least 12"),
        "{err}"
    );
    let (ok, _, err) = torso(&dir, &["inspect", "lab.csv", "--units", "furlong"]);
    assert!(
        !ok && err.contains("--units") && err.contains("mm, cm or m"),
        "{err}"
    );
    let (ok, info, err) = torso(&dir, &["inspect", "lab.csv"]);
    assert!(ok, "{err}");
    assert!(
        info.contains("format: CSV of named markers") && info.contains("provenance: none"),
        "{info}"
    );
}

/// docs/recordings.md's shell block, run as written from the repository's root with the
/// built `torso` first on the PATH.
#[test]
fn the_recordings_doc_example_runs_as_written() {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let doc = std::fs::read_to_string(root.join("docs/recordings.md")).unwrap();
    let mut blocks = Vec::new();
    let mut current: Option<String> = None;
    for line in doc.lines() {
        match (&mut current, line.trim_end()) {
            (None, "```sh") => current = Some(String::new()),
            (Some(b), "```") => {
                blocks.push(std::mem::take(b));
                current = None;
            }
            (Some(b), l) => {
                b.push_str(l);
                b.push('\n');
            }
            _ => {}
        }
    }
    assert_eq!(blocks.len(), 2, "docs/recordings.md holds two ```sh blocks");
    let bin = PathBuf::from(env!("CARGO_BIN_EXE_torso"));
    let path = format!(
        "{}:{}",
        bin.parent().unwrap().display(),
        std::env::var("PATH").unwrap_or_default()
    );
    let run = |block: &str| {
        let out = std::process::Command::new("bash")
            .arg("-c")
            .arg(block)
            .current_dir(&root)
            .env("PATH", &path)
            .output()
            .expect("bash runs");
        let (stdout, stderr) = (
            String::from_utf8_lossy(&out.stdout).into_owned(),
            String::from_utf8_lossy(&out.stderr).into_owned(),
        );
        assert!(out.status.success(), "{block}\n{stdout}\n{stderr}");
        (stdout, stderr)
    };
    let (stdout, stderr) = run(&blocks[0]);
    for want in [
        "format: C3D",
        "markers: 60",
        "frames: 181",
        "drive.diaphragm.amplitude",
    ] {
        assert!(stdout.contains(want), "no `{want}` in:\n{stdout}");
    }
    assert!(stderr.contains("fitting at level of detail 0"), "{stderr}");
    // The named marker set in a laboratory frame.
    let (stdout, stderr) = run(&blocks[1]);
    for want in [
        "format: C3D",
        "markers: 30",
        "30 of 30 markers bound to the skin",
        "\"scale\"",
        "lung_tidal_volume_l",
        "\"tidal_volume_l\"",
    ] {
        assert!(stdout.contains(want), "no `{want}` in:\n{stdout}");
    }
    assert!(
        stderr.contains("made with another model") && stderr.contains("subject.stature 1.89"),
        "{stderr}"
    );
}

/// A valid point whose residual byte is 128 or more (word 0x01C8: camera 1, residual 200)
/// stays present; a negative residual word (-1) is missing.
#[test]
fn c3d_residual_sign_is_the_whole_words() {
    let m = sample(Units::Millimetres);
    let path = tmp("residual.c3d");
    m.write(&path).unwrap();
    let mut bytes = std::fs::read(&path).unwrap();
    let block = u16::from_le_bytes([bytes[16], bytes[17]]) as usize;
    let residual_at =
        |frame: usize, marker: usize| (block - 1) * 512 + (frame * 3 + marker) * 16 + 12;
    assert!(m.frames[0][1].is_some() && m.frames[1][1].is_some());
    let at = residual_at(0, 1);
    bytes[at..at + 4].copy_from_slice(&(0x01C8 as f32).to_le_bytes());
    let at = residual_at(1, 1);
    bytes[at..at + 4].copy_from_slice(&(-1.0f32).to_le_bytes());
    let back = read_c3d(&bytes, "residual.c3d").unwrap();
    assert!(back.frames[0][1].is_some(), "residual 200 is a valid point");
    assert!(
        back.frames[1][1].is_none(),
        "residual word -1 is a missing point"
    );
}

/// Corrupted C3D bytes (each byte of the header block in turn, and a
/// truncated file) give an error or a recording, never a panic out of the reader.
#[test]
fn corrupted_c3d_never_panics() {
    let m = sample(Units::Millimetres);
    let path = tmp("corrupt.c3d");
    m.write(&path).unwrap();
    let good = std::fs::read(&path).unwrap();
    let quiet = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    let mut errors = 0;
    for at in 0..512 {
        for v in [0x00u8, 0xFF, 0x80, 0x7F] {
            let mut b = good.clone();
            b[at] = v;
            if read_c3d(&b, "c.c3d").is_err() {
                errors += 1;
            }
        }
    }
    for len in [0, 10, 511, 513, 1024, good.len() - 1] {
        let _ = read_c3d(&good[..len], "c.c3d");
    }
    std::panic::set_hook(quiet);
    assert!(errors > 0, "some corruptions must be reported");
}
