//! The abdominal cavity (thesis 2.3): a subdivided sphere deformed to fit under the rib cage
//! (its top is the diaphragm dome, spanning the costal margin) and above the pelvis, behind the
//! abdominal wall. Vertices on the back and the pelvic floor are fixed; the vertices of the
//! costal margin ride on the ribs (the diaphragm's insertions); the dome and the lateral and
//! ventral wall are free point masses sharing the abdomen's 8 kg (thesis Table 1.1).

use super::skeleton::{Rib, Scale, Side, Spine, Sternum, rib_index};
use super::subject::Subject;
use super::{Anchor, Body, push_anchor};
use crate::Result;
use crate::mesh::TriMesh;
use nalgebra::{Point3, Vector3};
use std::collections::{HashMap, HashSet};
use std::f64::consts::{FRAC_PI_2, PI};

/// Thickness of the ventral and lateral abdominal wall (muscle and fat) between the skin's
/// waist and the cavity: (base [m], growth per kg of body mass above the threshold [m/kg],
/// threshold [kg]): 2 cm up to 50 kg, 3 cm at 75 kg. Chosen by hand in the first anatomy
/// (commit 270ac4a); the cavity's half-breadth at the waist is the skin's less this wall.
/// Source: CT at L3-L4 of 232 patients (Abbas, Alrawi & Saeed, Khartoum 2021, "Assessment of
/// anterior abdominal wall layers thickness under the influence of age and sex", abstract at
/// fortuneonline.org): subcutaneous fat 17.5 mm in men and 24.8 mm in women; rectus abdominis
/// 8.1, external oblique 5.4, internal oblique 6.7, transversus 4.9 mm (both sexes). For a man
/// that is 25.6 mm ventrally (fat and rectus) and 34.5 mm laterally (fat and the three flat
/// muscles); ours, 30 mm at 75 kg, lies between (agrees for men). Women's wall is thicker than
/// ours: 33-42 mm there, and rectus 10.3 mm plus fat 23.9 mm, 34 mm, in 545 women (Kim, Lim,
/// Lee & Kim 2012, Arch Plast Surg 39:528, doi:10.5999/aps.2012.39.5.528), against ours
/// 24 mm at 60 kg (disagrees for women: the formula has no sex term). Rectus alone: 14.7 +- 2.9
/// mm (ultrasound, 120 adults; Egwu et al. 2014, Studia Medyczne 30:180).
pub const ABDOMINAL_WALL_THICKNESS: (f64, f64, f64) = (0.02, 0.0004, 50.0);

/// Role of an abdominal-surface vertex.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VertexRole {
    /// Fixed to the skeleton: back wall and pelvic floor.
    Fixed,
    /// On the costal margin, carried by a rib, the sternum or the spine: diaphragm insertions.
    Insertion,
    /// Diaphragm dome (free).
    Dome,
    /// Lateral and ventral abdominal wall (free).
    Wall,
}

/// Height of the dome's apex above the higher of the 9th thoracic vertebra and the 5th rib's
/// anterior end [m] at end-expiration, by posture. Lying supine, the weight of the abdominal
/// contents pushes the relaxed diaphragm cranially (the supine FRC is about 20 % lower than
/// the upright one), lengthening its fibres.
/// Calibrated: the posture-dependent dome height was set by hand in commit aeb7bbe against
/// `tests/physiology.rs` (tidal volumes, diaphragm excursion, rib-cage share); no command
/// reproduces a fit, and no measured cranial shift of the relaxed dome by posture was found
/// (sitting/supine MRI, Takazakura et al. 2004, J Magn Reson Imaging 19:605, reports
/// excursions, not positions; upright CT, Yamada et al. 2020, Respiration 99:598, reports lungs
/// 10.9 % larger standing than supine at full inspiration, not the dome's height).
fn apex_rise(posture: super::Posture) -> f64 {
    match posture {
        super::Posture::Standing => 0.04,
        super::Posture::Sitting => 0.045,
        super::Posture::Supine => 0.07,
    }
}

/// Inset of the diaphragm's insertions from the costal-margin centrelines toward the cavity
/// axis [m] (half a rib's thickness).
/// Unsourced: no source: chosen as half a rib's thickness, itself not sourced. The margin is
/// costal cartilage (ribs 7-10); no cartilage or rib depth was read (the rib cross-section
/// studies, see `RIB_BONE_DENSITY` and `WALL_THICKNESS`, give areas in their full texts).
const MARGIN_INSET: f64 = 0.008;

/// Exponent below 1 that fills out the dome's shoulders (a rounder, fuller dome).
/// Unsourced: no source: chosen by eye for the dome's shape; no measured profile of the dome
/// (height against distance from the rim) was found to fit it to.
const DOME_FULLNESS: f64 = 0.7;

/// Height of the dome/wall boundary on the unit sphere (u_y above it: dome).
/// Numerical: a parametrisation of the icosphere; the dome's physical extent is set by the
/// costal margin it spans.
const DOME_CUT: f64 = 0.2;

/// Chords by which the smooth dome's arc over one edge is measured ([`Abdomen::dome_arc`]).
/// Against 128 chords the arc of a level-0 edge (the longest) differs by at most 0.53 % of
/// itself, against 64 by 0.26 % (`cargo test --release --lib anatomy::abdomen --
/// --nocapture`): the sampled curve crosses the creases the ruled dome has over the margin's
/// points, so it converges slowly and unevenly.
const ARC_SAMPLES: usize = 32;

/// Subdivisions of the icosphere on which the smooth dome's cap volume is measured (10,242
/// vertices, four times the finest level of detail).
const REFERENCE_SUBDIVISIONS: u32 = 5;

/// Triangles wholly above [`DOME_CUT`] (the dome) and the vertices on edges between dome and
/// non-dome triangles (the rim, the diaphragm's insertions).
fn dome_and_rim(sphere: &TriMesh, dirs: &[Vector3<f64>]) -> (Vec<bool>, HashSet<u32>) {
    let dome_tri: Vec<bool> = sphere
        .triangles
        .iter()
        .map(|t| t.iter().all(|&v| dirs[v as usize].y > DOME_CUT))
        .collect();
    let mut edge_faces: HashMap<(u32, u32), Vec<usize>> = HashMap::new();
    for (f, t) in sphere.triangles.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            edge_faces.entry((a.min(b), a.max(b))).or_default().push(f);
        }
    }
    let mut rim_set: HashSet<u32> = HashSet::new();
    for ((a, b), faces) in &edge_faces {
        if faces.len() == 2 && dome_tri[faces[0]] != dome_tri[faces[1]] {
            rim_set.insert(*a);
            rim_set.insert(*b);
        }
    }
    (dome_tri, rim_set)
}

/// The smooth dome spanning the costal margin (thesis 2.3): a quarter-ellipse profile from
/// each rim point, vertical at the rim (the zone of apposition) and flat at the apex.
struct DomeShape<'a> {
    margin: &'a Margin,
    axis_x: f64,
    apex_x: f64,
    apex_y: f64,
}

impl DomeShape<'_> {
    /// Position of the dome point in the direction `u` of the unit sphere (u_y > DOME_CUT).
    fn point(&self, u: &Vector3<f64>) -> Point3<f64> {
        let psi = azimuth(u.x, u.z, 0.0);
        let (rim_p, _) = self.margin.at_azimuth(psi, self.axis_x);
        let rim_h = Vector3::new(rim_p.x - self.axis_x, 0.0, rim_p.z);
        let t = ((u.y - DOME_CUT) / (1.0 - DOME_CUT)).clamp(0.0, 1.0);
        let c = (t * FRAC_PI_2).cos();
        let apex = Vector3::new(self.apex_x - self.axis_x, 0.0, 0.0);
        let h = apex + (rim_h - apex) * c;
        let y = rim_p.y + (self.apex_y - rim_p.y) * (t * FRAC_PI_2).sin().powf(DOME_FULLNESS);
        Point3::new(self.axis_x + h.x, y, h.z)
    }

    /// Rim and dome positions on `sphere` (other vertices left at the origin).
    fn place(&self, dirs: &[Vector3<f64>], rim: &HashSet<u32>, out: &mut Vec<Point3<f64>>) {
        out.clear();
        out.extend(dirs.iter().enumerate().map(|(v, u)| {
            if rim.contains(&(v as u32)) {
                self.margin
                    .at_azimuth(azimuth(u.x, u.z, 0.0), self.axis_x)
                    .0
            } else if u.y > DOME_CUT {
                self.point(u)
            } else {
                Point3::origin()
            }
        }));
    }

    /// Length [m] of the smooth dome's curve between the points of unit-sphere directions
    /// `a` and `b` (rim points given by the direction of their azimuth at the rim's height,
    /// [`DOME_CUT`]): the image of the great-circle arc between them, measured by
    /// `samples` chords ([`ARC_SAMPLES`]). It is the length of the tissue a dome edge stands
    /// for; the edge itself is its chord, shorter on a coarse dome.
    fn arc(&self, a: &Vector3<f64>, b: &Vector3<f64>, samples: usize) -> f64 {
        let mut prev = self.point(a);
        let mut length = 0.0;
        for k in 1..=samples {
            let f = k as f64 / samples as f64;
            let p = self.point(&(a * (1.0 - f) + b * f).normalize());
            length += (p - prev).norm();
            prev = p;
        }
        length
    }

    /// Volume [m^3] between the faceted dome and the rim loop: the cap the dome takes from
    /// the thoracic cavity. With the origin at the rim's centroid, the fan closing the rim
    /// adds nothing, so the cap is the dome triangles' signed volume about that point.
    fn cap_volume(
        triangles: &[[u32; 3]],
        dome_tri: &[bool],
        rim: &HashSet<u32>,
        p: &[Point3<f64>],
    ) -> f64 {
        // in index order, so that every build gives the same bits
        let mut ring: Vec<u32> = rim.iter().copied().collect();
        ring.sort_unstable();
        let c = ring
            .iter()
            .map(|&v| p[v as usize].coords)
            .sum::<Vector3<f64>>()
            / ring.len() as f64;
        let six: f64 = triangles
            .iter()
            .zip(dome_tri)
            .filter(|(_, d)| **d)
            .map(|(t, _)| {
                let [a, b, d] = t.map(|v| p[v as usize].coords - c);
                a.dot(&b.cross(&d))
            })
            .sum();
        six.abs() / 6.0
    }

    /// Volume [m^3] the faceted dome on `sphere` cuts off the smooth dome: its cap volume
    /// less that of the same construction on a fine icosphere (about converged). A coarse
    /// dome's facets lie inside the smooth dome, so the mesh hands this much of the
    /// abdomen's volume to the thorax (10 % of the thorax at level of detail 0); the observed
    /// volumes add it back (see [`Abdomen::dome_faceting_volume`]).
    fn faceting_volume(&self, sphere: &TriMesh, dirs: &[Vector3<f64>]) -> Result<f64> {
        let fine = TriMesh::icosphere(REFERENCE_SUBDIVISIONS)?;
        let fine_dirs: Vec<Vector3<f64>> =
            fine.vertices.iter().map(|p| p.coords.normalize()).collect();
        let (fine_dome, fine_rim) = dome_and_rim(&fine, &fine_dirs);
        let mut p = Vec::new();
        self.place(&fine_dirs, &fine_rim, &mut p);
        let smooth = Self::cap_volume(&fine.triangles, &fine_dome, &fine_rim, &p);
        let (dome, rim) = dome_and_rim(sphere, dirs);
        self.place(dirs, &rim, &mut p);
        Ok(smooth - Self::cap_volume(&sphere.triangles, &dome, &rim, &p))
    }
}

/// The abdominal cavity surface.
#[derive(Clone, Debug)]
pub struct Abdomen {
    /// Anchor index of each surface vertex.
    pub anchor: Vec<u32>,
    /// Role of each surface vertex.
    pub roles: Vec<VertexRole>,
    /// Closed, outward-oriented triangles (surface vertex indices).
    pub triangles: Vec<[u32; 3]>,
    /// Whether each triangle belongs to the diaphragm dome.
    pub dome: Vec<bool>,
    /// Costal-margin loop (surface vertex indices), ordered by azimuth from dorsal, via the
    /// right side, ventral, to the left.
    pub rim: Vec<u32>,
    /// Mass of each free vertex [kg] (0 for carried vertices).
    pub mass: Vec<f64>,
    /// Unit-sphere direction each vertex came from (its parametric coordinates).
    pub sphere: Vec<Vector3<f64>>,
    /// Horizontal centre (x) of the cavity's vertical axis [m].
    pub axis_x: f64,
    /// Height of the pelvic floor [m].
    pub floor_y: f64,
    /// Height of the dome apex at rest [m].
    pub apex_y: f64,
    /// Volume [m^3] by which the faceted dome falls short of the smooth dome it samples
    /// (0 for a subject's own cavity). The mesh's thorax is that much larger and its abdomen
    /// that much smaller than the smooth surfaces'; the observed volumes are corrected by it,
    /// so that the levels of detail agree on the split of the trunk (dynamics use the mesh).
    pub dome_faceting_volume: f64,
    /// Length [m] of the smooth dome's curve over each edge of the dome and its rim (key: the
    /// edge's surface vertices, smaller first), the length of the tissue the edge's chord
    /// stands for. A coarse dome's chords cut across the dome's curvature. For a subject's own
    /// cavity, which the coarse mesh samples as it samples the smooth dome, each edge keeps
    /// the generated dome's arc over chord on its fitted chord.
    pub dome_arc: HashMap<(u32, u32), f64>,
}

impl Abdomen {
    /// Triangles as anchor indices.
    pub fn anchor_triangles(&self) -> impl Iterator<Item = [u32; 3]> + '_ {
        self.triangles
            .iter()
            .map(|t| t.map(|v| self.anchor[v as usize]))
    }

    /// Dome triangles as anchor indices.
    pub fn dome_triangles(&self) -> impl Iterator<Item = [u32; 3]> + '_ {
        self.triangles
            .iter()
            .zip(&self.dome)
            .filter(|(_, d)| **d)
            .map(|(t, _)| t.map(|v| self.anchor[v as usize]))
    }

    /// Number of surface vertices.
    pub fn len(&self) -> usize {
        self.anchor.len()
    }

    /// Whether the surface is empty (never, once built).
    pub fn is_empty(&self) -> bool {
        self.anchor.is_empty()
    }

    /// Surface vertices with a given role.
    pub fn with_role(&self, role: VertexRole) -> impl Iterator<Item = u32> + '_ {
        self.roles
            .iter()
            .enumerate()
            .filter(move |(_, r)| **r == role)
            .map(|(i, _)| i as u32)
    }
}

/// Azimuth about the cavity axis: 0 dorsal, increasing through the right side (pi/2),
/// ventral (pi) and the left side (3 pi / 2).
pub fn azimuth(x: f64, z: f64, axis_x: f64) -> f64 {
    let phi = z.atan2(-(x - axis_x)); // 0 dorsal, +pi/2 right
    phi.rem_euclid(2.0 * PI)
}

/// A closed polyline (the costal margin) with the carrier of each vertex.
pub(super) struct Margin {
    /// Vertices of the loop, dorsal midline first, via the right side, ventral, to the left.
    pub(super) points: Vec<Point3<f64>>,
    /// Carrier of each vertex.
    pub(super) bodies: Vec<Body>,
}

impl Margin {
    /// Where a horizontal ray from the axis at azimuth `psi` meets the margin: the point and the
    /// body of the nearer segment end.
    fn at_azimuth(&self, psi: f64, axis_x: f64) -> (Point3<f64>, Body) {
        let n = self.points.len();
        let az: Vec<f64> = self
            .points
            .iter()
            .map(|p| azimuth(p.x, p.z, axis_x))
            .collect();
        for i in 0..n {
            let j = (i + 1) % n;
            let (a0, mut a1) = (az[i], az[j]);
            let mut q = psi;
            if a1 < a0 {
                a1 += 2.0 * PI;
                if q < a0 {
                    q += 2.0 * PI;
                }
            }
            if q >= a0 && q <= a1 {
                let f = if a1 > a0 { (q - a0) / (a1 - a0) } else { 0.0 };
                let p = self.points[i] + (self.points[j] - self.points[i]) * f;
                let body = if f < 0.5 {
                    self.bodies[i]
                } else {
                    self.bodies[j]
                };
                return (p, body);
            }
        }
        (self.points[0], self.bodies[0])
    }
}

/// The costal margin, inset by the wall thickness: xiphoid, 7th costal cartilage, ends of ribs
/// 8-12 and the spine at the first lumbar level, on both sides.
pub(super) fn costal_margin(
    ribs: &[Rib],
    sternum: &Sternum,
    spine: &Spine,
    axis_x: f64,
    scale: &Scale,
) -> Margin {
    let xiphoid = Point3::new(
        sternum.xiphisternal.x - 0.01 * scale.x,
        sternum.xiphisternal.y - 0.045 * scale.y,
        0.0,
    );
    let l1 = spine
        .joint("lumbar1")
        .unwrap_or(Point3::new(-0.03, 1.12, 0.0));
    // Dorsally the diaphragm's crura reach down beside the lumbar spine: the margin passes
    // just behind the front of the vertebral bodies.
    let dorsal = Point3::new(
        l1.x - 0.01 * scale.x,
        ribs[rib_index(12, Side::Right)].head.y - 0.02,
        0.0,
    );
    let mut right: Vec<(Point3<f64>, Body)> = Vec::new();
    let r7 = &ribs[rib_index(7, Side::Right)];
    let c7 = &r7.cartilage;
    right.push((c7[c7.len() / 2], Body::Rib(r7.index() as u8)));
    right.push((r7.bone_end(), Body::Rib(r7.index() as u8)));
    for level in 8..=12 {
        let r = &ribs[rib_index(level, Side::Right)];
        right.push((r.bone_end(), Body::Rib(r.index() as u8)));
    }
    // Dorsally the margin follows the bodies of ribs 11 and 12 round the posterior gutters.
    for (level, f) in [(11, 0.4), (12, 0.3)] {
        let r = &ribs[rib_index(level, Side::Right)];
        let p = super::skeleton::point_at(&r.bone, f * super::skeleton::polyline_length(&r.bone));
        right.push((p, Body::Rib(r.index() as u8)));
    }
    let mut points = vec![dorsal];
    let mut bodies = vec![Body::Ground];
    // Right side from dorsal to ventral, xiphoid, then the left side from ventral to dorsal.
    for (p, b) in right.iter().rev() {
        points.push(*p);
        bodies.push(*b);
    }
    points.push(xiphoid);
    bodies.push(Body::Sternum);
    for (p, b) in right.iter() {
        points.push(Point3::new(p.x, p.y, -p.z));
        let left = match b {
            Body::Rib(i) => Body::Rib(*i + 12),
            other => *other,
        };
        bodies.push(left);
    }
    // Inset toward the axis.
    let points = points
        .into_iter()
        .map(|p| {
            let d = Vector3::new(axis_x - p.x, 0.0, -p.z);
            let n = d.norm();
            if n > 1e-9 {
                p + d * (MARGIN_INSET.min(0.5 * n) / n)
            } else {
                p
            }
        })
        .collect();
    Margin { points, bodies }
}

/// Builds the abdominal cavity from an icosphere with `subdivisions` (2, 3, 4), appending its
/// anchors.
#[allow(clippy::too_many_arguments)]
pub fn build(
    subject: &Subject,
    scale: &Scale,
    ribs: &[Rib],
    sternum: &Sternum,
    spine: &Spine,
    masses: &HashMap<String, f64>,
    subdivisions: u32,
    anchors: &mut Vec<Anchor>,
) -> Result<Abdomen> {
    build_sampled(
        subject,
        scale,
        ribs,
        sternum,
        spine,
        masses,
        subdivisions,
        anchors,
        ARC_SAMPLES,
    )
}

/// [`build`] with the smooth dome's arcs measured by `arc_samples` chords.
#[allow(clippy::too_many_arguments)]
fn build_sampled(
    subject: &Subject,
    scale: &Scale,
    ribs: &[Rib],
    sternum: &Sternum,
    spine: &Spine,
    masses: &HashMap<String, f64>,
    subdivisions: u32,
    anchors: &mut Vec<Anchor>,
    arc_samples: usize,
) -> Result<Abdomen> {
    let sphere = TriMesh::icosphere(subdivisions)?;
    let n = sphere.vertices.len();
    let ansur = super::data::ansur2();
    let sex = if subject.sex == super::Sex::Male {
        "M"
    } else {
        "F"
    };
    let waist = |name: &str| {
        ansur
            .get(&(sex.to_string(), name.to_string()))
            .map(|r| r.predict(subject.stature, subject.mass, subject.age))
    };
    // Cavity cross-section at the waist: the skin's waist less the abdominal wall (about 2.5 cm
    // of muscle and fat ventrally and laterally, more for heavier subjects).
    let (wall_base, wall_per_kg, wall_from) = ABDOMINAL_WALL_THICKNESS;
    let wall = wall_base + wall_per_kg * (subject.mass - wall_from).max(0.0);
    let half_breadth = 0.5 * waist("waistbreadth").unwrap_or(0.30) - wall;
    let x_back = -0.06 * scale.x;
    let x_front = sternum.xiphisternal.x - 0.005;
    let axis_x = 0.5 * (x_front + x_back);
    let margin = costal_margin(ribs, sternum, spine, axis_x, scale);
    let floor_y = scale.y_origin - 0.07 * scale.y;
    let waist_y = floor_y
        + 0.55
            * (margin
                .points
                .iter()
                .map(|p| p.y)
                .fold(f64::INFINITY, f64::min)
                - floor_y);
    // Dome apex: at end-expiration the domes rise to the level of the 9th thoracic vertebra
    // dorsally and the 5th rib's anterior end ventrally; take the higher.
    let t9 = spine.joint("thoracic9").map(|p| p.y).unwrap_or(1.22);
    let apex_y =
        t9.max(ribs[rib_index(5, Side::Right)].bone_end().y) + apex_rise(subject.posture) * scale.y;
    let apex_x = axis_x + 0.1 * (x_front - axis_x);

    let dirs: Vec<Vector3<f64>> = sphere
        .vertices
        .iter()
        .map(|p| p.coords.normalize())
        .collect();
    let (dome_tri, rim_set) = dome_and_rim(&sphere, &dirs);
    let shape = DomeShape {
        margin: &margin,
        axis_x,
        apex_x,
        apex_y,
    };
    let dome_faceting_volume = shape.faceting_volume(&sphere, &dirs)?;
    let in_dome: Vec<bool> = (0..n).map(|v| dirs[v].y > DOME_CUT).collect();
    // The smooth dome's arc over each edge between dome and rim vertices; a rim vertex sits on
    // the margin, the smooth dome's curve at the rim's height, in its azimuth's direction.
    let on_smooth = |v: usize| {
        let u = dirs[v];
        if rim_set.contains(&(v as u32)) {
            let r = u.x.hypot(u.z).max(1e-12);
            let h = (1.0 - DOME_CUT * DOME_CUT).sqrt() / r;
            Vector3::new(u.x * h, DOME_CUT, u.z * h)
        } else {
            u
        }
    };
    let mut dome_arc = HashMap::new();
    for t in &sphere.triangles {
        for k in 0..3 {
            let (a, b) = (t[k].min(t[(k + 1) % 3]), t[k].max(t[(k + 1) % 3]));
            if in_dome[a as usize] && in_dome[b as usize] && !dome_arc.contains_key(&(a, b)) {
                let arc = shape.arc(&on_smooth(a as usize), &on_smooth(b as usize), arc_samples);
                dome_arc.insert((a, b), arc);
            }
        }
    }

    let mut roles = Vec::with_capacity(n);
    let mut positions = Vec::with_capacity(n);
    let mut carriers = Vec::with_capacity(n);
    let smooth = |x: f64| {
        let x = x.clamp(0.0, 1.0);
        x * x * (3.0 - 2.0 * x)
    };
    for v in 0..n {
        let u = dirs[v];
        let psi = azimuth(u.x, u.z, 0.0);
        let (rim_p, rim_body) = margin.at_azimuth(psi, axis_x);
        let rim_h = Vector3::new(rim_p.x - axis_x, 0.0, rim_p.z);
        if rim_set.contains(&(v as u32)) {
            roles.push(VertexRole::Insertion);
            positions.push(rim_p);
            carriers.push(rim_body);
        } else if in_dome[v] {
            positions.push(shape.point(&u));
            roles.push(VertexRole::Dome);
            carriers.push(Body::Vertex(0));
        } else {
            let s = ((DOME_CUT - u.y) / (1.0 + DOME_CUT)).clamp(0.0, 1.0);
            // Unit horizontal direction and the waist ellipse (ventral and dorsal halves).
            let r = u.x.hypot(u.z).max(1e-12);
            let (ax, az) = (u.x / r, u.z / r);
            let depth = if ax > 0.0 {
                x_front - axis_x
            } else {
                axis_x - x_back
            };
            let waist_h = Vector3::new(ax * depth, 0.0, az * half_breadth);
            let b = smooth(s / 0.35);
            let mut h = rim_h * (1.0 - b) + waist_h * b;
            let closure = if s < 0.55 {
                1.0
            } else {
                (1.0 - ((s - 0.55) / 0.45).powi(2)).max(0.0).sqrt()
            };
            h *= closure;
            let y_mid = rim_p.y + (waist_y - rim_p.y) * smooth(s / 0.35);
            let y = if s < 0.35 {
                y_mid
            } else {
                waist_y + (floor_y - waist_y) * ((s - 0.35) / 0.65)
            };
            positions.push(Point3::new(axis_x + h.x, y, h.z));
            let dorsal = ax < -0.45;
            let fixed = s > 0.8 || (dorsal && s > 0.05);
            roles.push(if fixed {
                VertexRole::Fixed
            } else {
                VertexRole::Wall
            });
            carriers.push(if fixed { Body::Ground } else { Body::Vertex(0) });
        }
    }

    // Free vertices get consecutive indices; the contents' mass is shared by the vertices'
    // areas on the parametric sphere (nearly uniform), not by the deformed areas, so that no
    // vertex squeezed near the costal margin becomes needlessly light.
    let mut area = vec![0.0; n];
    for t in &sphere.triangles {
        let [a, b, c] = t.map(|v| Point3::from(dirs[v as usize]));
        let ar = 0.5 * (b - a).cross(&(c - a)).norm();
        for v in t {
            area[*v as usize] += ar / 3.0;
        }
    }
    let free_area: f64 = (0..n)
        .filter(|&v| matches!(carriers[v], Body::Vertex(_)))
        .map(|v| area[v])
        .sum();
    let total_mass = masses.get("abdomen").copied().unwrap_or(8.0) * subject.mass / 75.0;
    let mut mass = vec![0.0; n];
    let mut next_free = 0u32;
    let mut anchor = Vec::with_capacity(n);
    for v in 0..n {
        let body = match carriers[v] {
            Body::Vertex(_) => {
                mass[v] = total_mass * area[v] / free_area;
                next_free += 1;
                Body::Vertex(next_free - 1)
            }
            other => other,
        };
        anchor.push(push_anchor(anchors, body, positions[v]));
    }
    // Rim loop ordered by azimuth.
    let mut rim: Vec<u32> = rim_set.into_iter().collect();
    rim.sort_by(|a, b| {
        let pa = positions[*a as usize];
        let pb = positions[*b as usize];
        azimuth(pa.x, pa.z, axis_x).total_cmp(&azimuth(pb.x, pb.z, axis_x))
    });
    Ok(Abdomen {
        anchor,
        roles,
        triangles: sphere.triangles.clone(),
        dome: dome_tri,
        rim,
        mass,
        sphere: dirs,
        axis_x,
        floor_y,
        apex_y,
        dome_faceting_volume,
        dome_arc,
    })
}

#[cfg(test)]
mod tests {
    use super::{ARC_SAMPLES, build_sampled};
    use crate::anatomy::{LOD_SUBDIVISIONS, Scale, Subject, data, skeleton};

    /// Four times [`ARC_SAMPLES`] change the smooth dome's arc over any edge of the coarsest
    /// dome (level of detail 0, rim edges included) by under 1 % of itself: the sampling
    /// error is a small part of the correction the arcs make (level 0's fibre chords are up
    /// to 13.4 % short of their arcs, `tests/anatomy_geometry.rs`) and of the 5 % the levels
    /// of detail are to agree within.
    #[test]
    fn more_arc_samples_change_the_coarsest_arcs_by_under_1_percent() {
        let subject = Subject::default();
        let scale = Scale::for_subject(&subject, &data::ansur2());
        let masses = data::body_masses();
        let spine = skeleton::build_spine(&scale);
        let sternum = skeleton::build_sternum(&subject, &scale, &masses);
        let ribs = skeleton::build_ribs(&subject, &scale, &sternum, &masses);
        let arcs = |samples| {
            let mut anchors = Vec::new();
            build_sampled(
                &subject,
                &scale,
                &ribs,
                &sternum,
                &spine,
                &masses,
                LOD_SUBDIVISIONS[0],
                &mut anchors,
                samples,
            )
            .unwrap()
            .dome_arc
        };
        let coarse = arcs(ARC_SAMPLES);
        assert!(!coarse.is_empty());
        let change = |samples| {
            let fine = arcs(samples);
            coarse
                .iter()
                .map(|(edge, &a)| (a / fine[edge] - 1.0).abs())
                .fold(0.0, f64::max)
        };
        let (double, quadruple) = (change(2 * ARC_SAMPLES), change(4 * ARC_SAMPLES));
        println!(
            "largest change of a level-0 arc from {ARC_SAMPLES} chords: {double:.2e} to {}, {quadruple:.2e} to {}",
            2 * ARC_SAMPLES,
            4 * ARC_SAMPLES
        );
        assert!(double.max(quadruple) < 0.01, "{double:e} / {quadruple:e}");
    }
}
