//! The OpenSim TRC marker file: a tab-separated header of eight defined fields (extra
//! fields carry the provenance), a line of labels, then one row per frame; read into
//! [`Markers`] and written from them.

use super::{Format, Markers, Units, coordinate, extra_provenance, point, split_cells};
use crate::{Error, Result};
use std::fmt::Write as _;
use std::path::Path;

/// The header fields of TRC line 2 that the format defines.
const TRC_FIELDS: [&str; 8] = [
    "DataRate",
    "CameraRate",
    "NumFrames",
    "NumMarkers",
    "Units",
    "OrigDataRate",
    "OrigDataStartFrame",
    "OrigNumFrames",
];

/// Parses an OpenSim TRC file. `name` is used in error messages.
pub fn parse_trc(text: &str, name: &str) -> Result<Markers> {
    let lines: Vec<&str> = text.lines().map(|l| l.trim_end_matches('\r')).collect();
    let line = |i: usize| lines.get(i).copied().unwrap_or("");
    if !line(0).starts_with("PathFileType") {
        return Err(Error::parse(
            name,
            1,
            1,
            "expected a TRC file starting `PathFileType` (OpenSim marker file)",
        ));
    }
    let keys = split_cells(line(1), '\t');
    let values = split_cells(line(2), '\t');
    let field = |key: &str| -> Result<(usize, &str)> {
        let k = keys
            .iter()
            .position(|(_, c)| c.trim().eq_ignore_ascii_case(key))
            .ok_or_else(|| {
                Error::parse(name, 2, 1, format!("header line 2 has no `{key}` field"))
            })?;
        let (col, v) = values.get(k).copied().ok_or_else(|| {
            Error::parse(
                name,
                3,
                line(2).chars().count() + 1,
                format!("no value under `{key}`"),
            )
        })?;
        Ok((col, v.trim()))
    };
    let positive = |key: &str| -> Result<f64> {
        let (col, v) = field(key)?;
        v.parse::<f64>()
            .ok()
            .filter(|r| r.is_finite() && *r > 0.0)
            .ok_or_else(|| Error::parse(name, 3, col, format!("{key}: `{v}` is not a number > 0")))
    };
    let count = |key: &str| -> Result<usize> {
        let (col, v) = field(key)?;
        v.parse::<usize>()
            .map_err(|_| Error::parse(name, 3, col, format!("{key}: `{v}` is not a whole number")))
    };
    positive("DataRate")?;
    let num_frames = count("NumFrames")?;
    let num_markers = count("NumMarkers")?;
    let (units_col, units_text) = field("Units")?;
    let units = Units::parse(units_text).ok_or_else(|| {
        Error::parse(
            name,
            3,
            units_col,
            format!("Units: `{units_text}` is not mm, cm or m"),
        )
    })?;
    let provenance: Vec<(String, String)> = keys
        .iter()
        .enumerate()
        .filter(|(_, (_, k))| {
            !k.trim().is_empty() && !TRC_FIELDS.iter().any(|f| f.eq_ignore_ascii_case(k.trim()))
        })
        .map(|(i, (_, k))| {
            let v = values.get(i).map_or("", |c| c.1.trim());
            (k.trim().to_string(), v.to_string())
        })
        .collect();

    // Line 4: Frame#, Time, then each label followed by two empty cells.
    let names = split_cells(line(3), '\t');
    if names.len() < 2
        || !names[0].1.trim().eq_ignore_ascii_case("Frame#")
        || !names[1].1.trim().eq_ignore_ascii_case("Time")
    {
        return Err(Error::parse(
            name,
            4,
            1,
            "line 4 should start `Frame#<TAB>Time`",
        ));
    }
    let labels: Vec<String> = names[2..]
        .iter()
        .map(|(_, c)| c.trim())
        .filter(|c| !c.is_empty())
        .map(str::to_string)
        .collect();
    if labels.len() != num_markers {
        return Err(Error::parse(
            name,
            4,
            1,
            format!(
                "line 4 names {} markers, NumMarkers says {num_markers}",
                labels.len()
            ),
        ));
    }
    for (k, (col, c)) in names[2..].iter().enumerate() {
        let want_label = k % 3 == 0;
        if want_label == c.trim().is_empty() {
            return Err(Error::parse(
                name,
                4,
                *col,
                format!(
                    "column {}: expected {} (each label is followed by two empty cells)",
                    k + 3,
                    if want_label {
                        "a marker label"
                    } else {
                        "an empty cell"
                    }
                ),
            ));
        }
    }
    let width = 2 + 3 * num_markers;
    let column_name = |k: usize| -> String {
        match k {
            0 => "Frame#".into(),
            1 => "Time".into(),
            _ => format!("{} {}", labels[(k - 2) / 3], ["X", "Y", "Z"][(k - 2) % 3]),
        }
    };
    let scale = units.to_metres();
    let mut times = Vec::new();
    let mut frames = Vec::new();
    let mut last_no = 5;
    for (i, raw) in lines.iter().enumerate().skip(5) {
        let no = i + 1;
        if raw.trim().is_empty() {
            continue;
        }
        last_no = no;
        let row = split_cells(raw, '\t');
        if row.len() > width && row[width..].iter().any(|(_, c)| !c.trim().is_empty()) {
            return Err(Error::parse(
                name,
                no,
                row[width].0,
                format!("{} cells, the header has {width}", row.len()),
            ));
        }
        let cell = |k: usize| -> Result<Option<f64>> {
            match row.get(k) {
                None => Ok(None),
                Some(&(col, s)) => coordinate(s, |m| {
                    Error::parse(
                        name,
                        no,
                        col,
                        format!("column {} `{}`: {m}", k + 1, column_name(k)),
                    )
                }),
            }
        };
        let t = cell(1)?.ok_or_else(|| {
            let col = row.get(1).map_or(raw.chars().count() + 1, |c| c.0);
            Error::parse(name, no, col, "column 2 `Time`: empty time")
        })?;
        if let Some(&prev) = times.last()
            && t <= prev
        {
            return Err(Error::parse(
                name,
                no,
                row[1].0,
                format!("column 2 `Time`: {t} s does not increase (previous frame: {prev} s)"),
            ));
        }
        let mut frame = Vec::with_capacity(num_markers);
        for m in 0..num_markers {
            let k = 2 + 3 * m;
            frame.push(point([cell(k)?, cell(k + 1)?, cell(k + 2)?], scale));
        }
        times.push(t);
        frames.push(frame);
    }
    if frames.len() != num_frames {
        return Err(Error::parse(
            name,
            last_no,
            1,
            format!(
                "{} frames of data, NumFrames says {num_frames}",
                frames.len()
            ),
        ));
    }
    if frames.len() < 2 {
        return Err(Error::parse(
            name,
            last_no,
            1,
            format!("{} frame(s): a recording needs at least two", frames.len()),
        ));
    }
    Ok(Markers {
        labels,
        times,
        frames,
        units,
        format: Format::Trc,
        provenance,
    })
}

/// The TRC text of `m` (rate from the mean frame interval; provenance as extra header
/// fields after the eight the format defines).
pub(super) fn trc_text(m: &Markers, path: &Path) -> String {
    let scale = 1.0 / m.units.to_metres();
    let rate = m.rate();
    let n = m.times.len();
    let file = path
        .file_name()
        .and_then(|f| f.to_str())
        .unwrap_or("markers.trc");
    let mut s = String::new();
    let _ = writeln!(s, "PathFileType\t4\t(X/Y/Z)\t{file}");
    let extra: Vec<&(String, String)> = extra_provenance(m).collect();
    s.push_str(&TRC_FIELDS.join("\t"));
    for (k, _) in &extra {
        let _ = write!(s, "\t{k}");
    }
    s.push('\n');
    let _ = write!(
        s,
        "{rate}\t{rate}\t{n}\t{}\t{}\t{rate}\t1\t{n}",
        m.markers(),
        m.units.name()
    );
    for (_, v) in &extra {
        let _ = write!(s, "\t{v}");
    }
    s.push('\n');
    s.push_str("Frame#\tTime");
    for l in &m.labels {
        let _ = write!(s, "\t{l}\t\t");
    }
    s.push_str("\n\t");
    for k in 1..=m.markers() {
        let _ = write!(s, "\tX{k}\tY{k}\tZ{k}");
    }
    s.push_str("\n\n");
    for (i, (t, f)) in m.times.iter().zip(&m.frames).enumerate() {
        let _ = write!(s, "{}\t{t:.9}", i + 1);
        for p in f {
            match p {
                Some(p) => {
                    for v in p.coords.iter() {
                        let _ = write!(s, "\t{}", v * scale);
                    }
                }
                None => s.push_str("\t\t\t"),
            }
        }
        s.push('\n');
    }
    s
}
