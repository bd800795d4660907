//! Reading and writing the CSV time series the validation works on: a header row naming the
//! columns (one of them `time` in seconds), `#` comment lines, comma-separated numbers.
//! Every error names the file, the 1-based line and the 1-based character column of the
//! offending field.

use crate::{Error, Result};
use std::path::Path;

/// A uniformly sampled time series read from a CSV file.
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    /// Sample times [s], strictly increasing.
    pub time: Vec<f64>,
    /// Sample values (unit of the column, L or L/s for the validation).
    pub values: Vec<f64>,
    /// Header of the value column as found in the file.
    pub column: String,
    /// Where the series came from (the file name), used in error messages.
    pub source: String,
}

impl Series {
    /// Number of samples.
    pub fn len(&self) -> usize {
        self.values.len()
    }

    /// True when there are no samples.
    pub fn is_empty(&self) -> bool {
        self.values.is_empty()
    }

    /// Sampling rate [Hz]: (n - 1) / (t_last - t_first), which is insensitive to the
    /// rounding of individual time stamps (NaN with fewer than 2 samples).
    pub fn rate(&self) -> f64 {
        let n = self.time.len();
        if n < 2 {
            return f64::NAN;
        }
        (n - 1) as f64 / (self.time[n - 1] - self.time[0])
    }
}

/// A parsed CSV table: header names and numeric rows with their source lines.
#[derive(Debug, Clone)]
pub struct Table {
    /// File name used in error messages.
    pub path: String,
    /// Column headers, trimmed.
    pub headers: Vec<String>,
    /// Line number (1-based) of the header.
    pub header_line: usize,
    /// Numeric rows.
    pub rows: Vec<Vec<f64>>,
    /// 1-based source line of each row.
    pub lines: Vec<usize>,
    /// Source text of each row (for error columns).
    raw: Vec<String>,
}

/// Parses CSV text (header row, `#` comments and blank lines skipped, numbers in every
/// field). `path` is only used in error messages.
pub fn parse_table(path: &str, text: &str) -> Result<Table> {
    let mut headers: Option<(Vec<String>, usize)> = None;
    let mut rows = Vec::new();
    let mut lines = Vec::new();
    let mut raw_rows = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let line_no = i + 1;
        let trimmed = raw.trim();
        if trimmed.is_empty() || trimmed.starts_with('#') {
            continue;
        }
        match &headers {
            None => {
                let h: Vec<String> = raw.split(',').map(|s| s.trim().to_string()).collect();
                if let Some(pos) = h.iter().position(String::is_empty) {
                    return Err(Error::parse(
                        path,
                        line_no,
                        field_column(raw, pos),
                        format!("empty column name in header (field {})", pos + 1),
                    ));
                }
                headers = Some((h, line_no));
            }
            Some((h, _)) => {
                let fields: Vec<&str> = raw.split(',').collect();
                if fields.len() != h.len() {
                    return Err(Error::parse(
                        path,
                        line_no,
                        1,
                        format!(
                            "expected {} fields as in the header, found {}",
                            h.len(),
                            fields.len()
                        ),
                    ));
                }
                let mut row = Vec::with_capacity(fields.len());
                for (j, f) in fields.iter().enumerate() {
                    match f.trim().parse::<f64>() {
                        Ok(v) if v.is_finite() => row.push(v),
                        _ => {
                            return Err(Error::parse(
                                path,
                                line_no,
                                field_column(raw, j),
                                format!("column `{}`: `{}` is not a finite number", h[j], f.trim()),
                            ));
                        }
                    }
                }
                rows.push(row);
                lines.push(line_no);
                raw_rows.push(raw.to_string());
            }
        }
    }
    let (headers, header_line) = headers.ok_or_else(|| {
        Error::parse(path, 0, 0, "no header row (file is empty or only comments)")
    })?;
    Ok(Table {
        path: path.to_string(),
        headers,
        header_line,
        rows,
        lines,
        raw: raw_rows,
    })
}

/// 1-based character column where field `index` of a comma-separated line starts.
fn field_column(line: &str, index: usize) -> usize {
    let mut col = 1;
    for (k, part) in line.split(',').enumerate() {
        if k == index {
            let lead = part.len() - part.trim_start().len();
            return col + lead;
        }
        col += part.chars().count() + 1;
    }
    col
}

/// True when `header` names `name`: equal ignoring case, or `name` followed by a unit
/// suffix such as `volume [L]`, `volume_L` or `time (s)`.
pub fn header_matches(header: &str, name: &str) -> bool {
    let h = header.trim().to_ascii_lowercase();
    let n = name.trim().to_ascii_lowercase();
    h == n
        || (h.starts_with(&n)
            && matches!(h.as_bytes().get(n.len()), Some(b' ' | b'_' | b'[' | b'(')))
}

impl Table {
    /// Index of the column named `name` (see [`header_matches`]).
    pub fn column_index(&self, name: &str) -> Option<usize> {
        self.headers.iter().position(|h| header_matches(h, name))
    }

    /// Extracts the series (`time`, `name`), checking that time strictly increases, the
    /// sampling is uniform within 50 % of the mean step and there are `min_rows` rows.
    pub fn series(&self, name: &str, min_rows: usize) -> Result<Series> {
        let min_rows = min_rows.max(2);
        let ti = self.column_index("time").ok_or_else(|| {
            Error::parse(
                &self.path,
                self.header_line,
                1,
                format!(
                    "no `time` column in header (columns: {})",
                    self.headers.join(", ")
                ),
            )
        })?;
        let vi = self.column_index(name).ok_or_else(|| {
            Error::parse(
                &self.path,
                self.header_line,
                1,
                format!(
                    "no `{name}` column in header (columns: {})",
                    self.headers.join(", ")
                ),
            )
        })?;
        let time: Vec<f64> = self.rows.iter().map(|r| r[ti]).collect();
        let values: Vec<f64> = self.rows.iter().map(|r| r[vi]).collect();
        let time_col = |k: usize| field_column(&self.raw[k], ti);
        for k in 1..time.len() {
            if time[k] <= time[k - 1] {
                return Err(Error::parse(
                    &self.path,
                    self.lines[k],
                    time_col(k),
                    format!(
                        "column `{}`: time {} does not increase (previous row {})",
                        self.headers[ti],
                        time[k],
                        time[k - 1]
                    ),
                ));
            }
        }
        let series = Series {
            time,
            values,
            column: self.headers[vi].clone(),
            source: self.path.clone(),
        };
        if self.rows.len() < min_rows {
            return Err(Error::parse(
                &self.path,
                self.lines.last().copied().unwrap_or(self.header_line),
                0,
                format!(
                    "{} data rows, at least {min_rows} are needed",
                    self.rows.len()
                ),
            ));
        }
        let step = 1.0 / series.rate();
        for k in 1..series.time.len() {
            let dt = series.time[k] - series.time[k - 1];
            if (dt - step).abs() > 0.5 * step {
                return Err(Error::parse(
                    &self.path,
                    self.lines[k],
                    time_col(k),
                    format!(
                        "column `{}`: time step {dt} s differs from the mean step {step} s by more \
                         than 50 %; resample the recording uniformly first",
                        self.headers[ti]
                    ),
                ));
            }
        }
        Ok(series)
    }
}

/// Reads a CSV file into a [`Table`].
pub fn read_table(path: &Path) -> Result<Table> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    parse_table(&path.display().to_string(), &text)
}

/// Writes columns of equal length as CSV with the given header names.
pub fn write_csv(path: &Path, headers: &[&str], columns: &[&[f64]]) -> Result<()> {
    use std::fmt::Write as _;
    let n = columns.first().map_or(0, |c| c.len());
    let mut s = String::with_capacity(n * 24 * columns.len().max(1));
    s.push_str(&headers.join(","));
    s.push('\n');
    for i in 0..n {
        for (j, c) in columns.iter().enumerate() {
            if j > 0 {
                s.push(',');
            }
            let _ = write!(s, "{}", c[i]);
        }
        s.push('\n');
    }
    std::fs::write(path, s).map_err(|e| Error::io(path, e))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn errors_name_line_and_column() {
        let text = "# comment\ntime,volume\n0,1\n0.01,x\n";
        let e = parse_table("a.csv", text).unwrap_err().to_string();
        assert!(e.starts_with("a.csv:4:6:"), "{e}");
        assert!(e.contains("`volume`"), "{e}");
        let text = "time,volume\n0,1\n0.01,2\n0.01,3\n";
        let t = parse_table("b.csv", text).unwrap();
        let e = t.series("volume", 2).unwrap_err().to_string();
        assert!(e.starts_with("b.csv:4:1:"), "{e}");
        let e = t.series("flow", 2).unwrap_err().to_string();
        assert!(e.contains("no `flow` column"), "{e}");
        let t = parse_table("c.csv", "time,volume\n0,1\n0.01,2\n0.02,3\n").unwrap();
        let e = t.series("volume", 10).unwrap_err().to_string();
        assert!(
            e.starts_with("c.csv:4:0:") && e.contains("at least 10"),
            "{e}"
        );
        let t = parse_table("d.csv", "time,volume\n0,1\n0.01,2\n0.05,3\n0.06,3\n").unwrap();
        let e = t.series("volume", 2).unwrap_err().to_string();
        assert!(
            e.starts_with("d.csv:4:1:") && e.contains("differs from the mean step"),
            "{e}"
        );
    }

    #[test]
    fn unit_suffixes_match() {
        assert!(header_matches("Volume [L]", "volume"));
        assert!(header_matches("time_s", "time"));
        assert!(!header_matches("volumetric", "volume"));
    }
}
