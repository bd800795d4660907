//! The bones the skin must enclose, taken from the subject's [`Anatomy`]: rib centrelines
//! (bone and costal cartilage), the sternum (jugular notch, sternal angle, xiphisternal
//! joint), the spinous processes of the thoracic and lumbar vertebrae, and the free
//! abdominal wall. Also the reference spine profile the trunk sections are hung from, and
//! the clavicles, which the skin need not enclose but which hold the skin of the clavicle
//! line as skinning handles.

use super::Clearance;
use crate::anatomy::{Anatomy, VertexRole};
use nalgebra::{Point3, Vector3};

/// Stature [m] of the subject the reference spine profile was placed for.
/// Derived: the stature of `anatomy::skeleton::REFERENCE_BODY`.
pub const REFERENCE_STATURE: f64 = 1.75;

/// Vertebral body centres (x, y) [mm] of the reference spine, caudal to cranial.
/// T1-T12: `vert_origin` of the costovertebral joints of the Bruno et al. thoracolumbar
/// OpenSim model (rib_joints_right_mm.csv); lumbar and cervical centres placed with that
/// model's segment lengths and sagittal angles (spine_segments.csv: lumbar lordosis about
/// 43 deg, cervical column leaning forward).
/// Source: T1-T12 copied from rib_joints_right_mm.csv (Bruno, Bouxsein & Anderson 2015, J
/// Biomech Eng 137:081003); the lumbar and cervical centres are placed from spine_segments.csv
/// of the same model.
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

/// Radial room [m] kept between the skin and a bone centreline: rib half-thickness (about
/// 6 mm) plus the thinnest soft tissue over the ribs and sternum (about 12 mm).
/// Source: CT of 53 adults of normal body mass index (Wayne State University School of
/// Medicine research abstract, digitalcommons.wayne.edu/som_srs/70): 17.9 +- 8.9 mm of soft
/// tissue over the sternum in men and 13.0 +- 6.0 mm in women, over a sternum 17.2 / 13.8 mm
/// deep, so 26.5 +- 8.9 / 19.9 +- 6.0 mm from the skin to the bone's mid-plane; ours 18 mm lies
/// within both spreads (17.6-35.4 and 13.9-25.9 mm), near the lower end, as a minimum room
/// should. Multislice CT of 111 adults with a sternal foramen (Ma, Wang, Wang & Cui 2023, Clin
/// Anat, doi:10.1002/ca.24105, PMID 37596889) agrees: over the sternal body 11.3 +- 5.1 mm of
/// subcutaneous fat and 18.6 +- 5.7 mm from the skin to the lung (the bone's back), between
/// which the mid-plane lies. Over the ribs, away from the sternum, the soft tissue is thicker
/// (pectoral muscles), so 18 mm is a lower bound there.
pub const BONE_CLEARANCE: f64 = 0.018;

/// Radial room [m] kept between the skin and the abdominal cavity's wall: the thinnest
/// abdominal wall (muscle, fascia, fat and skin, about 10 mm in lean adults).
/// Unsourced: no source: chosen by hand (commit 85fbc4f). Literature: the rectus abdominis
/// alone is 14.7 +- 2.9 mm thick (Egwu et al. 2014), 10.3 mm in 545 women (Kim et al. 2012,
/// Arch Plast Surg 39:528), 8.1 mm at L3-L4 in 232 patients (Abbas et al. 2021, see
/// `ABDOMINAL_WALL_THICKNESS` in `anatomy/abdomen.rs`), to which 17.5 mm (men) to 24.8 mm
/// (women) of fat add: 10 mm is thinner than a typical ventral wall (a lower bound, not a
/// typical value). Periumbilical wall thickness by ultrasound in 187 women before laparoscopy:
/// 25.9 (SD 11.2) mm, 18.2 mm in the 83 of normal body mass index ("Transabdominal color
/// doppler ultrasound assessment of abdominal wall thickness and distance to major vessels",
/// AAGL Global Congress 2024, abstract 12045): ours lies below one SD of the whole cohort, so
/// it is no typical value there either.
pub const WALL_CLEARANCE: f64 = 0.010;

/// Spinous tip offset from a vertebral joint centre (x, y) [m] for a 1.75 m subject: body,
/// canal, lamina and process about 70 mm dorsal, the process sloping 12 mm caudally.
/// Unsourced: no source: chosen by hand (commit 85fbc4f). Panjabi et al. 1991 (Spine 16:888,
/// PMID 1948374) tabulate the thoracic vertebrae's body, canal and spinous-process dimensions,
/// from which this offset could be summed; their tables were not read, nor were the absolute
/// spinous-process lengths of 4,080 dry vertebrae (Masharawi et al. 2011, "Shape variation of
/// the neural arch in the thoracic and lumbar spine", Clin Anat 24:858, doi:10.1002/ca.21175:
/// changes along the spine only in the abstract). CT of 600 thoracic vertebrae (Kaur, Singh,
/// Prasath, Magu & Tanwar 2016, J Clin Orthop Trauma 7:101) gives the spinous process angle,
/// 30.1 +- 6.7 deg at T1, 57.9 +- 9.3 deg at T6, 16.2 +- 7.4 deg at T12, the slope of the
/// process itself; ours is the line from the joint centre to the tip, 9.7 deg below the
/// horizontal at every level: not the same quantity, and the level dependence is not modelled.
const SPINOUS_OFFSET: (f64, f64) = (-0.070, -0.012);

/// Names of the thoracic and lumbar levels of [`crate::anatomy::Spine::joints`].
pub fn is_trunk_vertebra(name: &str) -> bool {
    name.starts_with("thoracic") || name.starts_with("lumbar")
}

/// The anatomy's bones as named polylines: 24 ribs (body index order, bone then
/// cartilage), the sternum (jugular notch, sternal angle, xiphisternal joint) and the
/// thoracic and lumbar spine (joint centres, caudal to cranial).
pub fn bone_polylines(anatomy: &Anatomy) -> Vec<(String, Vec<Point3<f64>>)> {
    let mut out: Vec<(String, Vec<Point3<f64>>)> = anatomy
        .ribs
        .iter()
        .map(|r| {
            let side = match r.side {
                crate::anatomy::Side::Right => "right",
                crate::anatomy::Side::Left => "left",
            };
            (format!("rib{}_{side}", r.level), r.polyline())
        })
        .collect();
    let s = &anatomy.sternum;
    out.push(("sternum".into(), vec![s.jugular, s.angle, s.xiphisternal]));
    out.push(("spine".into(), trunk_spine(anatomy)));
    out
}

/// The clavicles as polylines from the sternoclavicular joint to the acromioclavicular
/// joint, right then left. The medial end sits beside the jugular notch; the lateral end 3 cm
/// inside half the biacromial breadth (measured over the acromia's lateral edges), at the
/// acromion's height above the suprasternale (the joint lies about 5 mm below the skin
/// over the acromion, as the medial end lies 5 mm above the notch: nearly level standing)
/// and set back 4 cm dorsally (the clavicle runs about 15 deg backwards from the coronal
/// plane); the medial part bows ventrally. The default man's clavicles are 16.5 cm long
/// (adults: about 15 cm in men, 13.5 cm in women).
pub fn clavicles(anatomy: &Anatomy) -> Vec<(String, Vec<Point3<f64>>)> {
    let s = anatomy.subject.stature / REFERENCE_STATURE;
    let j = anatomy.sternum.jugular;
    let dims = super::anthropometry::TorsoDimensions::from_subject(&anatomy.subject);
    let (half, rise) = match dims {
        Ok(d) => (
            0.5 * d.biacromial_breadth - 0.03 * s,
            d.acromial_height - d.suprasternale_height,
        ),
        Err(_) => (0.175 * s, 0.0),
    };
    [("right", 1.0), ("left", -1.0)]
        .into_iter()
        .map(|(side, z)| {
            let medial = Point3::new(j.x - 0.005 * s, j.y + 0.005 * s, z * 0.025 * s);
            let lateral = Point3::new(j.x - 0.04 * s, j.y + rise - 0.005 * s, z * half);
            let bow = Point3::new(
                j.x + 0.005 * s,
                j.y + 0.4 * rise,
                z * (0.025 * s + 0.6 * (half - 0.025 * s)),
            );
            (format!("clavicle_{side}"), vec![medial, bow, lateral])
        })
        .collect()
}

/// Joint centres of the thoracic and lumbar vertebrae, caudal to cranial.
pub fn trunk_spine(anatomy: &Anatomy) -> Vec<Point3<f64>> {
    anatomy
        .spine
        .joints
        .iter()
        .filter(|(n, _)| is_trunk_vertebra(n))
        .map(|(_, p)| *p)
        .collect()
}

/// Spinous process tips of the thoracic and lumbar vertebrae (the posterior limit of the
/// spine), caudal to cranial.
pub fn spinous_tips(anatomy: &Anatomy) -> Vec<Point3<f64>> {
    let s = anatomy.subject.stature / REFERENCE_STATURE;
    trunk_spine(anatomy)
        .into_iter()
        .map(|p| p + Vector3::new(SPINOUS_OFFSET.0 * s, SPINOUS_OFFSET.1 * s, 0.0))
        .collect()
}

/// Samples of a polyline at most `step` metres apart (ends included).
pub fn densify(points: &[Point3<f64>], step: f64, out: &mut Vec<Point3<f64>>) {
    for w in points.windows(2) {
        let n = ((w[1] - w[0]).norm() / step).ceil().max(1.0) as usize;
        for i in 0..n {
            out.push(w[0] + (w[1] - w[0]) * (i as f64 / n as f64));
        }
    }
    if let Some(last) = points.last() {
        out.push(*last);
    }
}

/// Bone samples at most `step` metres apart: rib centrelines, sternum, spinous tips (for
/// enclosure constraints and gap reports).
pub fn dense_bone_points(anatomy: &Anatomy, step: f64) -> Vec<Point3<f64>> {
    let mut out = Vec::new();
    for (name, pts) in bone_polylines(anatomy) {
        if name != "spine" {
            densify(&pts, step, &mut out);
        }
    }
    densify(&spinous_tips(anatomy), step, &mut out);
    out
}

/// Rest positions of the abdominal cavity's free lateral and ventral wall.
pub fn wall_points(anatomy: &Anatomy) -> Vec<Point3<f64>> {
    let ab = &anatomy.abdomen;
    ab.with_role(VertexRole::Wall)
        .map(|v| anatomy.rest(ab.anchor[v as usize]))
        .collect()
}

/// What the skin must enclose: every bone sample (5 mm apart) with `bone_clearance` (see
/// [`BONE_CLEARANCE`]) and every free abdominal-wall vertex with [`WALL_CLEARANCE`].
pub fn anatomy_clearance(anatomy: &Anatomy, bone_clearance: f64) -> Vec<Clearance> {
    let mut out: Vec<Clearance> = dense_bone_points(anatomy, 0.005)
        .into_iter()
        .map(|point| Clearance {
            point,
            clearance: bone_clearance,
        })
        .collect();
    out.extend(wall_points(anatomy).into_iter().map(|point| Clearance {
        point,
        clearance: WALL_CLEARANCE,
    }));
    out
}
