//! A subject's own surfaces in place of the generated ones: a directory written by
//! `torso mesh prepare` (Peeters & Pronost 2013, figure 1) holding `skin.obj` and, optionally,
//! `abdomen.obj`, loaded and checked by [`SubjectMesh::load`].
//!
//! The model keeps its own surface layouts (the cavity's subdivided sphere with its vertex
//! roles and diaphragm meridians, the skin's rings under the marker grid) and re-samples the
//! subject's surfaces with them, as a template is fitted to a scan:
//!
//! - each vertex g of the generated cavity moves along the ray from the cavity's centre c
//!   through g to where that ray crosses the subject's cavity surface (the crossing nearest
//!   g when there are several), so the layout keeps its topology, roles and left-right
//!   pairing while its shape becomes the subject's;
//! - the diaphragm's insertions are then found by geometry (paper section 3.8): the costal
//!   margin carried by ribs 7-12, the sternum (xiphoid) and the spine (crura) becomes one
//!   [`Attachment`] per carrier, the union of balls of radius [`INSERTION_REACH`] around the
//!   margin between its vertices; each rim vertex of the fitted cavity is carried by the body
//!   whose area contains it (the nearest when several do), and a cavity that does not reach
//!   the margin is refused;
//! - the skin's vertices move along rays from the trunk axis (horizontal on the side, tilted
//!   toward the ends) to the subject's skin.
//!
//! Muscle paths are laid out afterwards on the fitted cavity (`layout`), so the abdominal
//! muscles follow the subject's wall and the diaphragm's fibres its dome.

use super::abdomen::{Abdomen, Margin, VertexRole};
use super::{Anchor, Body};
use crate::mesh::{Attachment, Bvh, TriMesh, pipeline};
use crate::{Error, Result};
use nalgebra::{Point3, Vector3};
use std::path::{Path, PathBuf};

/// Distance [m] within which the subject's cavity surface counts as reaching the costal
/// margin: about the width of the diaphragm's costal insertion band on the inner face of the
/// lower ribs and cartilages (2-3 cm), so that a cavity segmented a little inside or outside
/// the rib centrelines still finds its insertions.
/// Numerical: a matching tolerance for a segmented cavity, not a property of the body.
pub const INSERTION_REACH: f64 = 0.03;

/// Largest and smallest plausible extent of a trunk skin [m]: outside it the file is almost
/// certainly in other units (millimetres) or not a trunk.
/// Numerical: an input check.
const SKIN_EXTENT: (f64, f64) = (0.2, 3.0);

/// Search window [m] along a projection ray on either side of the template vertex, before
/// falling back to a search over the whole surface.
/// Numerical: a search window.
const RAY_WINDOW: f64 = 0.1;

/// Distance [m] the skin's projection centres stay inside its ends.
/// Numerical: a projection setting.
const SKIN_END_INSET: f64 = 0.1;

/// The name users see for the directory (the FMI parameter).
const PARAMETER: &str = "subject.mesh_dir";

/// A prepared subject directory: the skin and, when present, the abdominal cavity, closed
/// and outward-oriented, in metres in the model frame (x anterior, y superior, z right).
#[derive(Clone, Debug, PartialEq)]
pub struct SubjectMesh {
    /// The directory it was read from.
    pub dir: PathBuf,
    /// `skin.obj`.
    pub skin: TriMesh,
    /// `abdomen.obj`, if the directory has one.
    pub abdomen: Option<TriMesh>,
}

/// How the generated cavity was fitted to the subject's (figures for reports and tests).
#[derive(Clone, Debug, PartialEq)]
pub struct CavityFit {
    /// Volume of the subject's cavity surface [m^3].
    pub surface_volume: f64,
    /// Volume of the generated cavity [m^3].
    pub generated_volume: f64,
    /// Volume of the fitted cavity [m^3] (the model's rest volume of the abdomen).
    pub fitted_volume: f64,
    /// Vertices of the subject's cavity surface inside the insertion areas.
    pub surface_insertion_vertices: usize,
    /// Largest distance [m] of a fitted rim vertex from the costal margin.
    pub rim_distance_max: f64,
    /// Largest distance [m] a template vertex moved.
    pub moved_max: f64,
    /// Rim vertices whose carrier differs from the generated cavity's.
    pub carriers_changed: usize,
}

/// Checks cheaply that `dir` looks like a prepared directory (a directory holding
/// `skin.obj`); [`SubjectMesh::load`] reads and checks the surfaces.
pub fn check_dir(dir: &Path) -> Result<()> {
    if !dir.is_dir() {
        return Err(Error::invalid(
            PARAMETER,
            dir.display(),
            "an existing directory written by `torso mesh prepare` (empty: generated geometry)",
        ));
    }
    let skin = dir.join("skin.obj");
    if !skin.is_file() {
        return Err(Error::invalid(
            PARAMETER,
            dir.display(),
            format!(
                "a directory written by `torso mesh prepare`: {} is missing",
                skin.display()
            ),
        ));
    }
    Ok(())
}

impl SubjectMesh {
    /// Reads `skin.obj` and the optional `abdomen.obj` of `dir` and checks that each is a
    /// closed, consistently oriented surface of trunk size in metres, turned outward (an
    /// inward-oriented surface is flipped), and that the cavity lies inside the skin.
    pub fn load(dir: impl AsRef<Path>) -> Result<SubjectMesh> {
        let dir = dir.as_ref();
        check_dir(dir)?;
        let prepared = pipeline::read_prepared(dir)?;
        let mut skin = prepared.skin;
        check_surface(&dir.join("skin.obj"), &mut skin)?;
        let extent = skin.bounding_box().extent().max();
        if !(SKIN_EXTENT.0..=SKIN_EXTENT.1).contains(&extent) {
            return Err(Error::invalid(
                dir.join("skin.obj").display().to_string(),
                format!("a surface {extent:.3} units across"),
                format!(
                    "a trunk {}-{} m across, in metres (convert millimetres before preparing)",
                    SKIN_EXTENT.0, SKIN_EXTENT.1
                ),
            ));
        }
        let mut abdomen = prepared.abdomen;
        if let Some(a) = abdomen.as_mut() {
            let path = dir.join("abdomen.obj");
            check_surface(&path, a)?;
            let outside = outside_skin(a.vertices.iter(), &skin);
            if let Some(p) = outside.first() {
                return Err(Error::invalid(
                    path.display().to_string(),
                    format!(
                        "{} of {} vertices outside skin.obj, e.g. ({:.4}, {:.4}, {:.4})",
                        outside.len(),
                        a.vertices.len(),
                        p.x,
                        p.y,
                        p.z
                    ),
                    "a cavity inside the skin wherever the skin reaches (run `torso mesh prepare` with both surfaces)",
                ));
            }
        }
        Ok(SubjectMesh {
            dir: dir.to_path_buf(),
            skin,
            abdomen,
        })
    }
}

/// The points lying outside `skin` at heights it covers: below its lowest point (a trunk
/// scan cut at the hips, as the generated skin is) the pelvic part of the cavity is not
/// compared.
fn outside_skin<'a>(
    points: impl Iterator<Item = &'a Point3<f64>>,
    skin: &TriMesh,
) -> Vec<Point3<f64>> {
    let bottom = skin.bounding_box().min.y;
    let bvh = Bvh::new(skin);
    points
        .filter(|p| p.y >= bottom && !bvh.contains(p))
        .copied()
        .collect()
}

/// Checks that `mesh` (read from `path`) is non-empty, closed and consistently oriented, and
/// turns it outward.
fn check_surface(path: &Path, mesh: &mut TriMesh) -> Result<()> {
    let allowed = "a closed, consistently oriented triangle surface (run `torso mesh prepare`)";
    if mesh.triangles.is_empty() {
        return Err(Error::invalid(
            path.display().to_string(),
            "no triangle",
            allowed,
        ));
    }
    let topo = mesh.topology();
    if !topo.is_closed() || !topo.is_edge_manifold() {
        return Err(Error::invalid(
            path.display().to_string(),
            format!(
                "an open surface ({} boundary edges, {} non-manifold edges)",
                topo.boundary_edges, topo.non_manifold_edges
            ),
            allowed,
        ));
    }
    if !topo.is_consistently_oriented() {
        return Err(Error::invalid(
            path.display().to_string(),
            "triangles with inconsistent orientation",
            allowed,
        ));
    }
    if mesh.volume() < 0.0 {
        mesh.flip_orientation();
    }
    Ok(())
}

/// Surface crossings of rays, searched first in a window around the expected distance.
struct RayCaster<'a> {
    mesh: &'a TriMesh,
    bvh: Bvh,
}

impl<'a> RayCaster<'a> {
    fn new(mesh: &'a TriMesh) -> Self {
        RayCaster {
            mesh,
            bvh: Bvh::new(mesh),
        }
    }

    /// The crossing of the ray `o + t d` (unit `d`, t > 0) with the surface nearest to
    /// `t = expected`.
    fn nearest_crossing(&self, o: &Point3<f64>, d: &Vector3<f64>, expected: f64) -> Option<f64> {
        let test = |t: u32, best: &mut Option<f64>| {
            let [a, b, c] = self.mesh.corners(t as usize);
            if let Some(s) = crate::mesh::geom::ray_triangle_closed(o, d, &a, &b, &c, 1e-9)
                && s > 0.0
                && best.is_none_or(|b| (s - expected).abs() < (b - expected).abs())
            {
                *best = Some(s);
            }
        };
        let mut best = None;
        let lo = o + d * (expected - RAY_WINDOW).max(0.0);
        let hi = o + d * (expected + RAY_WINDOW);
        let mut window = crate::mesh::Aabb::empty();
        window.grow(&lo);
        window.grow(&hi);
        self.bvh.for_each_in_box(&window, |t| test(t, &mut best));
        if best.is_none() {
            for t in 0..self.mesh.triangles.len() as u32 {
                test(t, &mut best);
            }
        }
        best
    }
}

/// Moves every point of `points` along the ray from `centre(p)` through it to the surface.
/// Errors name the first point whose ray misses.
fn project(
    points: &mut [Point3<f64>],
    surface: &TriMesh,
    centre: impl Fn(&Point3<f64>) -> Point3<f64>,
    what: &str,
    file: &Path,
) -> Result<f64> {
    let caster = RayCaster::new(surface);
    let mut moved: f64 = 0.0;
    for p in points.iter_mut() {
        let c = centre(p);
        let v = *p - c;
        let Some(d) = v.try_normalize(1e-12) else {
            continue;
        };
        let Some(t) = caster.nearest_crossing(&c, &d, v.norm()) else {
            return Err(Error::invalid(
                file.display().to_string(),
                format!(
                    "no surface in the direction ({:.3}, {:.3}, {:.3}) from ({:.4}, {:.4}, {:.4})",
                    d.x, d.y, d.z, c.x, c.y, c.z
                ),
                format!("a closed {what} surrounding the model's {what}"),
            ));
        };
        let q = c + d * t;
        moved = moved.max((q - *p).norm());
        *p = q;
    }
    Ok(moved)
}

/// Refuses a fitted layout with a triangle turned over relative to the template (the
/// subject's surface is not star-shaped enough about the projection centres).
fn check_folds(
    template: &[Point3<f64>],
    fitted: &[Point3<f64>],
    triangles: &[[u32; 3]],
    what: &str,
    file: &Path,
) -> Result<()> {
    let normal = |p: &[Point3<f64>], t: &[u32; 3]| {
        let [a, b, c] = t.map(|v| p[v as usize]);
        (b - a).cross(&(c - a))
    };
    let folded: Vec<&[u32; 3]> = triangles
        .iter()
        .filter(|t| normal(template, t).dot(&normal(fitted, t)) <= 0.0)
        .collect();
    if let Some(t) = folded.first() {
        let p = fitted[t[0] as usize];
        return Err(Error::invalid(
            file.display().to_string(),
            format!(
                "a {what} the model's layout folds on ({} triangles, first near ({:.4}, {:.4}, {:.4}))",
                folded.len(),
                p.x,
                p.y,
                p.z
            ),
            format!("a {what} shaped like the generated one (star-shaped about its centre)"),
        ));
    }
    Ok(())
}

/// A piece of the costal margin: a straight segment between two points.
type Segment = (Point3<f64>, Point3<f64>);

/// The insertion area of one carrier: the halves of the costal-margin segments nearer to
/// its vertices, and the [`Attachment`] covering them (balls of [`INSERTION_REACH`] around
/// samples every 5 mm).
struct InsertionArea {
    body: Body,
    halves: Vec<Segment>,
    area: Attachment,
}

impl InsertionArea {
    /// Distance from `p` to the carrier's part of the margin.
    fn distance(&self, p: &Point3<f64>) -> f64 {
        self.halves
            .iter()
            .map(|(a, b)| {
                let ab = b - a;
                let t = ((p - a).dot(&ab) / ab.norm_squared().max(1e-300)).clamp(0.0, 1.0);
                (a + ab * t - p).norm()
            })
            .fold(f64::INFINITY, f64::min)
    }
}

/// One insertion area per carrier of the costal margin: each margin segment is split at its
/// middle and each half given to the carrier of its end (as the generated cavity does).
fn insertion_areas(margin: &Margin) -> Result<Vec<InsertionArea>> {
    let n = margin.points.len();
    let mut halves: Vec<(Body, Vec<Segment>)> = Vec::new();
    let mut add = |body: Body, a: Point3<f64>, b: Point3<f64>| match halves
        .iter_mut()
        .find(|(bd, _)| *bd == body)
    {
        Some((_, h)) => h.push((a, b)),
        None => halves.push((body, vec![(a, b)])),
    };
    for i in 0..n {
        let j = (i + 1) % n;
        let (a, b) = (margin.points[i], margin.points[j]);
        let mid = a + (b - a) * 0.5;
        add(margin.bodies[i], a, mid);
        add(margin.bodies[j], mid, b);
    }
    halves
        .into_iter()
        .map(|(body, halves)| {
            let mut samples = Vec::new();
            for (a, b) in &halves {
                let steps = ((b - a).norm() / 0.005).ceil().max(1.0) as usize;
                samples.extend((0..=steps).map(|k| a + (b - a) * (k as f64 / steps as f64)));
            }
            let area = Attachment::from_points(
                format!("diaphragm insertion on {}", body_name(body)),
                samples,
                INSERTION_REACH,
            )?;
            Ok(InsertionArea { body, halves, area })
        })
        .collect()
}

/// Readable name of a carrier.
fn body_name(body: Body) -> String {
    match body {
        Body::Ground => "the spine".into(),
        Body::Sternum => "the sternum".into(),
        Body::Rib(i) => {
            let side = if i < 12 { "right" } else { "left" };
            format!("{side} rib {}", i % 12 + 1)
        }
        Body::Vertex(j) => format!("abdominal vertex {j}"),
    }
}

/// Fits the generated cavity `abdomen` (anchors already pushed) to the subject's cavity
/// `surface`, read from `file`: moves its vertices onto the surface, re-derives the carrier of
/// each rim vertex from the insertion areas of `margin`, and updates the rest positions of
/// its anchors and its heights. The lining built on the generated rim keeps its topology.
pub(super) fn fit_cavity(
    abdomen: &mut Abdomen,
    anchors: &mut [Anchor],
    surface: &TriMesh,
    margin: &Margin,
    file: &Path,
) -> Result<CavityFit> {
    let template: Vec<Point3<f64>> = abdomen
        .anchor
        .iter()
        .map(|&a| anchors[a as usize].rest)
        .collect();
    let generated = TriMesh {
        vertices: template.clone(),
        triangles: abdomen.triangles.clone(),
    };
    let centre = generated.centroid();
    if !Bvh::new(surface).contains(&centre) {
        return Err(Error::invalid(
            file.display().to_string(),
            format!(
                "a cavity not enclosing the model's cavity centre ({:.4}, {:.4}, {:.4})",
                centre.x, centre.y, centre.z
            ),
            "a cavity under the rib cage, in metres in the model frame (x anterior, y up, z right)",
        ));
    }
    let mut fitted = template.clone();
    let moved_max = project(&mut fitted, surface, |_| centre, "abdominal cavity", file)?;
    check_folds(&template, &fitted, &abdomen.triangles, "cavity", file)?;
    // Insertions by geometry.
    let areas = insertion_areas(margin)?;
    let surface_insertion_vertices = {
        let mut found = vec![false; surface.vertices.len()];
        for a in &areas {
            for v in a.area.find_vertices(surface) {
                found[v as usize] = true;
            }
        }
        found.iter().filter(|f| **f).count()
    };
    if surface_insertion_vertices == 0 {
        return Err(Error::invalid(
            file.display().to_string(),
            "a cavity with no vertex near the costal margin",
            format!(
                "a cavity whose top reaches the costal margin (ribs 7-12, xiphoid) within {:.0} mm",
                INSERTION_REACH * 1e3
            ),
        ));
    }
    let mut rim_distance_max: f64 = 0.0;
    let mut carriers_changed = 0;
    for &v in &abdomen.rim {
        let q = fitted[v as usize];
        let nearest = |inside: bool| {
            areas
                .iter()
                .filter(|a| !inside || a.area.contains(&q))
                .map(|a| (a.body, a.distance(&q)))
                .min_by(|x, y| x.1.total_cmp(&y.1))
        };
        let Some((body, dist)) = nearest(true) else {
            let (b, d) = nearest(false).unwrap_or((Body::Ground, f64::INFINITY));
            return Err(Error::invalid(
                file.display().to_string(),
                format!(
                    "no diaphragm insertion found: the cavity's rim at ({:.4}, {:.4}, {:.4}) lies {:.0} mm from the costal margin ({})",
                    q.x,
                    q.y,
                    q.z,
                    d * 1e3,
                    body_name(b)
                ),
                format!(
                    "a cavity meeting the costal margin within {:.0} mm all round",
                    INSERTION_REACH * 1e3
                ),
            ));
        };
        rim_distance_max = rim_distance_max.max(dist);
        let anchor = &mut anchors[abdomen.anchor[v as usize] as usize];
        if anchor.body != body {
            carriers_changed += 1;
            anchor.body = body;
        }
    }
    for (v, p) in fitted.iter().enumerate() {
        anchors[abdomen.anchor[v] as usize].rest = *p;
    }
    abdomen.floor_y = fitted.iter().map(|p| p.y).fold(f64::INFINITY, f64::min);
    abdomen.apex_y = abdomen
        .with_role(VertexRole::Dome)
        .map(|v| fitted[v as usize].y)
        .fold(f64::NEG_INFINITY, f64::max);
    // the subject's own cavity is the reference: no smooth dome to correct toward
    abdomen.dome_faceting_volume = 0.0;
    // Its dome edges stand for as much more tissue than their chords as the generated dome's
    // did (the same edges over the same parametric directions): each edge keeps its arc over
    // chord on the fitted chord, so that a fitted cavity's fibres have the tissue lengths of
    // the generated ones to within the fit's change of their chords.
    for (&(a, b), arc) in abdomen.dome_arc.iter_mut() {
        let generated = (template[b as usize] - template[a as usize]).norm();
        let subject = (fitted[b as usize] - fitted[a as usize]).norm();
        if generated > 0.0 {
            *arc *= subject / generated;
        }
    }
    let fitted_mesh = TriMesh {
        vertices: fitted,
        triangles: abdomen.triangles.clone(),
    };
    Ok(CavityFit {
        surface_volume: surface.volume(),
        generated_volume: generated.volume(),
        fitted_volume: fitted_mesh.volume(),
        surface_insertion_vertices,
        rim_distance_max,
        moved_max,
        carriers_changed,
    })
}

/// Checks that the generated cavity (kept when the directory has no `abdomen.obj`) lies
/// inside the subject's skin wherever the skin reaches.
pub(super) fn check_cavity_inside(
    abdomen: &Abdomen,
    anchors: &[Anchor],
    skin: &TriMesh,
    file: &Path,
) -> Result<()> {
    let rest: Vec<Point3<f64>> = abdomen
        .anchor
        .iter()
        .map(|&a| anchors[a as usize].rest)
        .collect();
    let outside = outside_skin(rest.iter(), skin);
    if let Some(p) = outside.first() {
        return Err(Error::invalid(
            file.display().to_string(),
            format!(
                "a skin the generated abdominal cavity pokes out of ({} vertices, e.g. ({:.4}, {:.4}, {:.4}))",
                outside.len(),
                p.x,
                p.y,
                p.z
            ),
            "a skin enclosing the cavity (prepare an abdomen.obj with it, in metres in the model frame)",
        ));
    }
    Ok(())
}

/// Moves the generated skin's `vertices` (rings about the vertical axis at `axis_x`, z = 0,
/// between heights `y0` and `y1`) onto the subject's skin along rays from the axis, the ray
/// origins kept [`SKIN_END_INSET`] inside the ends; refuses a fit that folds the layout.
pub(crate) fn fit_skin(
    vertices: &mut [Point3<f64>],
    triangles: &[[u32; 3]],
    axis_x: f64,
    (y0, y1): (f64, f64),
    subject: &SubjectMesh,
) -> Result<()> {
    let file = subject.dir.join("skin.obj");
    let template = vertices.to_vec();
    let (lo, hi) = if y1 - y0 > 2.0 * SKIN_END_INSET {
        (y0 + SKIN_END_INSET, y1 - SKIN_END_INSET)
    } else {
        let m = 0.5 * (y0 + y1);
        (m, m)
    };
    project(
        vertices,
        &subject.skin,
        |p| Point3::new(axis_x, p.y.clamp(lo, hi), 0.0),
        "skin",
        &file,
    )?;
    check_folds(&template, vertices, triangles, "skin", &file)
}
