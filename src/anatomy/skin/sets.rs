//! Marker sets: named points bound to the skin by barycentric coordinates. The SLP grid is
//! one such set (labels `marker[k]`); the built-in named sets of motion-capture protocols
//! (a 30-marker chest-and-back set and an 89-marker set after optoelectronic
//! plethysmography) are placed here from the subject's own landmarks, so they scale with the
//! subject; sets recorded in a laboratory are bound by [`super::register_to_surface`].

use super::Skin;
use super::geometry::ray_triangle;
use super::markers::{MarkerGrid, SurfaceBinding};
use crate::{Error, Result};
use nalgebra::{Point3, Vector3};
use std::hash::{Hash, Hasher};

/// Named markers bound to the skin's triangles.
#[derive(Clone, Debug, PartialEq)]
pub struct MarkerSet {
    /// Name of the set (`grid` for the SLP grid, a built-in name, or `recording`).
    pub name: String,
    /// Marker labels, one per binding, distinct.
    pub labels: Vec<String>,
    /// Where each marker sits on the skin.
    pub bindings: Vec<SurfaceBinding>,
}

// Bindings are finite (barycentric coordinates of a point on a triangle), so equality is an
// equivalence and bit-wise hashing agrees with it.
impl Eq for MarkerSet {}

impl Hash for MarkerSet {
    fn hash<H: Hasher>(&self, state: &mut H) {
        self.name.hash(state);
        self.labels.hash(state);
        for b in &self.bindings {
            b.triangle.hash(state);
            for v in b.barycentric {
                v.to_bits().hash(state);
            }
        }
    }
}

/// Names of the built-in marker sets of [`MarkerSet::builtin`].
pub const BUILTIN_SETS: [&str; 3] = ["grid", "chest30", "oep89"];

impl MarkerSet {
    /// The SLP grid as a marker set: labels `marker[1]`..`marker[R*C]` in the grid's
    /// row-major order, the grid's bindings.
    pub fn from_grid(grid: &MarkerGrid) -> MarkerSet {
        MarkerSet {
            name: "grid".into(),
            labels: (0..grid.markers.len())
                .map(|k| format!("marker[{}]", k + 1))
                .collect(),
            bindings: grid.bindings(),
        }
    }

    /// The set's bindings as JSON, one object per marker in the set's order:
    /// `{"label": .., "triangle": .., "barycentric": [b0, b1, b2]}` (numbers written so that
    /// they read back bit for bit). [`MarkerSet::from_bindings_json`] reads it.
    pub fn bindings_json(&self) -> serde_json::Value {
        serde_json::Value::Array(
            self.labels
                .iter()
                .zip(&self.bindings)
                .map(|(label, b)| {
                    serde_json::json!({
                        "label": label,
                        "triangle": b.triangle,
                        "barycentric": b.barycentric,
                    })
                })
                .collect(),
        )
    }

    /// A set called `name` from the JSON of [`MarkerSet::bindings_json`]; `source` names where
    /// the JSON comes from in errors, which give the entry (0-based) and the key that is
    /// missing or wrong. Labels must be distinct and the barycentric coordinates finite, at
    /// least 0 and summing to 1 (the triangle is checked against a skin by
    /// [`MarkerSet::check`]).
    pub fn from_bindings_json(
        name: &str,
        json: &serde_json::Value,
        source: &str,
    ) -> Result<MarkerSet> {
        let entries = json.as_array().ok_or_else(|| {
            Error::invalid(
                format!("{source}: bindings"),
                json.to_string(),
                "an array of {label, triangle, barycentric} objects",
            )
        })?;
        let mut set = MarkerSet {
            name: name.to_string(),
            labels: Vec::with_capacity(entries.len()),
            bindings: Vec::with_capacity(entries.len()),
        };
        for (k, e) in entries.iter().enumerate() {
            let bad = |key: &str, want: &str| {
                Error::invalid(
                    format!("{source}: bindings[{k}].{key}"),
                    e.get(key).map_or("missing".to_string(), |v| v.to_string()),
                    want,
                )
            };
            let label = e
                .get("label")
                .and_then(|v| v.as_str())
                .filter(|l| !l.is_empty())
                .ok_or_else(|| bad("label", "a non-empty string"))?;
            let triangle = e
                .get("triangle")
                .and_then(|v| v.as_u64())
                .and_then(|t| u32::try_from(t).ok())
                .ok_or_else(|| bad("triangle", "a triangle index (an unsigned 32-bit integer)"))?;
            let bary: Vec<f64> = e
                .get("barycentric")
                .and_then(|v| v.as_array())
                .map(|a| a.iter().filter_map(|x| x.as_f64()).collect())
                .filter(|a: &Vec<f64>| {
                    a.len() == 3
                        && a.iter().all(|v| v.is_finite() && *v >= -1e-9)
                        && (a.iter().sum::<f64>() - 1.0).abs() < 1e-9
                })
                .ok_or_else(|| {
                    bad(
                        "barycentric",
                        "three barycentric coordinates >= 0 summing to 1",
                    )
                })?;
            if set.labels.iter().any(|l| l == label) {
                return Err(bad(
                    "label",
                    "a label not given before (labels are distinct)",
                ));
            }
            set.labels.push(label.to_string());
            set.bindings.push(SurfaceBinding {
                triangle,
                barycentric: [bary[0], bary[1], bary[2]],
            });
        }
        if set.is_empty() {
            return Err(Error::invalid(
                format!("{source}: bindings"),
                "[]",
                "at least one marker",
            ));
        }
        Ok(set)
    }

    /// Number of markers.
    pub fn len(&self) -> usize {
        self.bindings.len()
    }

    /// Whether the set has no marker.
    pub fn is_empty(&self) -> bool {
        self.bindings.is_empty()
    }

    /// Marker positions on a surface with these vertices and triangles (the skin's).
    pub fn positions(&self, vertices: &[Point3<f64>], triangles: &[[u32; 3]]) -> Vec<Point3<f64>> {
        self.bindings
            .iter()
            .map(|b| b.point(vertices, triangles))
            .collect()
    }

    /// Checks labels and bindings against a skin with `triangles` triangles.
    pub fn check(&self, triangles: usize) -> Result<()> {
        if self.labels.len() != self.bindings.len() || self.bindings.is_empty() {
            return Err(Error::invalid(
                format!("marker set `{}`", self.name),
                format!(
                    "{} labels, {} bindings",
                    self.labels.len(),
                    self.bindings.len()
                ),
                "one label per binding, at least one marker",
            ));
        }
        for (l, b) in self.labels.iter().zip(&self.bindings) {
            let bary_ok = b.barycentric.iter().all(|v| v.is_finite() && *v >= -1e-9)
                && (b.barycentric.iter().sum::<f64>() - 1.0).abs() < 1e-9;
            if b.triangle as usize >= triangles || !bary_ok {
                return Err(Error::invalid(
                    format!("binding of marker `{l}`"),
                    format!("triangle {} {:?}", b.triangle, b.barycentric),
                    format!(
                        "a triangle below {triangles} and barycentric coordinates >= 0 summing to 1"
                    ),
                ));
            }
        }
        let mut seen = std::collections::HashSet::new();
        if let Some(l) = self.labels.iter().find(|l| !seen.insert(l.as_str())) {
            return Err(Error::invalid(
                format!("marker set `{}`", self.name),
                format!("label `{l}` twice"),
                "distinct labels",
            ));
        }
        Ok(())
    }

    /// A built-in set placed on `skin`: `grid` (the 10 x 6 SLP grid), `chest30` or `oep89`
    /// (see [`MarkerSet::chest30`], [`MarkerSet::oep89`]).
    pub fn builtin(skin: &Skin, name: &str) -> Result<MarkerSet> {
        match name {
            "grid" => Ok(MarkerSet::from_grid(&MarkerGrid::place(skin, 10, 6)?)),
            "chest30" => MarkerSet::chest30(skin),
            "oep89" => MarkerSet::oep89(skin),
            other => Err(Error::invalid("marker set", other, BUILTIN_SETS.join(", "))),
        }
    }

    /// A 30-marker chest-and-back set: five rows from the clavicle line (15 mm below the
    /// suprasternale, as the SLP grid's top row) to 40 mm below the omphalion (the grid's
    /// bottom row), six markers per row: four anterior at 20 and 55 degrees either side of
    /// the midline, and two posterior at 155 degrees either side (over the paraspinal
    /// muscles). Angles are about the trunk's vertical axis at each row, 0 = anterior
    /// midline, positive towards the subject's right. A set of our own for tests and
    /// sweeps of a sparse motion-capture layout, not a published protocol. Labels
    /// `C{row}{F|B}{R|L}{1|2}`: row 1 at the top, F front, B back, R/L the subject's side,
    /// 1 the inner and 2 the outer column.
    pub fn chest30(skin: &Skin) -> Result<MarkerSet> {
        let lm = &skin.landmarks;
        let s = lm.stature / super::REFERENCE_STATURE;
        let top = lm.suprasternale_height - 0.015 * s;
        let bottom = lm.omphalion_height - 0.04 * s;
        let columns = [
            ("FR1", 20.0),
            ("FL1", -20.0),
            ("FR2", 55.0),
            ("FL2", -55.0),
            ("BR1", 155.0),
            ("BL1", -155.0),
        ];
        let mut rows = Vec::new();
        for r in 0..5 {
            let y = top - r as f64 * (top - bottom) / 4.0;
            rows.push((format!("C{}", r + 1), y, columns.to_vec()));
        }
        place_rows(skin, "chest30", &rows)
    }

    /// An 89-marker set after the optoelectronic-plethysmography (OEP) layout of Cala et al.
    /// 1996 (J Appl Physiol 81:2680-2689) and Aliverti et al. 2001 (Ann Biomed Eng
    /// 29:60-70): markers in horizontal rows at anatomical levels (clavicular line,
    /// manubriosternal joint, nipples, xiphoid, lower costal margin, umbilicus, anterior
    /// superior iliac spines) over the front, sides and back. It is not the exact clinical
    /// protocol (whose columns follow the midline, the mid-clavicular and the anterior and
    /// mid-axillary lines palpated on the subject): here the columns are fixed angles about
    /// the trunk's vertical axis and the levels come from the skin's landmarks. Layout: 35
    /// anterior (7 rows x 5 at 0, +-25 and +-50 degrees), 12 lateral (the mid-axillary
    /// line, +-90 degrees, on the six rows below the clavicles, which the arm covers at
    /// the axilla), 42 posterior (7 rows x 6 at +-140, +-160 and +-175 degrees). Row
    /// heights, scaled by stature from a 1.75 m subject: the clavicle line 15 mm below the
    /// suprasternale, the manubriosternal joint 50 mm below it (the sternal angle lies about
    /// 5 cm below the jugular notch), the nipple line, the xiphoid halfway between the
    /// nipples and the tenth rib, the lower costal margin (tenth rib), the omphalion, and
    /// 80 mm below it (the anterior superior iliac spines), kept 20 mm above the skin's
    /// bottom. Labels `O{row}{A|L|P}{k}` (anterior, lateral, posterior; k from the subject's
    /// right).
    pub fn oep89(skin: &Skin) -> Result<MarkerSet> {
        let lm = &skin.landmarks;
        let s = lm.stature / super::REFERENCE_STATURE;
        let levels = [
            lm.suprasternale_height - 0.015 * s,
            lm.suprasternale_height - 0.05 * s,
            lm.chest_height,
            0.5 * (lm.chest_height + lm.tenth_rib_height),
            lm.tenth_rib_height,
            lm.omphalion_height,
            (lm.omphalion_height - 0.08 * s).max(lm.bottom_height + 0.02 * s),
        ];
        let anterior = [50.0, 25.0, 0.0, -25.0, -50.0];
        let posterior = [140.0, 160.0, 175.0, -175.0, -160.0, -140.0];
        let mut rows = Vec::new();
        for (r, &y) in levels.iter().enumerate() {
            let mut cols: Vec<(String, f64)> = Vec::new();
            for (k, a) in anterior.iter().enumerate() {
                cols.push((format!("A{}", k + 1), *a));
            }
            if r > 0 {
                cols.push(("L1".into(), 90.0));
                cols.push(("L2".into(), -90.0));
            }
            for (k, a) in posterior.iter().enumerate() {
                cols.push((format!("P{}", k + 1), *a));
            }
            rows.push((format!("O{}", r + 1), y, cols));
        }
        place_rows(skin, "oep89", &rows)
    }
}

/// A row of markers: its label, height [m] and (column label, angle [deg]) pairs.
type Row<C> = (String, f64, Vec<(C, f64)>);

/// Places rows of markers: each `(row label, height, [(column label, angle in degrees)])`
/// marker sits where a horizontal ray from the skin's axis at that height, at that angle
/// (0 anterior, +90 the subject's right), leaves the skin.
fn place_rows<C: AsRef<str>>(skin: &Skin, name: &str, rows: &[Row<C>]) -> Result<MarkerSet> {
    let mut labels = Vec::new();
    let mut bindings = Vec::new();
    for (row, y, cols) in rows {
        let ring = skin.ring_near(*y);
        let centre = ring.iter().fold(Vector3::zeros(), |a, p| a + p.coords) / ring.len() as f64;
        let origin = Point3::new(centre.x, *y, centre.z);
        for (col, angle) in cols {
            let label = format!("{row}{}", col.as_ref());
            let a = angle.to_radians();
            let d = Vector3::new(a.cos(), 0.0, a.sin());
            let b = cast_out(skin, &origin, &d).ok_or_else(|| {
                Error::State(format!(
                    "marker {label} of set {name} (y = {y:.3} m, {angle} deg) misses the skin"
                ))
            })?;
            labels.push(label);
            bindings.push(b);
        }
    }
    Ok(MarkerSet {
        name: name.into(),
        labels,
        bindings,
    })
}

/// The outermost skin point along the ray `o + t d`, t > 0.
fn cast_out(skin: &Skin, o: &Point3<f64>, d: &Vector3<f64>) -> Option<SurfaceBinding> {
    let mut best: Option<(f64, SurfaceBinding)> = None;
    for (ti, t) in skin.triangles.iter().enumerate() {
        let (a, b, c) = (
            &skin.vertices[t[0] as usize],
            &skin.vertices[t[1] as usize],
            &skin.vertices[t[2] as usize],
        );
        if let Some((dist, u, v)) = ray_triangle(o, d, a, b, c)
            && dist > 0.0
            && best.as_ref().is_none_or(|(bd, _)| dist > *bd)
        {
            best = Some((
                dist,
                SurfaceBinding {
                    triangle: ti as u32,
                    barycentric: [1.0 - u - v, u, v],
                },
            ));
        }
    }
    best.map(|(_, b)| b)
}
