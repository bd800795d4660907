//! The skin: a closed trunk surface from the neck to the hips generated from the subject's
//! anthropometry (thesis 3.2 used MakeHuman; we build it from ANSUR II regressions), the
//! SLP-like marker grid bound to it, its registration to a recording's first frame with
//! skin fitting (thesis 3.2, figure 3.4), other marker sets (built-in named sets placed from
//! the landmarks, and recorded sets registered to the surface without correspondences and
//! bound to it), and export of meshes, animations and pictures.
//!
//! Frame: ISB, x anterior, y superior, z right, metres, origin on the floor below the sacrum,
//! midsagittal plane z = 0.

mod anthropometry;
pub mod export;
pub mod geometry;
mod markers;
mod profile;
mod reference;
mod register;
pub mod render;
mod sets;
mod smooth;
mod surface;

pub use anthropometry::TorsoDimensions;
pub use markers::{MAX_GRID_SIZE, Marker, MarkerGrid, SurfaceBinding};
pub use profile::{Pchip, Section};
pub use reference::{
    BONE_CLEARANCE, REFERENCE_STATURE, SPINE_CENTRES_MM, WALL_CLEARANCE, anatomy_clearance,
    bone_polylines, clavicles, dense_bone_points, densify, is_trunk_vertebra, spinous_tips,
    trunk_spine, wall_points,
};
pub use register::{FitOptions, Registration, RigidTransform, SkinFitReport, register_rigid};
pub use sets::{BUILTIN_SETS, MarkerSet};
pub use smooth::{taubin_smooth, vertex_neighbours};
pub use surface::{
    AttachedMarker, DISTINCT_POSE_DEG, MIN_SURFACE_MARKERS, SurfaceOptions, SurfaceRegistration,
    register_candidates, register_to_surface,
};

use crate::anatomy::{Anatomy, Sex, Subject};
use crate::{Error, Result};
use nalgebra::{Point2, Point3};
use std::f64::consts::TAU;

/// Reach [m] of the smooth widening around a bone the trunk shape leaves too little room
/// for (1.75 m subject): about half a chest depth, so the widening spreads like soft tissue.
/// Numerical: a smoothing reach of the skin generator.
const ENCLOSE_REACH: f64 = 0.08;

/// Resolution and enclosure settings of the skin generator.
#[derive(Clone, Debug, PartialEq)]
pub struct SkinOptions {
    /// Vertices around each horizontal ring (>= 16).
    pub around: usize,
    /// Rings on the side surface, neck to hips (>= 8).
    pub side_rings: usize,
    /// Concentric rings of each flat end cap (>= 1).
    pub cap_rings: usize,
    /// Radial clearance [m] kept between the skin and each bone sample of the anatomy
    /// ([`Skin::for_anatomy`]): bone half-thickness plus the thinnest soft tissue.
    pub bone_clearance: f64,
}

impl Default for SkinOptions {
    /// 88 x 66 side vertices plus two caps of 4 rings: 6,514 vertices, close to the 6,572 of
    /// the thesis's mesh.
    fn default() -> Self {
        SkinOptions {
            around: 88,
            side_rings: 66,
            cap_rings: 4,
            bone_clearance: BONE_CLEARANCE,
        }
    }
}

/// A point the skin must enclose with at least `clearance` metres of radial room.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Clearance {
    /// The interior point (a bone sample).
    pub point: Point3<f64>,
    /// Required radial distance [m] from the trunk axis beyond the point.
    pub clearance: f64,
}

/// Landmark heights of a generated skin (metres above the floor).
#[derive(Clone, Debug, PartialEq)]
pub struct SkinLandmarks {
    /// Jugular notch; the marker grid's top row lies just below (the clavicle line).
    pub suprasternale_height: f64,
    /// Nipple (bust) level.
    pub chest_height: f64,
    /// Lowest point of the tenth rib.
    pub tenth_rib_height: f64,
    /// Umbilicus; the marker grid ends below it.
    pub omphalion_height: f64,
    /// Bottom cap (hips).
    pub bottom_height: f64,
    /// Top cap (neck).
    pub top_height: f64,
    /// x of the vertical axis the rings are built around (z = 0).
    pub axis_x: f64,
    /// The subject's stature [m], for offsets that scale with body size.
    pub stature: f64,
}

/// A closed, consistently oriented (outward normals) triangle surface of the trunk.
#[derive(Clone, Debug, PartialEq)]
pub struct Skin {
    /// Vertex positions [m]. Order: bottom pole, bottom cap rings, side rings (caudal to
    /// cranial), top cap rings, top pole; each ring has [`Skin::around`] vertices starting at
    /// the anterior midline and turning towards the subject's right.
    pub vertices: Vec<Point3<f64>>,
    /// Triangles (counter-clockwise seen from outside).
    pub triangles: Vec<[u32; 3]>,
    /// Vertices per ring.
    pub around: usize,
    /// Landmarks used for the marker grid.
    pub landmarks: SkinLandmarks,
    /// The ANSUR II dimensions the skin was built from.
    pub dimensions: TorsoDimensions,
}

/// Minimum and mean distance from bone points to the skin.
#[derive(Clone, Debug, PartialEq)]
pub struct GapReport {
    /// Points examined.
    pub count: usize,
    /// Points lying outside the skin (should be 0).
    pub outside: usize,
    /// Smallest distance to the skin [m] over the inside points.
    pub min: f64,
    /// Mean distance [m].
    pub mean: f64,
    /// Largest distance [m].
    pub max: f64,
}

/// The female breast added to the chest section: a radial bump centred on the bust point.
#[derive(Clone, Copy, Debug)]
struct Breast {
    amplitude: f64,
    theta: f64,
    height: f64,
    sigma_theta: f64,
    sigma_up: f64,
    sigma_down: f64,
}

impl Breast {
    fn bump(&self, theta: f64, y: f64) -> f64 {
        if self.amplitude <= 0.0 {
            return 0.0;
        }
        // Angle wrapped to (-pi, pi]; the two breasts mirror each other in z.
        let t = (theta + std::f64::consts::PI).rem_euclid(TAU) - std::f64::consts::PI;
        let dt = (t.abs() - self.theta) / self.sigma_theta;
        let sy = if y >= self.height {
            self.sigma_up
        } else {
            self.sigma_down
        };
        let dy = (y - self.height) / sy;
        self.amplitude * (-0.5 * (dt * dt + dy * dy)).exp()
    }
}

/// A measured level of the trunk: its height, section, and the offset of its back behind
/// the spine.
#[derive(Clone, Copy, Debug)]
struct Level {
    y: f64,
    section: Section,
    d_post: f64,
}

/// The trunk shape before triangulation: sections as smooth functions of height.
struct TrunkShape {
    levels: Vec<Level>,
    spine_x: Pchip,
    params: [Pchip; 6],
    breast: Breast,
}

impl TrunkShape {
    fn section(&self, y: f64) -> Section {
        let p = |k: usize| self.params[k].eval(y);
        Section {
            x_back: self.spine_x.eval(y) - p(5),
            depth: p(0),
            half_breadth: p(1),
            post_frac: p(2),
            n_front: p(3),
            n_back: p(4),
        }
    }

    fn radius(&self, axis_x: f64, theta: f64, y: f64) -> f64 {
        self.section(y).radius(axis_x, theta) + self.breast.bump(theta, y)
    }
}

/// Tape-measure circumference of a section with the breast bump at height y.
fn circumference(section: &Section, breast: &Breast, y: f64) -> f64 {
    let axis = section.x_back + section.depth * section.post_frac;
    let pts: Vec<Point2<f64>> = (0..360)
        .map(|i| {
            let t = i as f64 / 360.0 * TAU;
            let r = section.radius(axis, t) + breast.bump(t, y);
            Point2::new(axis + r * t.cos(), r * t.sin())
        })
        .collect();
    profile::hull_perimeter(&pts)
}

/// Solves `f(v) = target` for v in [lo, hi] by bisection, f increasing.
fn solve_increasing(
    mut lo: f64,
    mut hi: f64,
    target: f64,
    name: &str,
    f: impl Fn(f64) -> f64,
) -> Result<f64> {
    if !(f(lo) <= target && f(hi) >= target) {
        return Err(Error::State(format!(
            "skin generation: the ANSUR II {name} ({target:.3} m) cannot be matched by a trunk section"
        )));
    }
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if f(mid) < target {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Ok(0.5 * (lo + hi))
}

impl TrunkShape {
    /// The measured levels of the trunk (hips, waist, chest, shoulders, neck base, neck top).
    fn new(subject: &Subject, dims: &TorsoDimensions) -> Result<Self> {
        let s = subject.stature / REFERENCE_STATURE;
        let spine_x = Pchip::new(
            SPINE_CENTRES_MM.iter().map(|c| c.1 * s * 1e-3).collect(),
            SPINE_CENTRES_MM.iter().map(|c| c.0 * s * 1e-3).collect(),
        );
        let bs = if subject.sex == Sex::Female {
            subject.breast_size
        } else {
            0.0
        };
        let mut breast = Breast {
            amplitude: 0.06 * s * bs,
            theta: 0.0,
            height: dims.chest_height - 0.01 * s,
            sigma_theta: 0.3,
            sigma_up: 0.07 * s,
            sigma_down: 0.04 * s,
        };
        let no_breast = Breast {
            amplitude: 0.0,
            ..breast
        };
        let sec = |depth, half_breadth, post_frac, n_front, n_back, x_back| Section {
            x_back,
            depth,
            half_breadth,
            post_frac,
            n_front,
            n_back,
        };

        // Hips: breadth from ANSUR, depth fitted to the buttock circumference.
        let y_hip = dims.iliocristale_height - 0.16 * s;
        let d_hip = 0.115 * s;
        let xb = spine_x.eval(y_hip) - d_hip;
        let hb = 0.5 * dims.hip_breadth;
        let hip_depth = solve_increasing(
            0.08,
            0.8,
            dims.buttock_circumference,
            "buttock circumference",
            |d| circumference(&sec(d, hb, 0.52, 2.2, 2.4, xb), &no_breast, y_hip),
        )?;
        let hip = Level {
            y: y_hip,
            section: sec(hip_depth, hb, 0.52, 2.2, 2.4, xb),
            d_post: d_hip,
        };

        // Waist (omphalion): depth from ANSUR, breadth fitted to the circumference.
        let y_w = dims.omphalion_height;
        let d_w = 0.085 * s;
        let xb = spine_x.eval(y_w) - d_w;
        let wd = dims.waist_depth;
        let wb = solve_increasing(
            0.05,
            0.6,
            dims.waist_circumference,
            "waist circumference",
            |b| circumference(&sec(wd, b, 0.47, 2.2, 2.6, xb), &no_breast, y_w),
        )?;
        let waist = Level {
            y: y_w,
            section: sec(wd, wb, 0.47, 2.2, 2.6, xb),
            d_post: d_w,
        };

        // Chest (bust level): depth from ANSUR less the bust, breadth fitted to the tape
        // circumference (which bridges the breasts).
        let y_c = dims.chest_height;
        let d_c = 0.072 * s;
        let xb = spine_x.eval(y_c) - d_c;
        let cd = dims.chest_depth - 0.8 * breast.amplitude;
        // Bust points about 95 mm lateral and 110 mm in front of the trunk axis.
        breast.theta = (0.095f64).atan2(0.110);
        let cb = solve_increasing(
            0.05,
            0.6,
            dims.chest_circumference,
            "chest circumference",
            |b| circumference(&sec(cd, b, 0.5, 2.3, 2.8, xb), &breast, y_c),
        )?;
        let chest = Level {
            y: y_c,
            section: sec(cd, cb, 0.5, 2.3, 2.8, xb),
            d_post: d_c,
        };

        // Shoulders, just below the acromia: biacromial breadth plus the deltoid's cover.
        let y_s = dims.acromial_height - 0.02 * s;
        let d_s = 0.085 * s;
        let xb = spine_x.eval(y_s) - d_s;
        let shoulder = Level {
            y: y_s,
            section: sec(
                0.78 * dims.chest_depth,
                0.5 * dims.biacromial_breadth + 0.012 * s,
                0.5,
                2.6,
                2.8,
                xb,
            ),
            d_post: d_s,
        };

        // Neck base and top: a circle of the neck base circumference, the cervical spine in
        // its posterior third.
        let r_n = dims.neck_base_circumference / TAU;
        let neck = |y: f64| {
            let xb = spine_x.eval(y) + 0.024 * s - r_n;
            Level {
                y,
                section: sec(2.0 * r_n, r_n, 0.5, 2.0, 2.0, xb),
                d_post: r_n - 0.024 * s,
            }
        };
        let levels = vec![
            hip,
            waist,
            chest,
            shoulder,
            neck(dims.cervicale_height - 0.01 * s),
            neck(dims.cervicale_height + 0.03 * s),
        ];
        for w in levels.windows(2) {
            if w[1].y - w[0].y < 0.02 {
                return Err(Error::invalid(
                    "subject",
                    format!("{subject:?}"),
                    "a subject whose predicted trunk landmarks (hips, waist, chest, shoulders, neck) are at least 2 cm apart in height",
                ));
            }
        }
        let ys: Vec<f64> = levels.iter().map(|l| l.y).collect();
        let col =
            |f: &dyn Fn(&Level) -> f64| Pchip::new(ys.clone(), levels.iter().map(f).collect());
        let params = [
            col(&|l| l.section.depth),
            col(&|l| l.section.half_breadth),
            col(&|l| l.section.post_frac),
            col(&|l| l.section.n_front),
            col(&|l| l.section.n_back),
            col(&|l| l.d_post),
        ];
        Ok(TrunkShape {
            levels,
            spine_x,
            params,
            breast,
        })
    }
}

/// Radius of the (ring, angle) grid at height `y` and angle `theta`, bilinear between the
/// four surrounding grid values (the surface between rings is planar, so this is exact
/// along the rings' chords to within their sag).
fn radius_at(r: &[Vec<f64>], heights: &[f64], y: f64, theta: f64) -> f64 {
    let (nk, nj) = (r.len(), r[0].len());
    let k = heights.partition_point(|&h| h <= y).clamp(1, nk - 1) - 1;
    let fy = ((y - heights[k]) / (heights[k + 1] - heights[k]).max(1e-12)).clamp(0.0, 1.0);
    let u = theta.rem_euclid(TAU) / TAU * nj as f64;
    let j0 = (u.floor() as usize) % nj;
    let j1 = (j0 + 1) % nj;
    let fj = u - u.floor();
    let row = |k: usize| r[k][j0] * (1.0 - fj) + r[k][j1] * fj;
    row(k) * (1.0 - fy) + row(k + 1) * fy
}

/// Raises the radius grid so every clearance point is enclosed with its radial room. Each
/// point short of room lifts the surface by a smooth compact bump centred on it,
/// `need (1 - (d / R)^2)^3` for surface distance d < R (a Wendland-type C2 profile), and the
/// lift of a grid vertex is the largest bump reaching it, so a ridge of bone (the sternum)
/// widens the trunk by a gently rounded mound instead of a step. The lift field is then
/// blurred (two passes of a 5 x 5 box on the grid) so that neighbouring bumps of unequal
/// height merge without scallops; the blur lowers peaks, so passes repeat on the residual
/// deficits, the last ones unblurred so that every point ends with its room.
#[allow(clippy::needless_range_loop)] // (ring, angle) grid indexing reads clearer
fn enclose(r: &mut [Vec<f64>], heights: &[f64], axis_x: f64, points: &[Clearance], reach: f64) {
    let (nk, nj) = (r.len(), r[0].len());
    let blur = |f: &Vec<Vec<f64>>, w: usize| -> Vec<Vec<f64>> {
        let mut g = vec![vec![0.0; nj]; nk];
        for k in 0..nk {
            for j in 0..nj {
                let (mut sum, mut n) = (0.0, 0usize);
                for kk in k.saturating_sub(w)..=(k + w).min(nk - 1) {
                    for dj in 0..=2 * w {
                        sum += f[kk][(j + nj + dj - w) % nj];
                        n += 1;
                    }
                }
                g[k][j] = sum / n as f64;
            }
        }
        g
    };
    const PASSES: usize = 8;
    for pass in 0..PASSES {
        let mut lift = vec![vec![0.0f64; nj]; nk];
        let mut any = false;
        for c in points {
            let (dx, dz) = (c.point.x - axis_x, c.point.z);
            let rho = dx.hypot(dz);
            let theta = dz.atan2(dx).rem_euclid(TAU);
            let y = c.point.y;
            if y < heights[0] || y > heights[nk - 1] {
                continue;
            }
            // Aim a little beyond the room needed so that the passes converge from above.
            let need = rho + c.clearance - radius_at(r, heights, y, theta);
            if need <= 0.0 {
                continue;
            }
            let need = need + 1e-4;
            any = true;
            let r0 = rho.max(1e-3);
            let k_lo = heights.partition_point(|&h| h < y - reach);
            let k_hi = heights.partition_point(|&h| h <= y + reach);
            let dj = ((reach / r0) / TAU * nj as f64).ceil() as isize + 1;
            let jc = (theta / TAU * nj as f64).round() as isize;
            for k in k_lo..k_hi.min(nk) {
                let ddy = heights[k] - y;
                for o in -dj..=dj {
                    let j = (jc + o).rem_euclid(nj as isize) as usize;
                    let mut dt = TAU * j as f64 / nj as f64 - theta;
                    dt = (dt + std::f64::consts::PI).rem_euclid(TAU) - std::f64::consts::PI;
                    let d2 = (ddy * ddy + (r0 * dt).powi(2)) / (reach * reach);
                    if d2 < 1.0 {
                        let b = need * (1.0 - d2).powi(3);
                        if b > lift[k][j] {
                            lift[k][j] = b;
                        }
                    }
                }
            }
        }
        if !any {
            break;
        }
        if pass + 2 < PASSES {
            lift = blur(&blur(&lift, 2), 2);
        }
        for k in 0..nk {
            for j in 0..nj {
                r[k][j] += lift[k][j];
            }
        }
    }
}

impl Skin {
    /// Generates the default-resolution skin of `subject` around its anatomy's bones and
    /// abdominal wall (the anatomy is built at level of detail 0; the bones do not depend on
    /// the level of detail).
    pub fn generate(subject: &Subject) -> Result<Skin> {
        let anatomy = Anatomy::build(subject, 0)?;
        Skin::for_anatomy(&anatomy, &SkinOptions::default())
    }

    /// Generates the skin of `anatomy`'s subject enclosing its bones with
    /// [`SkinOptions::bone_clearance`] and its free abdominal wall with [`WALL_CLEARANCE`] of
    /// radial room ([`anatomy_clearance`]). When the anatomy was built on a prepared subject
    /// directory, the generated skin is then re-sampled onto the subject's `skin.obj` along
    /// rays from its axis (see [`crate::anatomy::prepared`]): the rings, their heights on the
    /// side and the landmarks stay, the shape becomes the subject's.
    pub fn for_anatomy(anatomy: &Anatomy, options: &SkinOptions) -> Result<Skin> {
        let clear = anatomy_clearance(anatomy, options.bone_clearance);
        let mut skin = Skin::generate_with(&anatomy.subject, options, &clear)?;
        if let Some(mesh) = &anatomy.subject_mesh {
            let lm = &skin.landmarks;
            let (axis_x, ends) = (lm.axis_x, (lm.bottom_height, lm.top_height));
            crate::anatomy::prepared::fit_skin(
                &mut skin.vertices,
                &skin.triangles,
                axis_x,
                ends,
                mesh,
            )?;
        }
        Ok(skin)
    }

    /// Generates a skin from the subject's ANSUR II dimensions at the given resolution, then
    /// widens it smoothly wherever a point of `enclosed` would lie closer than its clearance
    /// (pass the subject's own bone samples once the anatomy provides them).
    ///
    /// Construction: horizontal rings on one vertical axis inside every section, at heights
    /// spaced evenly along the trunk's profile; each ring is star-shaped about the axis and
    /// vertex j of every ring lies at the same angle, so the band between two rings splits
    /// into wedge-and-slab cells that meet only along shared edges: the side surface has no
    /// self-intersections by construction; the caps are flat, nested scaled copies of the end
    /// rings.
    pub fn generate_with(
        subject: &Subject,
        options: &SkinOptions,
        enclosed: &[Clearance],
    ) -> Result<Skin> {
        if options.around < 16 {
            return Err(Error::invalid("skin.around", options.around, "16 or more"));
        }
        if options.side_rings < 8 {
            return Err(Error::invalid(
                "skin.side_rings",
                options.side_rings,
                "8 or more",
            ));
        }
        if options.cap_rings < 1 {
            return Err(Error::invalid(
                "skin.cap_rings",
                options.cap_rings,
                "1 or more",
            ));
        }
        if !(options.bone_clearance.is_finite() && (0.0..=0.1).contains(&options.bone_clearance)) {
            return Err(Error::invalid(
                "skin.bone_clearance",
                options.bone_clearance,
                "[0, 0.1] m",
            ));
        }
        let dims = TorsoDimensions::from_subject(subject)?;
        let shape = TrunkShape::new(subject, &dims)?;
        let (y0, y1) = (shape.levels[0].y, shape.levels[shape.levels.len() - 1].y);

        // Ring heights evenly spaced along the arc length of the lateral and frontal profiles.
        let fine = 2000;
        let mut arc = vec![0.0; fine + 1];
        let prof = |y: f64| {
            let s = shape.section(y);
            (s.half_breadth, s.x_front(), s.x_back)
        };
        let mut prev = prof(y0);
        for i in 1..=fine {
            let y = y0 + (y1 - y0) * i as f64 / fine as f64;
            let cur = prof(y);
            let dy = (y1 - y0) / fine as f64;
            let d = (dy * dy
                + (cur.0 - prev.0).powi(2)
                + 0.5 * (cur.1 - prev.1).powi(2)
                + 0.5 * (cur.2 - prev.2).powi(2))
            .sqrt();
            arc[i] = arc[i - 1] + d;
            prev = cur;
        }
        let heights: Vec<f64> = (0..options.side_rings)
            .map(|k| {
                let target = arc[fine] * k as f64 / (options.side_rings - 1) as f64;
                let i = arc.partition_point(|&a| a < target).clamp(1, fine);
                let f = (target - arc[i - 1]) / (arc[i] - arc[i - 1]).max(1e-300);
                y0 + (y1 - y0) * ((i - 1) as f64 + f.clamp(0.0, 1.0)) / fine as f64
            })
            .collect();

        // One vertical axis inside every section.
        let sections: Vec<Section> = heights.iter().map(|&y| shape.section(y)).collect();
        let back = sections.iter().map(|s| s.x_back).fold(f64::MIN, f64::max);
        let front = sections
            .iter()
            .map(|s| s.x_front())
            .fold(f64::MAX, f64::min);
        if back >= front {
            return Err(Error::State(
                "skin generation: no vertical axis lies inside every trunk section".into(),
            ));
        }
        let axis_x = 0.5 * (back + front);

        let n = options.around;
        let thetas: Vec<f64> = (0..n).map(|j| TAU * j as f64 / n as f64).collect();
        let mut radii: Vec<Vec<f64>> = heights
            .iter()
            .map(|&y| thetas.iter().map(|&t| shape.radius(axis_x, t, y)).collect())
            .collect();
        enclose(
            &mut radii,
            &heights,
            axis_x,
            enclosed,
            ENCLOSE_REACH * subject.stature / REFERENCE_STATURE,
        );

        let ring = |y: f64, r: &[f64], scale: f64| -> Vec<Point3<f64>> {
            thetas
                .iter()
                .zip(r)
                .map(|(t, &r)| Point3::new(axis_x + scale * r * t.cos(), y, scale * r * t.sin()))
                .collect()
        };
        let nc = options.cap_rings;
        let mut rings: Vec<Vec<Point3<f64>>> = Vec::new();
        for c in 1..=nc {
            rings.push(ring(y0, &radii[0], c as f64 / (nc + 1) as f64));
        }
        for (k, &y) in heights.iter().enumerate() {
            rings.push(ring(y, &radii[k], 1.0));
        }
        let last = heights.len() - 1;
        for c in (1..=nc).rev() {
            rings.push(ring(y1, &radii[last], c as f64 / (nc + 1) as f64));
        }
        let mut vertices = vec![Point3::new(axis_x, y0, 0.0)];
        for r in &rings {
            vertices.extend_from_slice(r);
        }
        vertices.push(Point3::new(axis_x, y1, 0.0));

        let idx = |ring: usize, j: usize| (1 + ring * n + (j % n)) as u32;
        let mut triangles = Vec::with_capacity(2 * n * rings.len());
        for j in 0..n {
            triangles.push([0, idx(0, j), idx(0, j + 1)]);
        }
        for k in 0..rings.len() - 1 {
            for j in 0..n {
                triangles.push([idx(k, j), idx(k + 1, j), idx(k, j + 1)]);
                triangles.push([idx(k, j + 1), idx(k + 1, j), idx(k + 1, j + 1)]);
            }
        }
        let top = (vertices.len() - 1) as u32;
        let lr = rings.len() - 1;
        for j in 0..n {
            triangles.push([idx(lr, j), top, idx(lr, j + 1)]);
        }

        let landmarks = SkinLandmarks {
            suprasternale_height: dims.suprasternale_height,
            chest_height: dims.chest_height,
            tenth_rib_height: dims.tenth_rib_height,
            omphalion_height: dims.omphalion_height,
            bottom_height: y0,
            top_height: y1,
            axis_x,
            stature: subject.stature,
        };
        Ok(Skin {
            vertices,
            triangles,
            around: n,
            landmarks,
            dimensions: dims,
        })
    }

    /// Checks the surface is closed, oriented and manifold, and free of self-intersections.
    pub fn check(&self) -> Result<()> {
        geometry::check_closed_manifold(self.vertices.len(), &self.triangles)
            .map_err(|e| Error::State(format!("skin is not a closed manifold: {e}")))?;
        let hits = geometry::self_intersections(&self.vertices, &self.triangles);
        if let Some((a, b)) = hits.first() {
            return Err(Error::State(format!(
                "skin self-intersects: triangles {a} and {b} ({} pairs)",
                hits.len()
            )));
        }
        Ok(())
    }

    /// Enclosed volume [m^3] (divergence theorem over the outward-oriented triangles).
    pub fn volume(&self) -> f64 {
        self.triangles
            .iter()
            .map(|t| {
                let (a, b, c) = (
                    &self.vertices[t[0] as usize],
                    &self.vertices[t[1] as usize],
                    &self.vertices[t[2] as usize],
                );
                a.coords.dot(&b.coords.cross(&c.coords)) / 6.0
            })
            .sum()
    }

    /// Distances from `points` (bone samples) to the skin: minimum, mean and maximum over
    /// the points inside, and how many lie outside.
    pub fn gap_report(&self, points: &[Point3<f64>]) -> GapReport {
        let (mut min, mut max, mut sum, mut outside, mut inside) =
            (f64::MAX, 0.0f64, 0.0, 0usize, 0usize);
        for p in points {
            if !geometry::is_inside(p, &self.vertices, &self.triangles) {
                outside += 1;
                continue;
            }
            let d = geometry::distance_to_surface(p, &self.vertices, &self.triangles);
            min = min.min(d);
            max = max.max(d);
            sum += d;
            inside += 1;
        }
        GapReport {
            count: points.len(),
            outside,
            min: if inside > 0 { min } else { f64::NAN },
            mean: if inside > 0 {
                sum / inside as f64
            } else {
                f64::NAN
            },
            max,
        }
    }

    /// Tape-measure circumference [m] of the skin's horizontal section at height `y`
    /// (convex hull perimeter of the ring nearest to `y`).
    pub fn circumference_at(&self, y: f64) -> f64 {
        let ring = self.ring_near(y);
        let pts: Vec<Point2<f64>> = ring.iter().map(|p| Point2::new(p.x, p.z)).collect();
        profile::hull_perimeter(&pts)
    }

    /// The side ring (full-size, not a cap ring) whose height is nearest `y`.
    pub fn ring_near(&self, y: f64) -> &[Point3<f64>] {
        let n = self.around;
        let rings = (self.vertices.len() - 2) / n;
        let mut best = (f64::MAX, 0);
        for k in 0..rings {
            let v = &self.vertices[1 + k * n];
            let is_cap = (v.y - self.landmarks.bottom_height).abs() < 1e-12
                || (v.y - self.landmarks.top_height).abs() < 1e-12;
            // Cap rings share the end heights; keep the widest ring at an end height.
            let d = (v.y - y).abs();
            if d < best.0 - 1e-12
                || (is_cap
                    && (d - best.0).abs() <= 1e-12
                    && self.vertices[1 + k * n].x > self.vertices[1 + best.1 * n].x)
            {
                best = (d, k);
            }
        }
        &self.vertices[1 + best.1 * n..1 + (best.1 + 1) * n]
    }
}
