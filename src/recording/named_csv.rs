//! The wide CSV of named markers: a header of `NAME X`/`NAME.x`/`NAME_x` columns per marker
//! and an optional time or frame column, `# units:` and `# rate:` lines before it; read into
//! [`Markers`] and written from them. [`parse_csv`] tells it from the grid CSV by the header.

use super::{
    Format, Markers, ReadOptions, Recording, Units, coordinate, extra_provenance, point,
    split_cells,
};
use crate::{Error, Result};
use std::fmt::Write as _;

/// The marker name and axis (0, 1, 2) of a header cell `NAME X`, `NAME.x` or `NAME_x`.
fn named_axis(cell: &str) -> Option<(String, usize)> {
    let cell = cell.trim();
    let n = cell.len();
    if n < 3 || !cell.is_char_boundary(n - 2) {
        return None;
    }
    let (name, tail) = cell.split_at(n - 2);
    let mut tail = tail.chars();
    let sep = tail.next()?;
    let axis = match tail.next()?.to_ascii_lowercase() {
        'x' => 0,
        'y' => 1,
        'z' => 2,
        _ => return None,
    };
    let name = name.trim();
    ([' ', '.', '_'].contains(&sep) && !name.is_empty()).then(|| (name.to_string(), axis))
}

fn is_time_header(cell: &str) -> bool {
    let c = cell.trim().to_ascii_lowercase();
    c == "t" || c == "time" || c == "time (s)" || c == "time [s]" || c == "time_s"
}

fn is_frame_header(cell: &str) -> bool {
    let c = cell.trim().to_ascii_lowercase();
    c == "frame" || c == "frame#" || c == "frame number"
}

/// Parses a `.csv`: the grid format when the header starts `time,marker[1].x`, the
/// named-marker format otherwise. `name` is used in error messages.
pub fn parse_csv(text: &str, name: &str, options: &ReadOptions) -> Result<Markers> {
    let header = text
        .lines()
        .map(|l| l.trim_end_matches('\r'))
        .find(|l| !l.trim().is_empty() && !l.starts_with('#'));
    if header.is_some_and(|h| h.replace(' ', "").starts_with("time,marker[1].x")) {
        return Ok(Markers::from_recording(&Recording::parse(text, name)?));
    }
    parse_named_csv(text, name, options)
}

/// Parses a wide CSV of named markers (see the module documentation).
pub fn parse_named_csv(text: &str, name: &str, options: &ReadOptions) -> Result<Markers> {
    let mut file_units: Option<(Units, usize)> = None;
    let mut file_rate: Option<f64> = None;
    let mut provenance = Vec::new();
    let mut lines = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim_end_matches('\r')));
    let (header_no, header) = loop {
        let Some((no, line)) = lines.next() else {
            return Err(Error::parse(
                name,
                0,
                0,
                "no header row found: expected columns `NAME X, NAME Y, NAME Z` or `NAME.x, NAME.y, NAME.z` per marker and an optional `time` column",
            ));
        };
        let Some(comment) = line.strip_prefix('#') else {
            if line.trim().is_empty() {
                continue;
            }
            break (no, line);
        };
        let Some((key, value)) = comment.split_once(':') else {
            continue;
        };
        let (key, value) = (key.trim(), value.trim());
        let col = line.find(value).map_or(1, |b| b + 1);
        match key.to_ascii_lowercase().as_str() {
            "units" => match Units::parse(value) {
                Some(u) => file_units = Some((u, no)),
                None => {
                    return Err(Error::parse(
                        name,
                        no,
                        col,
                        format!("unknown units `{value}`: expected `m`, `cm` or `mm`"),
                    ));
                }
            },
            "rate" => match value.trim_end_matches("Hz").trim().parse::<f64>() {
                Ok(r) if r.is_finite() && r > 0.0 => file_rate = Some(r),
                _ => {
                    return Err(Error::parse(
                        name,
                        no,
                        col,
                        format!("bad rate `{value}`: expected a frame rate in Hz > 0"),
                    ));
                }
            },
            _ => provenance.push((key.to_string(), value.to_string())),
        }
    };

    // Header: a time column, a frame column, and x, y, z per marker.
    let head = split_cells(header, ',');
    let mut time_col = None;
    let mut labels: Vec<String> = Vec::new();
    let mut axes: Vec<[Option<usize>; 3]> = Vec::new();
    for (k, (col, cell)) in head.iter().enumerate() {
        if is_time_header(cell) && time_col.is_none() {
            time_col = Some(k);
            continue;
        }
        if is_frame_header(cell) {
            continue;
        }
        let Some((marker, axis)) = named_axis(cell) else {
            return Err(Error::parse(
                name,
                header_no,
                *col,
                format!(
                    "column {} `{}`: expected `time`, `frame` or a marker coordinate `NAME X`, `NAME.x` or `NAME_x` (axis x, y or z)",
                    k + 1,
                    cell.trim()
                ),
            ));
        };
        let m = match labels.iter().position(|l| l.eq_ignore_ascii_case(&marker)) {
            Some(m) => m,
            None => {
                labels.push(marker.clone());
                axes.push([None; 3]);
                labels.len() - 1
            }
        };
        if let Some(first) = axes[m][axis] {
            return Err(Error::parse(
                name,
                header_no,
                *col,
                format!(
                    "column {} `{}`: marker `{marker}` already has a {} column (column {})",
                    k + 1,
                    cell.trim(),
                    ["x", "y", "z"][axis],
                    first + 1
                ),
            ));
        }
        axes[m][axis] = Some(k);
    }
    if labels.is_empty() {
        return Err(Error::parse(
            name,
            header_no,
            1,
            "no marker columns: expected `NAME X, NAME Y, NAME Z` or `NAME.x, NAME.y, NAME.z` per marker",
        ));
    }
    for (m, a) in axes.iter().enumerate() {
        if let Some(axis) = a.iter().position(Option::is_none) {
            return Err(Error::parse(
                name,
                header_no,
                header.chars().count() + 1,
                format!(
                    "marker `{}` has no {} column",
                    labels[m],
                    ["x", "y", "z"][axis]
                ),
            ));
        }
    }
    let units = match (file_units, options.units) {
        (Some((f, no)), Some(o)) if f != o => {
            return Err(Error::parse(
                name,
                no,
                1,
                format!(
                    "the file says `# units: {}` but --units says {}",
                    f.name(),
                    o.name()
                ),
            ));
        }
        (Some((f, _)), _) => f,
        (None, Some(o)) => o,
        (None, None) => {
            return Err(Error::parse(
                name,
                header_no,
                1,
                "the file does not say its length unit: pass --units mm|cm|m or add a `# units: mm` line before the header",
            ));
        }
    };
    let rate = options.rate.or(file_rate);
    if time_col.is_none() && rate.is_none() {
        return Err(Error::parse(
            name,
            header_no,
            1,
            "no `time` column and no frame rate: pass --rate HZ or add a `# rate: HZ` line before the header",
        ));
    }

    // Frames.
    let scale = units.to_metres();
    let mut times = Vec::new();
    let mut frames = Vec::new();
    for (no, line) in lines {
        if line.trim().is_empty() {
            continue;
        }
        if line.starts_with('#') {
            return Err(Error::parse(
                name,
                no,
                1,
                "comment lines are only allowed before the header",
            ));
        }
        let row = split_cells(line, ',');
        if row.len() != head.len() {
            let col = row
                .get(head.len())
                .map_or(line.chars().count() + 1, |c| c.0);
            return Err(Error::parse(
                name,
                no,
                col,
                format!(
                    "ragged row: {} cells, the header has {}",
                    row.len(),
                    head.len()
                ),
            ));
        }
        let cell = |k: usize| -> Result<Option<f64>> {
            let (col, s) = row[k];
            coordinate(s, |m| {
                Error::parse(
                    name,
                    no,
                    col,
                    format!("column {} `{}`: {m}", k + 1, head[k].1.trim()),
                )
            })
        };
        let t = match time_col {
            Some(k) => cell(k)?.ok_or_else(|| {
                Error::parse(
                    name,
                    no,
                    row[k].0,
                    format!("column {} `{}`: empty time", k + 1, head[k].1.trim()),
                )
            })?,
            None => frames.len() as f64 / rate.unwrap_or(1.0),
        };
        if let Some(&prev) = times.last()
            && t <= prev
        {
            let col = time_col.map_or(1, |k| row[k].0);
            return Err(Error::parse(
                name,
                no,
                col,
                format!("time {t} s does not increase (previous frame: {prev} s)"),
            ));
        }
        let mut frame = Vec::with_capacity(labels.len());
        for a in &axes {
            let xyz = [
                cell(a[0].unwrap_or(0))?,
                cell(a[1].unwrap_or(0))?,
                cell(a[2].unwrap_or(0))?,
            ];
            frame.push(point(xyz, scale));
        }
        times.push(t);
        frames.push(frame);
    }
    if frames.len() < 2 {
        return Err(Error::parse(
            name,
            header_no + frames.len() + 1,
            1,
            format!("{} frame(s): a recording needs at least two", frames.len()),
        ));
    }
    Ok(Markers {
        labels,
        times,
        frames,
        units,
        format: Format::MarkerCsv,
        provenance,
    })
}

/// The named-marker CSV text (`# units:`, provenance lines, `time,NAME.x,NAME.y,NAME.z,...`).
pub(super) fn csv_text(m: &Markers) -> String {
    let scale = 1.0 / m.units.to_metres();
    let mut s = String::new();
    let _ = writeln!(s, "# units: {}", m.units.name());
    for (k, v) in extra_provenance(m) {
        let _ = writeln!(s, "# {k}: {v}");
    }
    s.push_str("time");
    for l in &m.labels {
        let _ = write!(s, ",{l}.x,{l}.y,{l}.z");
    }
    s.push('\n');
    for (t, f) in m.times.iter().zip(&m.frames) {
        let _ = write!(s, "{t:.9}");
        for p in f {
            match p {
                Some(p) => {
                    for v in p.coords.iter() {
                        let _ = write!(s, ",{}", v * scale);
                    }
                }
                None => s.push_str(",,,"),
            }
        }
        s.push('\n');
    }
    s
}
