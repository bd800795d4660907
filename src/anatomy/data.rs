//! The anatomy tables compiled into the library (files under `data/anatomy/`, sources named in
//! their comment headers), parsed once.

use std::collections::HashMap;

/// Right rib centrelines [mm]: per rib level 1..12, 11 stations head -> costochondral junction.
/// Source: the generic ribs and spine of the Bruno/Schmid thoracolumbar OpenSim models (Bruno,
/// Bouxsein & Anderson 2015, J Biomech Eng 137:081003); data/anatomy/README.md.
const RIB_CENTRELINES: &str = include_str!("../../data/anatomy/rib_centerlines_right_mm.csv");
/// Costovertebral joints [mm]: rib head, hinge axis, rib end per level.
/// Source: the generic ribs and spine of the Bruno/Schmid thoracolumbar OpenSim models (Bruno,
/// Bouxsein & Anderson 2015, J Biomech Eng 137:081003); data/anatomy/README.md.
const RIB_JOINTS: &str = include_str!("../../data/anatomy/rib_joints_right_mm.csv");
/// Spine joint offsets [mm] and sagittal angles [deg].
/// Source: the generic ribs and spine of the Bruno/Schmid thoracolumbar OpenSim models (Bruno,
/// Bouxsein & Anderson 2015, J Biomech Eng 137:081003); data/anatomy/README.md.
const SPINE_SEGMENTS: &str = include_str!("../../data/anatomy/spine_segments.csv");
/// ANSUR II torso regressions.
/// Source: ANSUR II (Gordon et al. 2014, 2012 Anthropometric Survey of U.S. Army Personnel),
/// least-squares fits on 4082 men and 1986 women of the public release (the fitting script is
/// not in the repository; the file's header names the data).
const ANSUR2: &str = include_str!("../../data/anatomy/torso_anthropometry_ansur2.csv");
/// Seed thesis Table 1.1 masses [kg].
/// Source: Maldonado 2011 (seed thesis), Table 1.1, after the Breathe Easy model (agrees:
/// copied): sternum 0.58 kg, costal cartilages, abdominal contents 8 kg, vertebrae.
const BODY_MASSES: &str = include_str!("../../data/anatomy/body_masses_thesis.csv");

/// Data rows of an embedded CSV: comment lines and the header skipped, cells split on commas.
fn rows(text: &str) -> impl Iterator<Item = Vec<&str>> {
    text.lines()
        .filter(|l| !l.trim().is_empty() && !l.starts_with('#'))
        .skip(1)
        .map(|l| l.split(',').map(str::trim).collect())
}

/// Parses an embedded numeric cell; the tables are compiled in and checked by the tests, so a
/// malformed cell is a build defect and reads as NaN (caught by the geometry checks).
fn num(cell: &str) -> f64 {
    cell.parse().unwrap_or(f64::NAN)
}

/// Reference rib centreline stations [m], `[level-1][station]`, right side.
pub fn rib_centrelines() -> Vec<Vec<[f64; 3]>> {
    let mut out = vec![Vec::new(); 12];
    for r in rows(RIB_CENTRELINES) {
        let level = num(r[0]) as usize;
        if (1..=12).contains(&level) {
            out[level - 1].push([num(r[2]) * 1e-3, num(r[3]) * 1e-3, num(r[4]) * 1e-3]);
        }
    }
    out
}

/// One costovertebral joint of the reference rib cage (right side), metres.
#[derive(Clone, Copy, Debug)]
pub struct RibJoint {
    /// Rib level 1..12.
    pub level: usize,
    /// Centre of the thoracic vertebra the rib articulates with.
    pub vertebra: [f64; 2],
    /// Rib head (hinge point).
    pub head: [f64; 3],
    /// Unit hinge axis (rib-neck axis), from the head laterally and dorsally.
    pub axis: [f64; 3],
    /// Bony costochondral junction.
    pub end: [f64; 3],
}

/// Reference costovertebral joints, levels 1..12.
pub fn rib_joints() -> Vec<RibJoint> {
    rows(RIB_JOINTS)
        .map(|r| RibJoint {
            level: num(r[0]) as usize,
            vertebra: [num(r[1]) * 1e-3, num(r[2]) * 1e-3],
            head: [num(r[4]) * 1e-3, num(r[5]) * 1e-3, num(r[6]) * 1e-3],
            axis: [num(r[7]), num(r[8]), num(r[9])],
            end: [num(r[12]) * 1e-3, num(r[13]) * 1e-3, num(r[14]) * 1e-3],
        })
        .collect()
}

/// Spine joints from the sacrum upward: (child body name, offset [m], sagittal angle [deg]).
/// The first two rows (pelvis placement, L5-S1) carry no offset in the table and are returned
/// with the documented L5-S1 offset from the sacrum body origin (106.8 mm).
pub fn spine_segments() -> Vec<(String, f64, f64)> {
    rows(SPINE_SEGMENTS)
        .skip(1)
        .map(|r| {
            let offset = if r[3].starts_with("n/a") {
                0.1068
            } else {
                num(r[3]) * 1e-3
            };
            (r[2].to_string(), offset, num(r[4]))
        })
        .collect()
}

/// One ANSUR II regression: dim_mm = b0 + b_stature stature_mm + b_weight kg + b_age years.
#[derive(Clone, Copy, Debug)]
pub struct Regression {
    /// Intercept [mm].
    pub b0: f64,
    /// Per mm of stature.
    pub stature: f64,
    /// Per kg of body mass.
    pub weight: f64,
    /// Per year of age.
    pub age: f64,
}

impl Regression {
    /// Predicted dimension [m] for stature [m], mass [kg], age [y].
    pub fn predict(&self, stature_m: f64, mass: f64, age: f64) -> f64 {
        (self.b0 + self.stature * stature_m * 1e3 + self.weight * mass + self.age * age) * 1e-3
    }
}

/// ANSUR II regressions keyed by (sex code "M"/"F", dimension name).
pub fn ansur2() -> HashMap<(String, String), Regression> {
    rows(ANSUR2)
        .map(|r| {
            let reg = Regression {
                b0: num(r[5]),
                stature: num(r[6]),
                weight: num(r[7]),
                age: num(r[8]),
            };
            ((r[0].to_string(), r[1].to_string()), reg)
        })
        .collect()
}

/// Seed thesis Table 1.1 masses [kg] by part name.
pub fn body_masses() -> HashMap<String, f64> {
    rows(BODY_MASSES)
        .map(|r| (r[0].to_string(), num(r[1])))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tables_parse_completely() {
        let c = rib_centrelines();
        assert!(
            c.iter()
                .all(|r| r.len() == 11 && r.iter().flatten().all(|v| v.is_finite()))
        );
        let j = rib_joints();
        assert_eq!(j.len(), 12);
        for joint in &j {
            let n = joint.axis.iter().map(|a| a * a).sum::<f64>().sqrt();
            assert!(
                (n - 1.0).abs() < 0.02,
                "axis of rib {} has norm {n}",
                joint.level
            );
        }
        let s = spine_segments();
        assert_eq!(s.len(), 25);
        assert!(s.iter().all(|(_, o, a)| o.is_finite() && a.is_finite()));
        assert_eq!(ansur2().len(), 40);
        assert_eq!(body_masses()["sternum"], 0.58);
    }
}
