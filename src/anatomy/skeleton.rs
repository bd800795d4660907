//! The skeleton of a subject: spine joint centres, 24 ribs with their rib-neck hinge axes
//! (bone plus costal cartilage, one rigid body each, thesis 1.3.2), the sternum, and the
//! cartilage joints (ribs 1-7 to the sternum, 8-10 to the cartilage above, 11-12 free).
//!
//! Geometry comes from the reference rib cage (`data/anatomy/`), scaled to the subject with
//! ANSUR II predictions: vertical lengths with sitting height, lateral with chest breadth,
//! sagittal with chest depth.

use super::data::{self, Regression};
use super::subject::{Sex, Subject};
use nalgebra::{Point3, Unit, Vector3};
use std::collections::HashMap;

/// Side of a bilateral structure.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Side {
    /// The subject's right (z > 0).
    Right,
    /// The subject's left (z < 0).
    Left,
}

impl Side {
    /// +1 for right, -1 for left: the sign of z.
    pub fn sign(self) -> f64 {
        match self {
            Side::Right => 1.0,
            Side::Left => -1.0,
        }
    }
}

/// Anisotropic scaling from the reference rib cage to the subject.
#[derive(Clone, Copy, Debug)]
pub struct Scale {
    /// Sagittal (x) factor: chest depth ratio.
    pub x: f64,
    /// Vertical (y) factor: sitting height ratio.
    pub y: f64,
    /// Lateral (z) factor: chest breadth ratio.
    pub z: f64,
    /// Height of the reference sacrum joint [m] (reference frame).
    pub y_ref_origin: f64,
    /// Height of the subject's sacrum joint [m].
    pub y_origin: f64,
    /// x about which sagittal scaling is applied [m] (the spine).
    pub x_pivot: f64,
}

/// Reference body the rib-cage data were measured on: a 1.75 m, 75 kg, 30-year-old man.
/// Unsourced: the rib and spine tables' source subject is about 1.68-1.75 m tall
/// (data/anatomy/*.csv headers); its mass and age are not stated there, and 75 kg and 30 y are
/// chosen as the default subject. Literature, for a reference person rather than the tables'
/// subject: the ICRP Reference Male is 1.76 m and 73 kg (ICRP Publication 89, 2002, as built into
/// the ICRP Publication 110 phantoms, 2009; its Reference Female, 1.63 m and 60 kg, is the default
/// woman here), and ICRP Publication 23 (1975) set Reference Man's age at 20-30 years; ours
/// 1.75 m, 75 kg, 30 y: within 1 % and 3 % and at the upper end of the age range, but ICRP gives
/// reference values without a spread, and they do not describe the tables' subject.
pub const REFERENCE_BODY: (f64, f64, f64) = (1.75, 75.0, 30.0);

impl Scale {
    /// Scale factors of `subject` against the reference body (ANSUR II regressions).
    pub fn for_subject(subject: &Subject, ansur: &HashMap<(String, String), Regression>) -> Scale {
        let sex = match subject.sex {
            Sex::Male => "M",
            Sex::Female => "F",
        };
        let dim = |s: &str, name: &str, stature: f64, mass: f64, age: f64| {
            ansur
                .get(&(s.to_string(), name.to_string()))
                .map(|r| r.predict(stature, mass, age))
                .unwrap_or(f64::NAN)
        };
        let (rs, rm, ra) = REFERENCE_BODY;
        let ratio = |name: &str| {
            dim(sex, name, subject.stature, subject.mass, subject.age) / dim("M", name, rs, rm, ra)
        };
        Scale {
            x: ratio("chestdepth"),
            y: ratio("sittingheight"),
            z: ratio("chestbreadth"),
            y_ref_origin: 0.890,
            y_origin: 0.890 * subject.stature / rs,
            x_pivot: -0.05,
        }
    }

    /// Maps a reference point [m] to the subject.
    pub fn point(&self, p: [f64; 3]) -> Point3<f64> {
        Point3::new(
            self.x_pivot + (p[0] - self.x_pivot) * self.x,
            self.y_origin + (p[1] - self.y_ref_origin) * self.y,
            p[2] * self.z,
        )
    }

    /// Maps a reference direction to the subject (renormalised).
    pub fn direction(&self, d: [f64; 3]) -> Unit<Vector3<f64>> {
        Unit::new_normalize(Vector3::new(d[0] * self.x, d[1] * self.y, d[2] * self.z))
    }
}

/// A rib: bone and costal cartilage turning as one rigid body about its rib-neck hinge.
#[derive(Clone, Debug)]
pub struct Rib {
    /// Level 1..12.
    pub level: usize,
    /// Side.
    pub side: Side,
    /// Rib head: a point on the hinge axis.
    pub head: Point3<f64>,
    /// Unit hinge axis, oriented so that a positive rotation lifts the ventral end (inspiration).
    pub axis: Unit<Vector3<f64>>,
    /// Bony centreline, head to costochondral junction.
    pub bone: Vec<Point3<f64>>,
    /// Costal cartilage polyline from the costochondral junction to its joint (empty for 11-12).
    pub cartilage: Vec<Point3<f64>>,
    /// Lumped mass points (position, mass [kg]) of bone, cartilage and carried chest-wall tissue.
    pub mass_points: Vec<(Point3<f64>, f64)>,
}

impl Rib {
    /// Body index of this rib: level-1 for the right side, 12 + level-1 for the left.
    pub fn index(&self) -> usize {
        rib_index(self.level, self.side)
    }

    /// Total mass [kg].
    pub fn mass(&self) -> f64 {
        self.mass_points.iter().map(|(_, m)| m).sum()
    }

    /// Moment of inertia about the hinge axis [kg m^2]: sum of m r_perp^2 over the mass points.
    pub fn inertia_about_axis(&self) -> f64 {
        self.mass_points
            .iter()
            .map(|(p, m)| {
                let r = p - self.head;
                let perp = r - self.axis.into_inner() * r.dot(&self.axis);
                m * perp.norm_squared()
            })
            .sum()
    }

    /// Centre of mass.
    pub fn centre_of_mass(&self) -> Point3<f64> {
        let m = self.mass();
        let s = self
            .mass_points
            .iter()
            .fold(Vector3::zeros(), |acc, (p, mi)| acc + p.coords * *mi);
        Point3::from(s / m)
    }

    /// The whole rib polyline: bone then cartilage (without repeating the junction).
    pub fn polyline(&self) -> Vec<Point3<f64>> {
        let mut out = self.bone.clone();
        out.extend(self.cartilage.iter().skip(1).copied());
        out
    }

    /// Ventral end of the bone (costochondral junction).
    pub fn bone_end(&self) -> Point3<f64> {
        *self.bone.last().unwrap_or(&self.head)
    }
}

/// Body index of a rib.
pub fn rib_index(level: usize, side: Side) -> usize {
    match side {
        Side::Right => level - 1,
        Side::Left => 12 + level - 1,
    }
}

/// The sternum: manubrium and body, one rigid body.
#[derive(Clone, Debug)]
pub struct Sternum {
    /// Jugular notch (top of the manubrium).
    pub jugular: Point3<f64>,
    /// Sternal angle (manubrium-body joint).
    pub angle: Point3<f64>,
    /// Xiphisternal joint (bottom of the body).
    pub xiphisternal: Point3<f64>,
    /// Mass [kg] (thesis Table 1.1: 0.58).
    pub mass: f64,
    /// Where the cartilage of rib k (1..7) joins the sternum, on the midline.
    pub costal_notches: [Point3<f64>; 7],
}

impl Sternum {
    /// Centre of mass: mass-weighted midpoint of the two segments.
    pub fn centre_of_mass(&self) -> Point3<f64> {
        let lm = (self.angle - self.jugular).norm();
        let lb = (self.xiphisternal - self.angle).norm();
        let cm = nalgebra::center(&self.jugular, &self.angle);
        let cb = nalgebra::center(&self.angle, &self.xiphisternal);
        Point3::from((cm.coords * lm + cb.coords * lb) / (lm + lb))
    }

    /// Inertia tensor about the centre of mass [kg m^2]: a slender plate 3 cm wide with the
    /// mass spread along the two segments.
    pub fn inertia(&self) -> nalgebra::Matrix3<f64> {
        let c = self.centre_of_mass();
        let mut inertia = nalgebra::Matrix3::zeros();
        let n = 20;
        let pts: Vec<Point3<f64>> = (0..n)
            .map(|i| {
                let s = (i as f64 + 0.5) / n as f64;
                if s < 0.35 {
                    self.jugular + (self.angle - self.jugular) * (s / 0.35)
                } else {
                    self.angle + (self.xiphisternal - self.angle) * ((s - 0.35) / 0.65)
                }
            })
            .collect();
        for p in pts {
            for dz in [-0.012, 0.012] {
                let r = p.coords + Vector3::new(0.0, 0.0, dz) - c.coords;
                let m = self.mass / (2 * n) as f64;
                inertia +=
                    (nalgebra::Matrix3::identity() * r.norm_squared() - r * r.transpose()) * m;
            }
        }
        inertia
    }
}

/// Spine joint centres from the sacrum up to the skull, with names.
#[derive(Clone, Debug)]
pub struct Spine {
    /// (body name, joint centre) from the sacrum upward: sacrum, lumbar5..1, thoracic12..1,
    /// cerv7..1, skull.
    pub joints: Vec<(String, Point3<f64>)>,
}

impl Spine {
    /// The joint centre of a named body (`cerv6`, `thoracic12`, ...).
    pub fn joint(&self, name: &str) -> Option<Point3<f64>> {
        self.joints.iter().find(|(n, _)| n == name).map(|(_, p)| *p)
    }
}

/// Builds the spine: joint centres placed from segment lengths and sagittal angles
/// (`data/anatomy/spine_segments.csv`), lengths scaled with sitting height.
///
/// The sacrum joint sits at the subject's origin height; the thoracic joints are then pinned to
/// the reference vertebra centres of the rib-joint table so that ribs and spine agree.
pub fn build_spine(scale: &Scale) -> Spine {
    let segments = data::spine_segments();
    let mut joints = vec![(
        "sacrum".to_string(),
        scale.point([-0.05, scale.y_ref_origin, 0.0]),
    )];
    // Chain upward; the sagittal angle accumulates (negative = flexion/kyphosis, tilting forward).
    let mut angle: f64 = 0.0;
    let mut p = joints[0].1;
    for (name, offset, deg) in segments {
        angle += deg.to_radians();
        let dir = Vector3::new(-angle.sin() * scale.x, angle.cos() * scale.y, 0.0).normalize();
        p += dir * offset * scale.y;
        joints.push((name, p));
    }
    // Pin the thoracic vertebrae to the rib-joint table's vertebra centres (same lineage), and
    // carry the cervical spine and skull along with T1.
    let chained_t1 = joints
        .iter()
        .find(|(n, _)| n == "thoracic1")
        .map(|(_, p)| *p);
    for j in data::rib_joints() {
        let name = format!("thoracic{}", j.level);
        if let Some(entry) = joints.iter_mut().find(|(n, _)| *n == name) {
            entry.1 = scale.point([j.vertebra[0], j.vertebra[1], 0.0]);
        }
    }
    let pinned_t1 = joints
        .iter()
        .find(|(n, _)| n == "thoracic1")
        .map(|(_, p)| *p);
    if let (Some(a), Some(b)) = (chained_t1, pinned_t1) {
        for (name, p) in joints.iter_mut() {
            if name.starts_with("cerv") || name == "skull" {
                *p += b - a;
            }
        }
    }
    Spine { joints }
}

/// Linear density of rib bone [kg/m] for a 75 kg adult (about 0.7 kg for all 24 ribs).
/// Unsourced: no source: chosen by hand in the first anatomy (commit 270ac4a). No measured rib
/// mass was found; rib cross-sectional areas of 240 adults, ribs 2-11 ("Cross-sectional
/// properties of rib geometry from an adult population", Front Bioeng Biotechnol 2023,
/// doi:10.3389/fbioe.2023.1158242), would give one with a bone density, but their values were
/// not read; nor were the sixth-rib cross-sections of 33 adults (Holcombe, Kang, Derstine, Wang
/// & Agnew 2019, J Anat 235:883, PMID 31225915: areas as corridors, not in the abstract).
/// Skeleton mass 8.0 kg in men, a wet mass derived from the dry bones of 486 adults (Chen et al. 1995, Chin J
/// Radiol Med Prot 15:317); the ribs' share is not in the abstract. At 1.920 g/cm^3, adult
/// mineral bone as tabulated for voxel phantoms (doi:10.1016/j.rpor.2014.03.004, Table 1),
/// ours is 57 mm^2 of solid bone per rib.
pub const RIB_BONE_DENSITY: f64 = 0.11;
/// Fraction of body mass carried by the ribs as chest-wall soft tissue (intercostal and
/// pectoral muscle, fat, skin) moving with them: about 3 kg for a 75 kg adult. Table 1.1 of
/// the thesis gives the bony and cartilage masses only; the wall's own inertia rides on the ribs.
/// Unsourced: no source: chosen by hand in the first anatomy (commit 270ac4a). No regional
/// (chest-wall) share of muscle, fat and skin was found: the ICRP reference male's whole-body
/// values, 29 kg of skeletal muscle, 18.2 kg of adipose tissue and 3.3 kg of skin in 73 kg
/// (ICRP Publication 89, 2002, as tabulated in Turner, Atoms, Radiation, and Radiation
/// Protection, Table 16.1), are not split by region; ours, 3 kg, is 6 % of their sum.
pub const CHEST_WALL_MASS_FRACTION: f64 = 0.04;

/// Costal cartilage mass [kg] of rib `level` (thesis Table 1.1: ribs 2-5 individually, the
/// "lower rib cartilage" 0.47 kg shared by the cartilages of ribs 6-10 on both sides; rib 1's
/// short cartilage, not listed, is [`RIB1_CARTILAGE_MASS`]).
/// Source: seed thesis Table 1.1 (data/anatomy/body_masses_thesis.csv; agrees: read from it).
fn cartilage_mass(level: usize, masses: &HashMap<String, f64>) -> f64 {
    let get = |k: &str, default: f64| masses.get(k).copied().unwrap_or(default);
    match level {
        1 => RIB1_CARTILAGE_MASS,
        2..=5 => get(&format!("rib{level}_cartilage"), 0.05),
        6..=10 => get("lower_rib_cartilage", 0.47) / 10.0,
        _ => 0.0,
    }
}

/// Mass of the first rib's costal cartilage [kg], which Table 1.1 of the seed thesis does not
/// list.
/// Unsourced: no source: chosen below rib 2's 0.03 kg, its cartilage being the shortest. No
/// measured costal cartilage mass was found (CT studies of costal cartilage for grafts measure
/// the lengths of ribs 6-8's cartilages, not masses: Acta Otolaryngol 2011, 131:67).
pub const RIB1_CARTILAGE_MASS: f64 = 0.02;

/// Lengths of the manubrium and the sternal body and the stature they are scaled from, men
/// then women: (manubrium [m], body [m], stature [m]).
/// Source: multidetector CT of 200 adults (PMID 29345718, 2018): manubrium 51.2 +- 6 mm in
/// men and 46.7 +- 5.1 mm in women, body 102.4 +- 13.3 and 86.6 +- 9.7 mm (agrees: rounded).
/// The reference statures 1.75 m and 1.63 m are the default man and woman, not that cohort's.
pub const STERNUM_LENGTHS: [(f64, f64, f64); 2] = [(0.051, 0.102, 1.75), (0.047, 0.087, 1.63)];

/// Sternal angle, between the manubrium and the body [deg].
/// Source: the same CT study (PMID 29345718): 162.2 +- 6.2 deg in men, 163.8 +- 5.8 deg in
/// women; ours 162 for both (agrees).
pub const STERNAL_ANGLE_DEG: f64 = 162.0;

/// Inclination of the sternal body from the vertical, lower end ventral [deg].
/// Unsourced: no source: chosen by hand in the first anatomy (commit 270ac4a); no measured
/// inclination of the sternum in upright adults was found. What was found measures other
/// quantities: the sternal curvature angle on lateral chest radiographs, 22.0 +- 7.7 deg in 196
/// controls of a pectus study (Lee, Zavala-Garcia, Teekappanavar, Lee, Idowu & Kim 2016,
/// Pediatr Surg Int, doi:10.1007/s00383-016-3996-9), is the bend of the bone, not its tilt;
/// CT of 1,035 young adults places the jugular notch at T2-T3 and the sternal angle at T4-T5
/// (vertebral levels, not an angle).
pub const STERNUM_BODY_TILT_DEG: f64 = 15.0;

/// Length of a polyline.
pub fn polyline_length(points: &[Point3<f64>]) -> f64 {
    points.windows(2).map(|w| (w[1] - w[0]).norm()).sum()
}

/// The point at arc length `s` along a polyline (clamped to its ends).
pub fn point_at(points: &[Point3<f64>], s: f64) -> Point3<f64> {
    let mut left = s.max(0.0);
    for w in points.windows(2) {
        let l = (w[1] - w[0]).norm();
        if left <= l && l > 0.0 {
            return w[0] + (w[1] - w[0]) * (left / l);
        }
        left -= l;
    }
    *points.last().unwrap_or(&Point3::origin())
}

/// Builds the sternum (manubrium and body lengths by sex, CT norms: 51/102 mm men, 47/87 mm
/// women, scaled with stature; sternal angle 162 deg) hanging from a jugular notch placed
/// ventral to and just above the first ribs' ends.
pub fn build_sternum(subject: &Subject, scale: &Scale, masses: &HashMap<String, f64>) -> Sternum {
    let joints = data::rib_joints();
    let e1 = scale.point(joints[0].end);
    let (manubrium, body, ref_stature) = match subject.sex {
        Sex::Male => STERNUM_LENGTHS[0],
        Sex::Female => STERNUM_LENGTHS[1],
    };
    let k = subject.stature / ref_stature;
    // Body inclined from the vertical (lower end ventral); the manubrium by the sternal
    // angle's supplement more (162 deg: 18 deg).
    let body_tilt = STERNUM_BODY_TILT_DEG.to_radians();
    let manubrium_tilt = body_tilt + (180.0 - STERNAL_ANGLE_DEG).to_radians();
    let jugular = Point3::new(e1.x + 0.021 * scale.x, e1.y + 0.019 * scale.y, 0.0);
    let angle = jugular
        + Vector3::new(
            manubrium_tilt.sin() * scale.x,
            -manubrium_tilt.cos() * scale.y,
            0.0,
        ) * manubrium
            * k;
    let xiphisternal =
        angle + Vector3::new(body_tilt.sin() * scale.x, -body_tilt.cos() * scale.y, 0.0) * body * k;
    let along = |f: f64| angle + (xiphisternal - angle) * f;
    let costal_notches = [
        jugular + (angle - jugular) * 0.35,
        angle,
        along(0.25),
        along(0.5),
        along(0.72),
        along(0.9),
        xiphisternal,
    ];
    Sternum {
        jugular,
        angle,
        xiphisternal,
        mass: masses.get("sternum").copied().unwrap_or(0.58),
        costal_notches,
    }
}

/// Half-width of the sternum where the cartilages join it [m]: 28 mm wide. Chosen by hand in the
/// first anatomy (commit 270ac4a), used at all seven costal notches.
/// Source: CT of 144 cardiovascular-surgery patients (Kawamura, Masai, Matsue, Yoshikawa & Sawa 2013, Asian Cardiovasc
/// Thorac Ann 21:331): the bone-marrow (inner) width of the sternal body is 23.4 +- 3.7 mm in
/// men and 20.8 +- 2.8 mm in women; ours, the outer width, is 4.6 mm more than the men's marrow
/// width, 2.3 mm for each cortex (agrees for the body, ribs 2-7). The manubrium, where rib 1
/// joins, is wider (marrow 38.6 +- 3.9 mm in men, 34.5 +- 3.3 mm in women): narrower than that
/// for rib 1.
pub const STERNUM_HALF_WIDTH: f64 = 0.014;

/// Builds the 24 ribs: bone from the reference centrelines, cartilage to the sternum (1-7) or
/// to the cartilage above (8-10), hinge axes oriented so that positive rotation is inspiratory,
/// and lumped mass points (bone, cartilage, carried chest-wall tissue).
pub fn build_ribs(
    subject: &Subject,
    scale: &Scale,
    sternum: &Sternum,
    masses: &HashMap<String, f64>,
) -> Vec<Rib> {
    let centrelines = data::rib_centrelines();
    let joints = data::rib_joints();
    let mut ribs: Vec<Rib> = Vec::with_capacity(24);
    for side in [Side::Right, Side::Left] {
        let sz = side.sign();
        for level in 1..=12 {
            let j = &joints[level - 1];
            let mirror = |p: [f64; 3]| [p[0], p[1], p[2] * sz];
            let head = scale.point(mirror(j.head));
            let bone: Vec<Point3<f64>> = centrelines[level - 1]
                .iter()
                .map(|p| scale.point(mirror(*p)))
                .collect();
            let end = *bone.last().unwrap_or(&head);
            let cartilage = match level {
                1..=7 => {
                    let notch = sternum.costal_notches[level - 1]
                        + Vector3::new(0.0, 0.0, STERNUM_HALF_WIDTH * sz);
                    vec![end, nalgebra::center(&end, &notch), notch]
                }
                8..=10 => {
                    let above: &Rib = &ribs[rib_index(level - 1, side)];
                    let target =
                        point_at(&above.cartilage, 0.5 * polyline_length(&above.cartilage));
                    vec![end, nalgebra::center(&end, &target), target]
                }
                _ => Vec::new(),
            };
            let mut axis = scale.direction(mirror(j.axis));
            let r = end - head;
            if axis.cross(&r).y < 0.0 {
                axis = -axis;
            }
            ribs.push(Rib {
                level,
                side,
                head,
                axis,
                bone,
                cartilage,
                mass_points: Vec::new(),
            });
        }
    }
    // Mass points: bone by arc length, cartilage mass on its polyline, chest-wall tissue
    // shared by arc length over all ribs.
    let body_factor = subject.mass / REFERENCE_BODY.1;
    let total_length: f64 = ribs.iter().map(|r| polyline_length(&r.polyline())).sum();
    let wall_mass = CHEST_WALL_MASS_FRACTION * subject.mass;
    for rib in ribs.iter_mut() {
        let bone_len = polyline_length(&rib.bone);
        let cart_len = polyline_length(&rib.cartilage);
        let bone_mass = RIB_BONE_DENSITY * bone_len * body_factor;
        let wall_share = wall_mass / total_length;
        let mut pts = Vec::new();
        spread(&rib.bone, bone_mass + wall_share * bone_len, &mut pts);
        if cart_len > 0.0 {
            spread(
                &rib.cartilage,
                cartilage_mass(rib.level, masses) + wall_share * cart_len,
                &mut pts,
            );
        }
        rib.mass_points = pts;
    }
    ribs
}

/// Spreads `mass` uniformly along a polyline as point masses at segment midpoints.
fn spread(points: &[Point3<f64>], mass: f64, out: &mut Vec<(Point3<f64>, f64)>) {
    let total = polyline_length(points);
    if total <= 0.0 {
        return;
    }
    for w in points.windows(2) {
        let l = (w[1] - w[0]).norm();
        out.push((nalgebra::center(&w[0], &w[1]), mass * l / total));
    }
}
