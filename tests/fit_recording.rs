//! The SLP recording format: round trip, units, default grid, and every rejected file with
//! its line and column.

use breathing_torso::Error;
use breathing_torso::recording::{Recording, Units};
use nalgebra::Point3;

fn header(points: usize) -> String {
    let mut h = String::from("time");
    for i in 1..=points {
        h.push_str(&format!(",marker[{i}].x,marker[{i}].y,marker[{i}].z"));
    }
    h
}

fn row(t: f64, points: usize) -> String {
    let mut r = format!("{t}");
    for i in 0..points {
        r.push_str(&format!(",{},{},{}", 0.01 * i as f64, 1.0 + t, -0.02));
    }
    r
}

/// A 2x2 recording with `n` frames.
fn small(n: usize) -> String {
    let mut s = String::from("# produced by a test\n# grid: 2x2\n# units: m\n");
    s.push_str(&header(4));
    s.push('\n');
    for k in 0..n {
        s.push_str(&row(k as f64 * 0.1, 4));
        s.push('\n');
    }
    s
}

/// Parses and expects an error at (line, column) whose message contains `needle`.
fn rejects(text: &str, line: usize, column: usize, needle: &str) {
    match Recording::parse(text, "rec.csv") {
        Err(Error::Parse {
            path,
            line: l,
            column: c,
            message,
        }) => {
            assert_eq!(path, "rec.csv");
            assert_eq!(
                (l, c),
                (line, column),
                "position of `{message}` (expected {line}:{column})"
            );
            assert!(
                message.contains(needle),
                "message `{message}` lacks `{needle}`"
            );
            let shown = Recording::parse(text, "rec.csv").unwrap_err().to_string();
            assert!(
                shown.starts_with(&format!("rec.csv:{line}:{column}: ")),
                "{shown}"
            );
        }
        other => panic!("expected a parse error, got {other:?}"),
    }
}

#[test]
fn reads_a_small_recording() {
    let r = Recording::parse(&small(3), "rec.csv").unwrap();
    assert_eq!(r.grid, (2, 2));
    assert_eq!(r.times, vec![0.0, 0.1, 0.2]);
    assert_eq!(r.frames.len(), 3);
    assert_eq!(r.frames[1][3], Some(Point3::new(0.03, 1.1, -0.02)));
    assert_eq!(r.units, Units::Metres);
}

#[test]
fn millimetres_are_converted_to_metres() {
    let text = small(2).replace("# units: m\n", "# units: mm\n");
    let r = Recording::parse(&text, "rec.csv").unwrap();
    assert_eq!(r.units, Units::Millimetres);
    let p = r.frames[0][2].unwrap();
    assert!((p.x - 0.02e-3).abs() < 1e-15 && (p.y - 1e-3).abs() < 1e-15);
}

#[test]
fn round_trip_keeps_untracked_points_and_values() {
    let mut r = Recording::parse(&small(4), "rec.csv").unwrap();
    r.frames[2][1] = None;
    r.frames[0][0] = Some(Point3::new(0.123_456_7, -1.5, 2.25));
    for units in [Units::Metres, Units::Millimetres] {
        r.units = units;
        let text = r.to_csv().unwrap();
        let back = Recording::parse(&text, "rt.csv").unwrap();
        assert_eq!(back.grid, r.grid);
        for (a, b) in back.times.iter().zip(&r.times) {
            assert!((a - b).abs() < 1e-9);
        }
        assert_eq!(back.frames[2][1], None);
        for (a, b) in back.frames.iter().flatten().zip(r.frames.iter().flatten()) {
            match (a, b) {
                (Some(a), Some(b)) => assert!((a - b).norm() < 1e-7, "{a} {b}"),
                (None, None) => {}
                _ => panic!("tracking flag changed"),
            }
        }
    }
}

#[test]
fn write_and_read_a_file() {
    let dir = std::env::temp_dir().join(format!("fit_recording_{}", std::process::id()));
    let path = dir.join("sub/rec.csv");
    let r = Recording::parse(&small(3), "rec.csv").unwrap();
    r.write(&path).unwrap();
    let back = Recording::read(&path).unwrap();
    assert_eq!(back.frames.len(), 3);
    let missing = Recording::read(&dir.join("nope.csv")).unwrap_err();
    assert!(matches!(missing, Error::Io { .. }), "{missing}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn sixty_points_default_to_ten_by_six() {
    let text = format!("{}\n{}\n{}\n", header(60), row(0.0, 60), row(0.1, 60));
    assert_eq!(Recording::parse(&text, "r").unwrap().grid, (10, 6));
}

#[test]
fn other_sizes_need_the_grid_line() {
    let text = format!("{}\n{}\n{}\n", header(48), row(0.0, 48), row(0.1, 48));
    rejects(&text, 1, 1, "add a `# grid: ROWSxCOLS` line");
}

#[test]
fn grid_must_match_the_header() {
    let text = small(2).replace("# grid: 2x2", "# grid: 3x2");
    rejects(&text, 2, 1, "grid 3x2 has 6 points but the header has 4");
}

#[test]
fn bad_grid_line() {
    let text = small(2).replace("# grid: 2x2", "# grid: two by two");
    rejects(&text, 2, 9, "bad grid `two by two`");
    let text = small(2).replace("# grid: 2x2", "# grid: 20x2");
    rejects(&text, 2, 9, "bad grid");
}

#[test]
fn unknown_units() {
    let text = small(2).replace("# units: m\n", "# units: inch\n");
    rejects(&text, 3, 10, "unknown units `inch`");
}

#[test]
fn header_cells_are_checked() {
    let text = small(2).replace("marker[2].y", "marker[2].q");
    // time, then marker[1] x y z, marker[2].x: the bad cell is the 6th.
    let col = header(4).find("marker[2].y").unwrap() + 1;
    rejects(&text, 4, col, "expected `marker[2].y`");
    let text = small(2).replace("time,", "t,");
    rejects(&text, 4, 1, "expected `time`");
}

#[test]
fn truncated_header() {
    let h = header(4);
    let cut = &h[..h.rfind(",marker[4].z").unwrap()];
    let text = small(2).replace(&h, cut);
    rejects(&text, 4, cut.len() + 1, "expected `time` then x, y, z");
}

#[test]
fn ragged_rows() {
    let short = row(0.1, 4);
    let cut = &short[..short.rfind(',').unwrap()];
    let text = small(2).replace(&short, cut);
    rejects(
        &text,
        6,
        cut.len() + 1,
        "ragged row: 12 cells, the header has 13",
    );
    let text = small(2).replace(&short, &format!("{short},7"));
    rejects(&text, 6, short.len() + 2, "ragged row: 14 cells");
}

#[test]
fn non_numeric_cell() {
    let r = row(0.1, 4);
    let bad = r.replacen("1.1", "abc", 1);
    let col = bad.find("abc").unwrap() + 1;
    let text = small(2).replace(&r, &bad);
    rejects(&text, 6, col, "marker[1].y: `abc` is not a number");
}

#[test]
fn nan_and_infinite_cells() {
    for word in ["NaN", "inf", "-inf"] {
        let r = row(0.1, 4);
        let bad = r.replacen("-0.02", word, 1);
        let col = bad.find(word).unwrap() + 1;
        let text = small(2).replace(&r, &bad);
        rejects(&text, 6, col, "is not finite");
    }
}

#[test]
fn time_must_increase() {
    let text = small(3).replace(&row(0.2, 4), &row(0.1, 4));
    rejects(
        &text,
        7,
        1,
        "time 0.1 s does not increase (previous frame: 0.1 s)",
    );
    let text = small(3).replace(&row(0.2, 4), &row(0.05, 4));
    rejects(&text, 7, 1, "does not increase");
}

#[test]
fn empty_time_cell() {
    let r = row(0.1, 4);
    let text = small(2).replace(&r, &r.replacen("0.1", "", 1));
    rejects(&text, 6, 1, "time: empty cell");
}

#[test]
fn fewer_than_two_frames() {
    rejects(&small(1), 6, 1, "1 frame(s)");
    rejects(&small(0), 5, 1, "0 frame(s)");
}

#[test]
fn no_header() {
    rejects("# grid: 2x2\n", 0, 0, "no header row");
}

#[test]
fn partly_empty_point() {
    let r = row(0.1, 4);
    // marker[2] is cells 5-7; blank its y.
    let mut cells: Vec<String> = r.split(',').map(String::from).collect();
    cells[5] = String::new();
    let bad = cells.join(",");
    let col = cells[..5].iter().map(|c| c.len() + 1).sum::<usize>() + 1;
    let text = small(2).replace(&r, &bad);
    rejects(&text, 6, col, "marker[2]: partly empty");
}

#[test]
fn empty_triple_is_untracked() {
    let r = row(0.1, 4);
    let mut cells: Vec<String> = r.split(',').map(String::from).collect();
    for c in &mut cells[4..7] {
        c.clear();
    }
    let text = small(2).replace(&r, &cells.join(","));
    let rec = Recording::parse(&text, "r").unwrap();
    assert_eq!(rec.frames[1][1], None);
    assert!(rec.frames[1][0].is_some());
    assert_eq!(rec.tracked(), 7);
}

#[test]
fn comments_only_before_the_header() {
    let text = format!("{}# late comment\n{}\n", small(2), row(0.3, 4));
    rejects(&text, 7, 1, "only allowed before the header");
}

#[test]
fn blank_line_between_frames() {
    let text = small(3).replace(
        &format!("{}\n", row(0.1, 4)),
        &format!("{}\n\n", row(0.1, 4)),
    );
    rejects(&text, 7, 1, "empty line between frames");
}

#[test]
fn crlf_and_trailing_blank_lines_are_accepted() {
    let text = small(3).replace('\n', "\r\n") + "\r\n\r\n";
    let r = Recording::parse(&text, "r").unwrap();
    assert_eq!(r.frames.len(), 3);
}

#[test]
fn writer_validates() {
    let mut r = Recording::parse(&small(3), "r").unwrap();
    r.times[2] = 0.05;
    assert!(
        r.to_csv()
            .unwrap_err()
            .to_string()
            .contains("time of frame 3")
    );
    let mut r = Recording::parse(&small(3), "r").unwrap();
    r.frames[1].pop();
    assert!(
        r.to_csv()
            .unwrap_err()
            .to_string()
            .contains("recording frame 2")
    );
}
