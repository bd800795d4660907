//! Muscle element layouts for the thesis's eight groups (thesis 2.2-2.3, default counts 250 /
//! 250 / 12 / 500 / 100 / 50 / 60 / 60 scaled by the level of detail) and the
//! sternocleidomastoids (one element per head and side at every level), with regional gains
//! (external intercostals strongest dorsally and fading ventrally, internal intercostals
//! mirrored: thesis 2.2.1 and 2.4.1), and the cartilage joints (ribs 1-7 to the sternum, 8-10
//! to the cartilage above: thesis 1.3.2).

use super::abdomen::{Abdomen, VertexRole, azimuth};
use super::skeleton::{Rib, Side, Spine, Sternum, point_at, polyline_length, rib_index};
use super::{Anchor, Body, MuscleGroup, push_anchor};
use nalgebra::{Point3, Vector3};

/// One spring-damper muscle element (thesis eq. 2.2) along a path of anchors: its length is
/// the path's length, so a muscle can wrap over the abdominal wall or the diaphragm dome
/// through via points, as musculoskeletal models route muscles. A two-anchor path is a
/// straight element.
#[derive(Clone, Debug, PartialEq)]
pub struct MuscleElement {
    /// Group whose activation drives it.
    pub group: MuscleGroup,
    /// Anchors from origin to insertion (at least two).
    pub path: Vec<u32>,
    /// Regional gain g in [0, 1] multiplying the activation.
    pub gain: f64,
    /// Side of the body (for the left/right gains); `None` on the midline.
    pub side: Option<Side>,
    /// Force at full activation, isometric at the rest length [N].
    pub max_force: f64,
    /// Rest length [m] of the tissue the element stands for, where its path does not measure
    /// it: for the diaphragm the smooth dome's arcs over the edges of its route
    /// ([`Abdomen::dome_arc`]); `None` elsewhere (the path's rest length is the tissue's). A
    /// fibre's contraction (beta a of its length) and its stiffness (F / (beta l)) are the
    /// tissue's, whatever the chords that carry it: the model scales them by this length over
    /// the path's rest length, as the model measures it (via points included).
    pub tissue_length: Option<f64>,
}

/// A ball joint between two bodies, as a stiff zero-length spring between two anchors that
/// coincide at rest.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Joint {
    /// Anchor on the first body.
    pub a: u32,
    /// Anchor on the second body.
    pub b: u32,
    /// Level of the rib whose cartilage ends here (1-10).
    pub level: u8,
}

/// Obliquity of the intercostal fibres: the arc-length fraction of the rib separating a
/// fibre's two attachments (external fibres run caudally and ventrally, internal fibres
/// caudally and dorsally).
/// Unsourced: no source: chosen by hand in commit 16087cb. No measured angle of the human
/// intercostal fibres to the ribs was found (anatomy texts give directions only: external
/// fibres caudal and ventral, internal ones at right angles to them; the review of De Troyer,
/// Kirkwood & Wilson 2005, Physiol Rev, doi:10.1152/physrev.00007.2004, says the mechanical
/// advantage depends partly on the fibres' orientation, with no angle in its abstract).
pub const OBLIQUITY: f64 = 0.2;

/// The external intercostals' inspiratory drive by interspace (the interspace below rib k is
/// the k-th), relative to the third: (interspace, relative drive) points, linear between them,
/// 1 above the first point and 0 below the last.
/// Source: De Troyer, Gorman & Gandevia 2003, J Physiol 546:943 (6 healthy adults, quiet
/// breathing, ultrasound-guided EMG): the dorsal third and fifth interspaces were active with
/// every breath in every subject, at peak discharge frequencies of 11.9 (SE 0.3) and 6.7 (0.4)
/// Hz, and the dorsal seventh "almost invariably silent"; ours 1 at the third, 6.7 / 11.9 =
/// 0.563 at the fifth (the discharge frequency taken as the drive, an assumption: the fifth
/// interspace's units were also recruited later, and force is not linear in firing rate), 0 at
/// the seventh and, unrecorded, below it (an extrapolation). Their ventral third interspace fired at 6.0 (0.5) Hz, about half the dorsal one, as
/// the dorsal-to-ventral gain (1 to 0.4) has it. Measured in quiet breathing only; the
/// gradient is applied to every activation, maximal ones included, for want of a measurement
/// in deep breaths (the parasternals keep their rostrocaudal gradient in voluntary breaths
/// 20 % stronger than quiet ones: Respir Physiol Neurobiol 2011, 175:20,
/// doi:10.1016/j.resp.2010.08.023, authors not on the page read).
pub const EXTERNAL_INTERCOSTAL_DRIVE_BY_SPACE: [(f64, f64); 3] =
    [(3.0, 1.0), (5.0, 0.563), (7.0, 0.0)];

/// The external intercostals' relative inspiratory drive in interspace `space` (1-11), from
/// [`EXTERNAL_INTERCOSTAL_DRIVE_BY_SPACE`].
pub fn external_intercostal_drive(space: usize) -> f64 {
    let x = space as f64;
    let points = EXTERNAL_INTERCOSTAL_DRIVE_BY_SPACE;
    if x <= points[0].0 {
        return points[0].1;
    }
    for w in points.windows(2) {
        let ((x0, y0), (x1, y1)) = (w[0], w[1]);
        if x <= x1 {
            return y0 + (y1 - y0) * (x - x0) / (x1 - x0);
        }
    }
    points[points.len() - 1].1
}

/// Maximal active tension of an intercostal layer per metre of interspace [N/m]. 29 N/cm^2
/// over a 3 mm layer (De Troyer 1998) gives 870 N/m; the 1200 N/m in use (1.4x that) is the
/// value of the model's first calibration, with which the drive amplitudes of
/// [`crate::model::Drive::quiet`] and every documented figure were calibrated, so changing it
/// is a recalibration, not a correction. The passive-and-active law uses the cited 870 N/m
/// (`dynamics::muscle::HILL_INTERCOSTAL_TENSION`).
/// Calibrated: the first calibration's value, no command reproduces it. Literature: 29 N/cm^2
/// (De Troyer 1998) over a 3 mm layer, 870 N/m; ours 1200 N/m: disagrees (x1.38).
pub const INTERCOSTAL_TENSION: f64 = 1200.0;
/// Maximal force of the scalenes on one side [N]: anterior 139 + medius 101 + posterior 77
/// (Mortensen 2014).
/// Source: Mortensen 2014's neck model, maximal forces 139 + 101 + 77 N (agrees: their sum).
pub const SCALENE_FORCE_PER_SIDE: f64 = 317.0;
/// Maximal force of the sternocleidomastoid on one side [N], both heads together: its
/// anatomical cross-section, 512 mm^2 averaged over four cervical levels in 6 young men (Stemper,
/// Baisden, Yoganandan, Pintar, Paskoff & Shender 2010, Aviat Space Environ Med 81:878,
/// doi:10.3357/ASEM.2758.2010, upright MRI), times the specific tension 26.8 N/cm^2 (Persad et
/// al. 2024, J Appl Physiol), as the other cited forces are taken. An anatomical cross-section,
/// not a physiological one (the muscle's fibres are nearly parallel to its line, so the two
/// differ little, but no physiological cross-section was read).
/// Source: Stemper et al. 2010 (512 mm^2) x Persad et al. 2024 (26.8 N/cm^2) = 137 N (agrees:
/// their product, docs/respiratory_muscles.md A9).
pub const SCM_FORCE_PER_SIDE: f64 = 137.0;
/// Maximal total force of the diaphragm's fibres [N]: a transdiaphragmatic pressure of about
/// 150 cmH2O (maximal combined efforts) over about 0.04 m^2 of dome.
/// Unsourced: the pressure is cited, the 0.04 m^2 is not: maximal transdiaphragmatic pressure at
/// FRC in 10 normal subjects 154 +- 25 cmH2O (Mueller and two-step efforts) and 180 +- 14 cmH2O
/// with visual feedback (Laporta & Grassino 1985, J Appl Physiol 58:1469,
/// doi:10.1152/jappl.1985.58.5.1469), so 600 N is that pressure over 0.040 (0.034-0.047) m^2, or
/// 0.034 m^2 at 180 cmH2O; no measured area on which the pressure acts (the dome's horizontal
/// projection inside the insertions) was found. Cross-section x specific tension
/// (docs/respiratory_muscles.md, section F): the in-vivo thickness at FRC, 1.7 +- 0.2 mm (Ueki et
/// al. 1995, Thorax 50:1157), over the default man's 92.6 cm insertion line (`cargo run --release
/// --example muscle_forces`) at 26.8 N/cm^2 (Persad et al. 2024, J Appl Physiol) gives 422
/// (372-472) N; the necropsy thickness, 3.20 +- 0.55 mm (Arora & Rochester 1987, PMID 3568775), an
/// upper bound of 794 N. Ours lies between, inside neither's spread. It is the scale the thesis's
/// law (its shortening spring F_max / (beta l0)) and its drives were calibrated with; the
/// passive-and-active law uses the cited 422 N (`dynamics::muscle::HILL_DIAPHRAGM_FORCE`).
pub const DIAPHRAGM_FORCE: f64 = 600.0;
/// Maximal forces of the abdominal wall muscles, both sides together [N] (about 25 N/cm^2 over
/// the physiological cross-sections): rectus, transversus, external and internal obliques.
/// Unsourced: 25 N/cm^2 is inside the 20-35 N/cm^2 commonly taken for skeletal muscle's
/// specific tension (physiology reference), but the cross-sections it implies (both sides:
/// rectus 20, transversus 16, obliques 20 and 16 cm^2) are not sourced. Literature, at the
/// 26.8 N/cm^2 of Persad et al. 2024 (J Appl Physiol), both sides: the rectus's physiological
/// cross-section in five cadavers, 2.6 (SD 0.9) cm^2 (Delp, Suryanarayanan, Murray, Uhlir &
/// Triolo 2001, J Biomech 34:371, PMID 11182129), gives 139 (91-188) N; the cross-sections
/// a trunk model took from the literature, rectus 6.80, external oblique 6.85, internal oblique
/// 5.68 cm^2 per muscle (Lambrecht, Audu, Triolo & Kirsch 2009, J Rehabil Res Dev 46:515,
/// Table 1), give 364, 367 and 304 N; no transversus cross-section was read. Ours, 500 / 500 /
/// 400 N for rectus / external / internal oblique, is 1.3-1.4x the compiled values and 3.6x
/// the cadaver rectus: disagrees (docs/respiratory_muscles.md, A15-A16).
pub const ABDOMINAL_FORCES: [(MuscleGroup, f64); 4] = [
    (MuscleGroup::RectusAbdominis, 500.0),
    (MuscleGroup::TransversusAbdominis, 400.0),
    (MuscleGroup::ExternalObliques, 500.0),
    (MuscleGroup::InternalObliques, 400.0),
];

/// Element count of `group` at muscle fraction `f` (at least 2 per side where bilateral).
fn count(group: MuscleGroup, f: f64) -> usize {
    ((group.default_count() as f64 * f).round() as usize).max(4)
}

/// Anchor on rib `rib` at arc-length fraction `f` of its whole polyline (bone and cartilage).
fn on_rib(rib: &Rib, f: f64, anchors: &mut Vec<Anchor>) -> u32 {
    let line = rib.polyline();
    let p = point_at(&line, f * polyline_length(&line));
    push_anchor(anchors, Body::Rib(rib.index() as u8), p)
}

/// Anchor on rib `rib` at arc-length fraction `f` of its bone only.
fn on_bone(rib: &Rib, f: f64, anchors: &mut Vec<Anchor>) -> u32 {
    let p = point_at(&rib.bone, f * polyline_length(&rib.bone));
    push_anchor(anchors, Body::Rib(rib.index() as u8), p)
}

/// The cartilage joints: for ribs 1-7 the cartilage end meets the sternum's costal notch; for
/// ribs 8-10 it meets the middle of the cartilage above.
pub fn cartilage_joints(ribs: &[Rib], anchors: &mut Vec<Anchor>) -> Vec<Joint> {
    let mut joints = Vec::new();
    for side in [Side::Right, Side::Left] {
        for level in 1..=10 {
            let rib = &ribs[rib_index(level, side)];
            let Some(end) = rib.cartilage.last().copied() else {
                continue;
            };
            let a = push_anchor(anchors, Body::Rib(rib.index() as u8), end);
            let body = if level <= 7 {
                Body::Sternum
            } else {
                Body::Rib(rib_index(level - 1, side) as u8)
            };
            let b = push_anchor(anchors, body, end);
            joints.push(Joint {
                a,
                b,
                level: level as u8,
            });
        }
    }
    joints
}

/// All muscle elements at muscle fraction `f` (level of detail).
pub fn muscles(
    ribs: &[Rib],
    sternum: &Sternum,
    spine: &Spine,
    abdomen: &Abdomen,
    f: f64,
    anchors: &mut Vec<Anchor>,
) -> Vec<MuscleElement> {
    let mut out = Vec::new();
    intercostals(ribs, f, anchors, &mut out);
    scalenes(ribs, spine, f, anchors, &mut out);
    sternocleidomastoids(ribs, sternum, spine, f, anchors, &mut out);
    diaphragm(abdomen, anchors, f, &mut out);
    abdominals(ribs, sternum, abdomen, f, anchors, &mut out);
    out
}

/// External and internal intercostals between ribs k and k+1 (k = 1..11) on both sides.
/// External fibres run from the upper rib down and forward (lower attachment more ventral),
/// internal fibres down and backward; 250 elements per layer at full detail (thesis 2.2.1).
/// Gains: external 1 at the head fading to 0.4 at the ventral end, times the interspace's
/// rostrocaudal drive ([`external_intercostal_drive`]: none from the seventh interspace down);
/// internal mirrored, without a rostrocaudal gradient.
fn intercostals(ribs: &[Rib], f: f64, anchors: &mut Vec<Anchor>, out: &mut Vec<MuscleElement>) {
    for group in [
        MuscleGroup::ExternalIntercostals,
        MuscleGroup::InternalIntercostals,
    ] {
        let per_space = (count(group, f) as f64 / 22.0).round().max(1.0) as usize;
        let external = group == MuscleGroup::ExternalIntercostals;
        for side in [Side::Right, Side::Left] {
            for level in 1..=11 {
                let upper = &ribs[rib_index(level, side)];
                let lower = &ribs[rib_index(level + 1, side)];
                // Interspace length: the shorter of the two ribs' spans covered by the layer.
                let span_u = if external {
                    polyline_length(&upper.bone)
                } else {
                    polyline_length(&upper.polyline())
                };
                let span_l = if external {
                    polyline_length(&lower.bone)
                } else {
                    polyline_length(&lower.polyline())
                };
                let length = span_u.min(span_l);
                let force = INTERCOSTAL_TENSION * length / per_space as f64;
                for e in 0..per_space {
                    let s = (e as f64 + 0.5) / per_space as f64;
                    // Fibre obliquity: OBLIQUITY (0.2) of the rib's length between attachments.
                    let (su, sl) = if external {
                        ((1.0 - OBLIQUITY) * s, (1.0 - OBLIQUITY) * s + OBLIQUITY)
                    } else {
                        (OBLIQUITY + (1.0 - OBLIQUITY) * s, (1.0 - OBLIQUITY) * s)
                    };
                    let (a, b) = if external {
                        (on_bone(upper, su, anchors), on_bone(lower, sl, anchors))
                    } else {
                        (on_rib(upper, su, anchors), on_rib(lower, sl, anchors))
                    };
                    let gain = if external {
                        (1.0 - 0.6 * s) * external_intercostal_drive(level)
                    } else {
                        0.4 + 0.6 * s
                    };
                    out.push(MuscleElement {
                        group,
                        path: vec![a, b],
                        gain,
                        side: Some(side),
                        max_force: force,
                        tissue_length: None,
                    });
                }
            }
        }
    }
}

/// Scalenes: 12 elements at full detail from the transverse processes of C6 (thesis 2.2.2:
/// "linking the cervical vertebrae C6 to the first rib") to the upper surface of rib 1.
fn scalenes(
    ribs: &[Rib],
    spine: &Spine,
    f: f64,
    anchors: &mut Vec<Anchor>,
    out: &mut Vec<MuscleElement>,
) {
    let group = MuscleGroup::Scalenes;
    let per_side = (count(group, f) / 2).max(2);
    let c6 = spine
        .joint("cerv6")
        .unwrap_or(Point3::new(-0.03, 1.50, 0.0));
    for side in [Side::Right, Side::Left] {
        let rib1 = &ribs[rib_index(1, side)];
        for e in 0..per_side {
            let s = (e as f64 + 0.5) / per_side as f64;
            // Origins spread along the transverse process (2-3.5 cm lateral).
            let origin = c6 + Vector3::new(0.005, 0.0, side.sign() * (0.02 + 0.015 * s));
            let a = push_anchor(anchors, Body::Ground, origin);
            let b = on_bone(rib1, 0.35 + 0.4 * s, anchors);
            out.push(MuscleElement {
                group,
                path: vec![a, b],
                gain: 1.0,
                side: Some(side),
                max_force: SCALENE_FORCE_PER_SIDE / per_side as f64,
                tissue_length: None,
            });
        }
    }
}

/// Sternocleidomastoids (not in the thesis): per side a sternal and a clavicular head (one
/// element each at every level of detail: [`MuscleGroup::default_count`] 4 is also the least
/// [`count`] gives), each carrying half of [`SCM_FORCE_PER_SIDE`] (no measured split between
/// the heads was read).
///
/// Origin: the mastoid process, fixed (`Body::Ground`: the head is held, as it is in the
/// maximal efforts that recruit the muscle, and as the scalenes' cervical origin is), placed
/// from C1's joint centre: level with it, 5 cm lateral (half a bimastoid breadth of about 10
/// cm, a stated round figure, no measurement was read) and 1 cm posterior (the mastoid lies
/// behind the ear, a little behind the vertebral bodies' line; stated, not measured). With the
/// default man the elements are 18.4 cm (sternal head) and 18.8 cm (clavicular head) long.
///
/// Insertions: the sternal head on the manubrium's anterior surface, 1 cm below the jugular
/// notch and 1 cm off the midline (`Body::Sternum`); the clavicular head on the medial third
/// of the clavicle, which the model does not have: its pull is taken at the sternal end of
/// rib 1's costal cartilage (`Body::Rib`, 95 % of the rib's length), where the clavicle's
/// sternal end rests on the first cartilage and passes its load to the first rib and the
/// manubrium through the sternoclavicular joint and the costoclavicular ligament.
fn sternocleidomastoids(
    ribs: &[Rib],
    sternum: &Sternum,
    spine: &Spine,
    f: f64,
    anchors: &mut Vec<Anchor>,
    out: &mut Vec<MuscleElement>,
) {
    let group = MuscleGroup::Sternocleidomastoids;
    let per_side = (count(group, f) / 2).max(2);
    // Without a C1 joint (a spine table lacking it) the mastoid is placed 10 cm above C6,
    // about the C6-C1 distance of the default spine (10.3 cm: the offsets of
    // data/anatomy/spine_segments.csv).
    let c1 = spine.joint("cerv1").unwrap_or_else(|| {
        spine
            .joint("cerv6")
            .unwrap_or(Point3::new(-0.03, 1.50, 0.0))
            + Vector3::new(0.0, 0.10, 0.0)
    });
    for side in [Side::Right, Side::Left] {
        let mastoid = c1 + Vector3::new(-0.01, 0.0, side.sign() * 0.05);
        let rib1 = &ribs[rib_index(1, side)];
        for e in 0..per_side {
            let a = push_anchor(anchors, Body::Ground, mastoid);
            let b = if e % 2 == 0 {
                let p = sternum.jugular + Vector3::new(0.0, -0.01, side.sign() * 0.01);
                push_anchor(anchors, Body::Sternum, p)
            } else {
                on_rib(rib1, 0.95, anchors)
            };
            out.push(MuscleElement {
                group,
                path: vec![a, b],
                gain: 1.0,
                side: Some(side),
                max_force: SCM_FORCE_PER_SIDE / per_side as f64,
                tissue_length: None,
            });
        }
    }
}

/// Diaphragm (thesis 2.3): radial fibres from the costal-margin insertions up the dome to the
/// central tendon along the dome's meridians, each a series of elements between successive
/// dome vertices, so that their shortening lowers the dome like a piston while pulling the
/// insertions (and the lower ribs) cranially.
///
/// The layout is the same muscle at every level of detail: every insertion (rim) vertex
/// carries one fibre, every fibre reaches the central tendon, and a fibre's share of
/// [`DIAPHRAGM_FORCE`] is its insertion's share of the rim's arc length (half the distance to
/// each neighbour on the costal margin), so the force per metre of insertion is the same at
/// every level. A fibre that starts on the midline and cannot stay on it forks into mirror
/// branches of half its force each. Where fibres converge and run along the same dome edge,
/// their elements are one element of their summed force (the same spring: stiffness and
/// force are proportional to the force at a common rest length).
fn diaphragm(abdomen: &Abdomen, anchors: &[Anchor], f: f64, out: &mut Vec<MuscleElement>) {
    let group = MuscleGroup::Diaphragm;
    let n = abdomen.len();
    let mut neighbours = vec![Vec::new(); n];
    for t in &abdomen.triangles {
        for k in 0..3 {
            let (u, v) = (t[k] as usize, t[(k + 1) % 3] as usize);
            if !neighbours[u].contains(&v) {
                neighbours[u].push(v);
                neighbours[v].push(u);
            }
        }
    }
    let dir = &abdomen.sphere;
    let tendon = |v: usize| dir[v].y > CENTRAL_TENDON;
    let on_midline = |v: usize| dir[v].z.abs() < 1e-9;
    // Fibres of the left side are the mirror images of the right side's (z -> -z), so the
    // layout is exactly symmetric.
    let key = |d: &Vector3<f64>| {
        (
            (d.x * 1e9).round() as i64,
            (d.y * 1e9).round() as i64,
            (d.z * 1e9).round() as i64,
        )
    };
    let by_dir: std::collections::HashMap<(i64, i64, i64), usize> =
        dir.iter().enumerate().map(|(v, d)| (key(d), v)).collect();
    let mirror_of = |v: usize| {
        by_dir
            .get(&key(&Vector3::new(dir[v].x, dir[v].y, -dir[v].z)))
            .copied()
    };
    // The next vertex up the dome from `cur` for a fibre starting at azimuth `az0` on side
    // `sign` (+1 right, -1 left, 0 midline): the higher dome neighbour closest to the fibre's
    // meridian, preferring height; ties lean away from the midline (mirror-symmetric).
    let step = |cur: usize, az0: f64, sign: f64| -> Option<usize> {
        neighbours[cur]
            .iter()
            .copied()
            .filter(|&v| abdomen.roles[v] == VertexRole::Dome && dir[v].y > dir[cur].y + 1e-9)
            .filter(|&v| sign * dir[v].z > -1e-9)
            .min_by(|&a, &b| {
                let cost = |v: usize| {
                    let d =
                        (azimuth(dir[v].x, dir[v].z, 0.0) - az0).rem_euclid(std::f64::consts::TAU);
                    d.min(std::f64::consts::TAU - d) - 2.0 * (dir[v].y - dir[cur].y)
                };
                let (ca, cb) = (cost(a), cost(b));
                if (ca - cb).abs() > 1e-12 {
                    ca.total_cmp(&cb)
                } else {
                    (-sign * dir[a].z).total_cmp(&(-sign * dir[b].z))
                }
            })
    };
    // Walks up from `start` (already in `path`) until the tendon.
    // (A walk that finds no way up stops there; the layout's tests check that none does.)
    let climb = |mut path: Vec<usize>, az0: f64, sign: f64| -> Option<Vec<usize>> {
        let mut cur = *path.last()?;
        while !tendon(cur) {
            match step(cur, az0, sign) {
                Some(v) => {
                    path.push(v);
                    cur = v;
                }
                None => break,
            }
        }
        Some(path)
    };
    // Insertion arc length of each rim vertex (the rim is ordered by azimuth and closed).
    let rim: Vec<usize> = abdomen.rim.iter().map(|&r| r as usize).collect();
    let at = |v: usize| anchors[abdomen.anchor[v] as usize].rest;
    let m = rim.len();
    let arc: Vec<f64> = (0..m)
        .map(|i| {
            let (prev, next) = (rim[(i + m - 1) % m], rim[(i + 1) % m]);
            0.5 * ((at(rim[i]) - at(prev)).norm() + (at(next) - at(rim[i])).norm())
        })
        .collect();
    let total_arc: f64 = arc.iter().sum();
    // Fibres as (path, side, force): right and midline ones routed, left ones mirrored.
    let mut fibres: Vec<(Option<Vec<usize>>, Option<Side>, f64)> = Vec::new();
    for (i, &r) in rim.iter().enumerate() {
        let force = DIAPHRAGM_FORCE * arc[i] / total_arc;
        let az0 = azimuth(dir[r].x, dir[r].z, 0.0);
        if dir[r].z > 1e-9 {
            let path = climb(vec![r], az0, 1.0);
            fibres.push((path, Some(Side::Right), force));
        } else if dir[r].z < -1e-9 {
            let path = mirror_of(r)
                .and_then(|q| climb(vec![q], azimuth(dir[q].x, dir[q].z, 0.0), 1.0))
                .and_then(|p| p.iter().map(|&v| mirror_of(v)).collect());
            fibres.push((path, Some(Side::Left), force));
        } else {
            // Midline: up the midline while the best step stays on it, then two branches.
            let mut trunk = vec![r];
            let mut cur = r;
            while !tendon(cur) {
                match step(cur, az0, 0.0).filter(|&v| on_midline(v)) {
                    Some(v) => {
                        trunk.push(v);
                        cur = v;
                    }
                    None => break,
                }
            }
            if tendon(cur) {
                fibres.push((Some(trunk), None, force));
                continue;
            }
            let right = climb(vec![cur], az0, 1.0);
            let left = right
                .as_ref()
                .and_then(|p| p.iter().map(|&v| mirror_of(v)).collect::<Option<Vec<_>>>());
            fibres.push((Some(trunk), None, force));
            fibres.push((right, Some(Side::Right), 0.5 * force));
            fibres.push((left, Some(Side::Left), 0.5 * force));
        }
    }
    let code = |side: Option<Side>| match side {
        Some(Side::Right) => 0u8,
        Some(Side::Left) => 1,
        None => 2,
    };
    // Where the fibres' distinct dome edges outnumber the thesis's element count for this
    // level of detail (at full detail: about 980 edges against 500 elements), each element
    // spans `span` successive edges, wrapping over the dome through the vertices between them
    // as via points: every fibre and every vertex it crosses is kept, only the springs merge.
    let edges: std::collections::HashSet<(usize, usize, u8)> = fibres
        .iter()
        .filter_map(|(p, side, _)| p.as_ref().map(|p| (p, code(*side))))
        .flat_map(|(p, c)| p.windows(2).map(move |w| (w[0], w[1], c)))
        .collect();
    let span = ((edges.len() as f64 / count(group, f) as f64).round() as usize).max(1);
    // The smooth dome's arcs over a run of vertices (`None` if an edge of the run has no
    // arc: the run's path is then the tissue).
    let tissue_length = |run: &[usize]| -> Option<f64> {
        run.windows(2)
            .map(|w| {
                let key = (w[0].min(w[1]) as u32, w[0].max(w[1]) as u32);
                abdomen.dome_arc.get(&key).copied()
            })
            .sum()
    };
    // Elements: one per distinct run of vertices and side, carrying the summed force of the
    // fibres along it. Runs are cut from the tendon end, so that fibres which have converged
    // share their elements.
    let mut index: std::collections::HashMap<(Vec<u32>, u8), usize> = Default::default();
    for (path, side, force) in fibres {
        let Some(path) = path else { continue };
        let last = path.len() - 1;
        let mut cuts: Vec<usize> = (0..=last).rev().step_by(span).collect();
        if cuts.last() != Some(&0) {
            cuts.push(0);
        }
        for w in cuts.windows(2) {
            let run: Vec<u32> = path[w[1]..=w[0]]
                .iter()
                .map(|&v| abdomen.anchor[v])
                .collect();
            let tissue_length = tissue_length(&path[w[1]..=w[0]]);
            let k = (run, code(side));
            match index.get(&k) {
                Some(&e) => out[e].max_force += force,
                None => {
                    index.insert(k.clone(), out.len());
                    out.push(MuscleElement {
                        group,
                        path: k.0,
                        gain: 1.0,
                        side,
                        max_force: force,
                        tissue_length,
                    });
                }
            }
        }
    }
}

/// Height on the unit sphere above which the dome is central tendon (no muscle fibres).
/// Unsourced: no source: chosen by hand in commit 16087cb. On the unit sphere the cap above
/// 0.85 is 0.15 / 0.65 = 23 % of the muscular band between `anatomy::abdomen`'s dome cut
/// (0.2) and it (a zone's area is proportional to its height); in 104 adult diaphragms the
/// tendon-to-muscle area ratio was 10-15 % in the commonest class (56.7 % of specimens;
/// du Plessis, Ramai, Shah, Holland, Tubbs & Loukas 2015, "The clinical anatomy of the
/// musculotendinous part of the diaphragm", Surg Radiol Anat 37:1013): ours is larger
/// (parametric areas; the deformed dome's were not measured). 0.90 would give 14.3 % and 0.91
/// 12.7 %, both inside that class, but with either level 0's fibres run along an edge near the
/// apex (44-51) whose chords do not converge to its arc as `tests/anatomy_geometry.rs`
/// requires (arc 23.77 mm, chords 23.63 / 23.64 / 23.68 mm at levels 0 / 1 / 2, the same at
/// 0.90 and 0.91): the dome's parametrisation has to be looked at first.
pub const CENTRAL_TENDON: f64 = 0.85;

/// The mirror image (z -> -z) of anchor `n`: for a vertex of the abdominal surface, the
/// vertex of mirrored parametric direction (`vertex_mirror`, so that a fitted, slightly
/// asymmetric cavity keeps left and right paired); otherwise an existing anchor at the
/// mirrored position on the mirrored body if there is one, else a new one.
fn mirror_anchor(
    n: u32,
    anchors: &mut Vec<Anchor>,
    vertex_mirror: &std::collections::HashMap<u32, u32>,
) -> u32 {
    if let Some(&m) = vertex_mirror.get(&n) {
        return m;
    }
    let a = anchors[n as usize];
    let body = match a.body {
        Body::Rib(i) => Body::Rib(if i < 12 { i + 12 } else { i - 12 }),
        other => other,
    };
    let p = Point3::new(a.rest.x, a.rest.y, -a.rest.z);
    let same = |b: &Anchor| {
        let kind_matches = match (b.body, body) {
            (Body::Vertex(_), Body::Vertex(_)) => true,
            (x, y) => x == y,
        };
        kind_matches && (b.rest - p).norm() < 1e-12
    };
    match anchors.iter().position(same) {
        Some(i) => i as u32,
        None => push_anchor(anchors, body, p),
    }
}

/// The abdominal wall muscles as chains of elements through the wall's vertices, so that
/// tension presses the wall inward where it is curved:
/// rectus abdominis (vertical, beside the midline, pubis to the cartilages of ribs 5-7),
/// transversus abdominis (horizontal hoops from the back to the linea alba),
/// external obliques (lower ribs, down and forward to the linea alba and pubis),
/// internal obliques (iliac crest, up and forward to the lower ribs and linea alba).
fn abdominals(
    ribs: &[Rib],
    sternum: &Sternum,
    abdomen: &Abdomen,
    f: f64,
    anchors: &mut Vec<Anchor>,
    out: &mut Vec<MuscleElement>,
) {
    let wall: Vec<u32> = abdomen
        .roles
        .iter()
        .enumerate()
        .filter(|(_, r)| matches!(r, VertexRole::Wall))
        .map(|(v, _)| abdomen.anchor[v])
        .collect();
    if wall.is_empty() {
        return;
    }
    let vertex_mirror = abdomen_mirror(abdomen);
    // The wall's parametric surface: (azimuth, height) -> nearest wall vertex.
    let axis_x = abdomen.axis_x;
    let wall_pts: Vec<(u32, Point3<f64>)> = wall
        .iter()
        .map(|&a| (a, anchors[a as usize].rest))
        .collect();
    let (ymin, ymax) = wall_pts
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), (_, p)| {
            (lo.min(p.y), hi.max(p.y))
        });
    // Nearest wall vertex to (azimuth, height); between mirror-image candidates at equal
    // distance, the one on `side` wins, so that left and right chains mirror each other.
    let nearest = |psi: f64, y: f64, side: Side| -> u32 {
        let cost = |p: &Point3<f64>| {
            let d = (azimuth(p.x, p.z, axis_x) - psi).rem_euclid(std::f64::consts::TAU);
            let d = d.min(std::f64::consts::TAU - d);
            (d * 0.12).powi(2) + (p.y - y).powi(2)
        };
        wall_pts
            .iter()
            .min_by(|(_, p), (_, q)| {
                let (cp, cq) = (cost(p), cost(q));
                if (cp - cq).abs() > 1e-12 {
                    cp.total_cmp(&cq)
                } else {
                    (-side.sign() * p.z).total_cmp(&(-side.sign() * q.z))
                }
            })
            .map(|(a, _)| *a)
            .unwrap_or(wall[0])
    };
    use std::f64::consts::PI;
    let ventral = PI;
    let mirror = |psi: f64, side: Side| {
        if side == Side::Right {
            psi
        } else {
            2.0 * PI - psi
        }
    };
    let h = |t: f64| ymin + (ymax - ymin) * t;
    for (group, total_force) in ABDOMINAL_FORCES {
        let n = count(group, f);
        let lanes = match group {
            MuscleGroup::RectusAbdominis => 2,
            MuscleGroup::TransversusAbdominis => 4,
            _ => 3,
        };
        // Elements per chain so that the group gets its element count.
        let segments = (n / (2 * lanes)).max(2);
        let mut chains: Vec<(Side, Vec<u32>)> = Vec::new();
        for side in [Side::Right, Side::Left] {
            for lane in 0..lanes {
                if side == Side::Left {
                    // The left chains are the mirror images of the right ones (z -> -z).
                    if let Some((_, right)) = chains
                        .iter()
                        .filter(|(s, _)| *s == Side::Right)
                        .nth(lane)
                        .cloned()
                    {
                        let mirrored: Vec<u32> = right
                            .iter()
                            .map(|&n| mirror_anchor(n, anchors, &vertex_mirror))
                            .collect();
                        chains.push((Side::Left, mirrored));
                    }
                    continue;
                }
                let l = lane as f64;
                let mut nodes = Vec::new();
                // Interior samples s in (0, 1) along the chain's path on the wall.
                let interior =
                    |segments: usize| (1..segments).map(move |k| k as f64 / segments as f64);
                match group {
                    MuscleGroup::RectusAbdominis => {
                        let psi = mirror(ventral - 0.12 - 0.12 * l, side);
                        let z = side.sign() * (0.02 + 0.025 * l);
                        let base = anchors[nearest(psi, ymin, side) as usize].rest;
                        let pubis = Point3::new(base.x, abdomen.floor_y + 0.04, z);
                        nodes.push(push_anchor(anchors, Body::Ground, pubis));
                        for s in interior(segments) {
                            nodes.push(nearest(psi, h(0.05 + 0.9 * s), side));
                        }
                        let rib = &ribs[rib_index(6 + lane, side)];
                        let top = rib
                            .cartilage
                            .last()
                            .copied()
                            .unwrap_or(sternum.xiphisternal);
                        nodes.push(push_anchor(anchors, Body::Rib(rib.index() as u8), top));
                    }
                    MuscleGroup::TransversusAbdominis => {
                        // Hoops from the thoracolumbar fascia round to the linea alba.
                        let y = h(0.15 + 0.22 * l);
                        let back = anchors[nearest(mirror(0.7, side), y, side) as usize].rest;
                        nodes.push(push_anchor(
                            anchors,
                            Body::Ground,
                            Point3::new(back.x - 0.01, y, back.z),
                        ));
                        for s in interior(segments) {
                            nodes.push(nearest(mirror(0.7 + (ventral - 0.75) * s, side), y, side));
                        }
                        // The linea alba: the midline vertex, shared with the other side's hoop.
                        nodes.push(nearest(ventral, y, side));
                    }
                    MuscleGroup::ExternalObliques | MuscleGroup::InternalObliques => {
                        let external = group == MuscleGroup::ExternalObliques;
                        let rib = &ribs[rib_index(8 + lane, side)];
                        let rib_anchor = on_bone(rib, 0.8, anchors);
                        // External: from the lower ribs down and forward to the linea alba;
                        // internal: from the iliac crest up and forward to the linea alba.
                        let (psi0, t0, t1) = if external {
                            (1.3 + 0.1 * l, 0.85 - 0.05 * l, 0.15 + 0.15 * l)
                        } else {
                            (1.2 + 0.1 * l, 0.1, 0.55 + 0.15 * l)
                        };
                        let start = if external {
                            rib_anchor
                        } else {
                            let crest = Point3::new(
                                axis_x - 0.02,
                                abdomen.floor_y + 0.09,
                                side.sign() * 0.12,
                            );
                            push_anchor(anchors, Body::Ground, crest)
                        };
                        nodes.push(start);
                        for s in interior(segments) {
                            nodes.push(nearest(
                                mirror(psi0 + (ventral - 0.08 - psi0) * s, side),
                                h(t0 + (t1 - t0) * s),
                                side,
                            ));
                        }
                        nodes.push(nearest(ventral, h(t1), side));
                    }
                    _ => {}
                }
                nodes.dedup();
                if nodes.len() >= 2 {
                    chains.push((side, nodes));
                }
            }
        }
        // Chains in parallel share the group's force; each is one element wrapping over the
        // wall through its via points.
        let per_chain = total_force / chains.len().max(1) as f64;
        for (side, nodes) in chains {
            out.push(MuscleElement {
                group,
                path: nodes,
                gain: 1.0,
                side: Some(side),
                max_force: per_chain,
                tissue_length: None,
            });
        }
    }
}

/// Anchor of each abdominal-surface vertex -> anchor of the vertex whose parametric direction
/// is its mirror image (z -> -z).
fn abdomen_mirror(abdomen: &Abdomen) -> std::collections::HashMap<u32, u32> {
    let key = |d: &Vector3<f64>| {
        (
            (d.x * 1e9).round() as i64,
            (d.y * 1e9).round() as i64,
            (d.z * 1e9).round() as i64,
        )
    };
    let by_dir: std::collections::HashMap<(i64, i64, i64), usize> = abdomen
        .sphere
        .iter()
        .enumerate()
        .map(|(v, d)| (key(d), v))
        .collect();
    abdomen
        .sphere
        .iter()
        .enumerate()
        .filter_map(|(v, d)| {
            by_dir
                .get(&key(&Vector3::new(d.x, d.y, -d.z)))
                .map(|&m| (abdomen.anchor[v], abdomen.anchor[m]))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_external_intercostal_drive_passes_through_its_cited_points() {
        // De Troyer, Gorman & Gandevia 2003: full at the third, 6.7 / 11.9 Hz at the fifth,
        // silent at the seventh
        assert_eq!(external_intercostal_drive(1), 1.0);
        assert_eq!(external_intercostal_drive(3), 1.0);
        assert!((external_intercostal_drive(5) - 6.7 / 11.9).abs() < 1e-3);
        assert_eq!(external_intercostal_drive(7), 0.0);
        assert_eq!(external_intercostal_drive(11), 0.0);
        // linear between them, falling caudally
        let d: Vec<f64> = (1..=11).map(external_intercostal_drive).collect();
        assert!(d.windows(2).all(|w| w[1] <= w[0]), "{d:?}");
        assert!((d[3] - 0.5 * (1.0 + 0.563)).abs() < 1e-12);
    }
}
