//! A stand-in skeleton for the skin: the reference rib centrelines (right side from
//! `data/rib_centerlines_right_mm.csv`, mirrored for the left), a sternum and a spine
//! centreline, scaled to the subject's stature. The skin generator uses it as the
//! interior the surface must enclose, and the skinning tests and benchmarks use it as
//! handles until the anatomy module supplies the subject's own bones.

use crate::anatomy::Subject;
use crate::{Error, Result};
use nalgebra::Point3;

/// Stature [m] of the subject the reference centrelines were placed for.
pub const REFERENCE_STATURE: f64 = 1.75;

const RIB_CSV: &str = include_str!("../../../data/rib_centerlines_right_mm.csv");

/// Vertebral body centres (x, y) [mm] of the reference spine, caudal to cranial.
/// T1-T12: `vert_origin` of the costovertebral joints of the Bruno et al. thoracolumbar
/// OpenSim model (rib_joints_right_mm.csv); lumbar and cervical centres placed with that
/// model's segment lengths and sagittal angles (spine_segments.csv: lumbar lordosis about
/// 43 deg, cervical column leaning forward).
pub const SPINE_CENTRES_MM: [(f64, f64); 24] = [
    (-40.0, 900.0),    // S1 plateau
    (-22.0, 940.0),    // L5
    (-12.0, 972.0),    // L4
    (-6.0, 1004.0),    // L3
    (-6.0, 1036.0),    // L2
    (-10.0, 1067.0),   // L1
    (-17.0, 1100.0),   // T12/L1 disc
    (-26.77, 1134.27), // T12
    (-38.14, 1165.49), // T11
    (-46.13, 1193.38), // T10
    (-51.57, 1221.33), // T9
    (-54.58, 1245.83), // T8
    (-55.42, 1269.99), // T7
    (-53.64, 1295.39), // T6
    (-49.44, 1319.22), // T5
    (-42.62, 1343.02), // T4
    (-33.97, 1364.41), // T3
    (-24.8, 1383.23),  // T2
    (-15.53, 1399.94), // T1
    (-8.0, 1419.0),    // C7
    (-3.0, 1436.0),    // C6
    (1.0, 1453.0),     // C5
    (4.0, 1470.0),     // C4
    (6.0, 1486.0),     // C3
];

/// The stand-in skeleton, in metres, ISB frame (x anterior, y superior, z right).
#[derive(Clone, Debug)]
pub struct ReferenceSkeleton {
    /// 24 ribs, right 1-12 then left 1-12, each as (name, centreline from head to
    /// costochondral junction, 11 samples).
    pub ribs: Vec<(String, Vec<Point3<f64>>)>,
    /// Sternum centreline, jugular notch to xiphoid tip.
    pub sternum: Vec<Point3<f64>>,
    /// Spine centreline through the vertebral bodies, caudal to cranial.
    pub spine: Vec<Point3<f64>>,
    /// Spinous process tips (posterior limit of the vertebrae) of T1-L5.
    pub spinous_tips: Vec<Point3<f64>>,
}

/// Parses the reference rib centrelines (right side), in millimetres.
fn parse_ribs() -> Result<Vec<Vec<[f64; 3]>>> {
    let mut ribs: Vec<Vec<[f64; 3]>> = vec![Vec::new(); 12];
    for (i, line) in RIB_CSV.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') || line.starts_with("rib,") {
            continue;
        }
        let parse_err = |column: usize, message: String| Error::Parse {
            path: "data/rib_centerlines_right_mm.csv".into(),
            line: i + 1,
            column,
            message,
        };
        let f: Vec<&str> = line.split(',').collect();
        if f.len() != 5 {
            return Err(parse_err(
                1,
                format!("expected 5 fields, found {}", f.len()),
            ));
        }
        let rib: usize = f[0]
            .parse()
            .map_err(|_| parse_err(1, format!("bad rib number `{}`", f[0])))?;
        if !(1..=12).contains(&rib) {
            return Err(parse_err(1, format!("rib number {rib} outside 1-12")));
        }
        let mut p = [0.0; 3];
        for k in 0..3 {
            p[k] = f[2 + k]
                .parse()
                .map_err(|_| parse_err(3 + k, format!("bad number `{}`", f[2 + k])))?;
        }
        ribs[rib - 1].push(p);
    }
    Ok(ribs)
}

impl ReferenceSkeleton {
    /// The reference skeleton scaled by `stature / 1.75 m` about the floor origin.
    pub fn for_subject(subject: &Subject) -> Result<Self> {
        subject.validate()?;
        let s = subject.stature / REFERENCE_STATURE * 1e-3;
        let p = |x: f64, y: f64, z: f64| Point3::new(x * s, y * s, z * s);
        let right = parse_ribs()?;
        let mut ribs = Vec::with_capacity(24);
        for (side, sign) in [("right", 1.0), ("left", -1.0)] {
            for (k, rib) in right.iter().enumerate() {
                let pts = rib.iter().map(|q| p(q[0], q[1], sign * q[2])).collect();
                ribs.push((format!("rib{}_{side}", k + 1), pts));
            }
        }
        // Sternum: manubrium from the jugular notch, body down to the seventh costal cartilage,
        // xiphoid; lengths 51 / 102 mm (CT norms, physiology reference), sternal angle ~162 deg.
        let sternum = vec![
            p(45.0, 1405.0, 0.0),
            p(62.0, 1357.0, 0.0),
            p(98.0, 1262.0, 0.0),
            p(106.0, 1215.0, 0.0),
        ];
        let spine = SPINE_CENTRES_MM
            .iter()
            .map(|&(x, y)| p(x, y, 0.0))
            .collect();
        // Spinous tips about 70 mm behind the body centre (body, canal, lamina and process).
        let spinous_tips = SPINE_CENTRES_MM[1..19]
            .iter()
            .map(|&(x, y)| p(x - 70.0, y - 12.0, 0.0))
            .collect();
        Ok(ReferenceSkeleton {
            ribs,
            sternum,
            spine,
            spinous_tips,
        })
    }

    /// Every bone sample of the skeleton: rib centrelines, sternum, spinous tips.
    pub fn bone_points(&self) -> Vec<Point3<f64>> {
        let mut out: Vec<Point3<f64>> = self
            .ribs
            .iter()
            .flat_map(|(_, r)| r.iter().copied())
            .collect();
        out.extend(self.sternum.iter().copied());
        out.extend(self.spinous_tips.iter().copied());
        out
    }

    /// Bone samples densified to at most `step` metres apart along each polyline, for
    /// enclosure constraints and gap reports.
    pub fn dense_bone_points(&self, step: f64) -> Vec<Point3<f64>> {
        let mut out = Vec::new();
        let mut add_polyline = |pts: &[Point3<f64>]| {
            for w in pts.windows(2) {
                let n = ((w[1] - w[0]).norm() / step).ceil().max(1.0) as usize;
                for i in 0..n {
                    out.push(w[0] + (w[1] - w[0]) * (i as f64 / n as f64));
                }
            }
            if let Some(last) = pts.last() {
                out.push(*last);
            }
        };
        for (_, r) in &self.ribs {
            add_polyline(r);
        }
        add_polyline(&self.sternum);
        add_polyline(&self.spinous_tips);
        out
    }
}
