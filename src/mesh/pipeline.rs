//! The preparation pipeline of subject surfaces (Peeters & Pronost 2013, figure 1, for the
//! torso's skin and abdominal cavity): Taubin smoothing, repair, overlap resolution, with a
//! report of what each stage did and how long it took; and the summary printed by
//! `torso mesh info`.

use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

use super::overlap::{OverlapOptions, OverlapReport, Relation, resolve_overlap};
use super::repair::{
    RepairOptions, RepairReport, fill_holes, remove_self_intersections, repair, self_intersections,
};
use super::{Bvh, Taubin, Topology, TriMesh, hausdorff, io};
use crate::{Error, Result};

/// Options of [`prepare`].
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct PrepareOptions {
    /// The smoothing filter; None skips smoothing.
    pub taubin: Option<Taubin>,
    /// Repair thresholds; None derives them per surface with [`RepairOptions::for_mesh`].
    pub repair: Option<RepairOptions>,
    /// Clearance between abdomen and skin; None uses half the abdomen's mean edge length.
    pub margin: Option<f64>,
    /// A surface whose smoothed vertices would lie at an RMS distance from the input surface
    /// under this fraction of its mean edge length counts as already smooth and is left as it is; this
    /// makes the pipeline idempotent (a low-pass filter's pass-band gain is not exactly 1).
    pub smooth_threshold: f64,
    /// Close the openings of open surfaces (a trunk scan open at neck, arms and waist) with
    /// faired patches before repair, so that volumes and inside tests are defined.
    pub close_holes: bool,
}

impl Default for PrepareOptions {
    /// Default Taubin filter, derived repair thresholds and margin, smoothing threshold 5 %
    /// of an edge.
    fn default() -> Self {
        PrepareOptions {
            taubin: Some(Taubin::default()),
            repair: None,
            margin: None,
            smooth_threshold: 0.05,
            close_holes: true,
        }
    }
}

/// Summary of one surface.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct MeshInfo {
    /// Vertex count.
    pub vertices: usize,
    /// Triangle count.
    pub triangles: usize,
    /// Enclosed volume (divergence theorem).
    pub volume: f64,
    /// Surface area.
    pub area: f64,
    /// Mean edge length.
    pub mean_edge: f64,
    /// Bounding-box minimum corner.
    pub bbox_min: [f64; 3],
    /// Bounding-box maximum corner.
    pub bbox_max: [f64; 3],
    /// Edge topology.
    pub topology: Topology,
    /// Self-intersecting triangle pairs.
    pub self_intersections: usize,
}

impl MeshInfo {
    /// Measures `mesh`.
    pub fn of(mesh: &TriMesh) -> MeshInfo {
        let bb = mesh.bounding_box();
        MeshInfo {
            vertices: mesh.num_vertices(),
            triangles: mesh.num_triangles(),
            volume: mesh.volume(),
            area: mesh.area(),
            mean_edge: mesh.mean_edge_length(),
            bbox_min: [bb.min.x, bb.min.y, bb.min.z],
            bbox_max: [bb.max.x, bb.max.y, bb.max.z],
            topology: mesh.topology(),
            self_intersections: self_intersections(mesh).len(),
        }
    }

    /// Human-readable lines.
    pub fn to_text(&self) -> String {
        let t = &self.topology;
        format!(
            "vertices            {}\ntriangles           {}\nvolume              {:.6e}\narea                {:.6e}\n\
             mean edge           {:.6e}\nbounding box        [{:.4}, {:.4}, {:.4}] .. [{:.4}, {:.4}, {:.4}]\n\
             closed              {}\nedge-manifold       {}\nconsistent normals  {}\nboundary edges      {}\n\
             non-manifold edges  {}\nEuler characteristic {}\nself-intersections  {}\n",
            self.vertices,
            self.triangles,
            self.volume,
            self.area,
            self.mean_edge,
            self.bbox_min[0],
            self.bbox_min[1],
            self.bbox_min[2],
            self.bbox_max[0],
            self.bbox_max[1],
            self.bbox_max[2],
            t.is_closed(),
            t.is_edge_manifold(),
            t.is_consistently_oriented(),
            t.boundary_edges,
            t.non_manifold_edges,
            t.euler_characteristic,
            self.self_intersections
        )
    }
}

/// What smoothing did to one surface.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct SmoothReport {
    /// The filter used.
    pub taubin: Taubin,
    /// Relative volume change (V_after / V_before - 1).
    pub volume_change: f64,
    /// Hausdorff distance between the surface before and after.
    pub hausdorff: f64,
    /// RMS distance of the filtered vertices from the input surface, as a fraction of the
    /// mean edge length.
    pub rms_displacement: f64,
    /// The surface was already smooth (RMS displacement under the threshold) and was kept.
    pub skipped: bool,
}

/// The stages applied to one surface.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct SurfaceReport {
    /// Surface name (`skin`, `abdomen`).
    pub name: String,
    /// Measures of the input.
    pub input: MeshInfo,
    /// Smoothing, if run.
    pub smoothing: Option<SmoothReport>,
    /// Triangles added to close the surface's own openings.
    pub holes_closed: usize,
    /// Repair.
    pub repair: RepairReport,
    /// Overlap resolution steps in which this surface moved against another.
    pub overlaps: Vec<OverlapStep>,
    /// Measures of the output.
    pub output: MeshInfo,
}

/// One overlap resolution of a surface against a fixed one.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct OverlapStep {
    /// Name of the fixed surface.
    pub against: String,
    /// Required relation to it.
    pub relation: Relation,
    /// What was done.
    pub report: OverlapReport,
    /// Self-intersecting pairs the pushing created (a thin part squeezed flat), removed
    /// again by [`super::repair::remove_self_intersections`] before the next round.
    pub self_intersections_removed: usize,
}

/// Wall time of each stage (ms).
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct StageTimes {
    /// Smoothing of all surfaces.
    pub smoothing_ms: f64,
    /// Repair of all surfaces.
    pub repair_ms: f64,
    /// Overlap resolution.
    pub overlap_ms: f64,
}

/// Report of [`prepare`].
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct PrepareReport {
    /// One entry per surface.
    pub surfaces: Vec<SurfaceReport>,
    /// Stage timings.
    pub times: StageTimes,
}

/// Prepared surfaces.
#[derive(Debug, Clone, PartialEq)]
pub struct Prepared {
    /// The skin.
    pub skin: TriMesh,
    /// The abdominal cavity, inside the skin and outside the ribs.
    pub abdomen: Option<TriMesh>,
    /// Named rib (or other bone) surfaces, inside the skin.
    pub ribs: Vec<(String, TriMesh)>,
}

fn check_input(name: &str, m: &TriMesh) -> Result<()> {
    m.validate()?;
    if m.triangles.is_empty() {
        return Err(Error::invalid(name, "no triangle", "a non-empty surface"));
    }
    Ok(())
}

/// Runs smoothing, repair and (with an abdomen) overlap resolution on a skin and an
/// optional abdominal cavity; see [`prepare_all`].
pub fn prepare(
    skin: TriMesh,
    abdomen: Option<TriMesh>,
    opts: &PrepareOptions,
) -> Result<(Prepared, PrepareReport)> {
    prepare_all(skin, abdomen, Vec::new(), opts)
}

/// Rounds of the overlap stage with ribs (each round: ribs into the skin, abdomen out of
/// the ribs, abdomen into the skin).
const OVERLAP_ROUNDS: usize = 4;

/// Runs the pipeline on a skin, an optional abdominal cavity and named rib surfaces: every
/// surface is smoothed (unless already smooth) and repaired; then ribs are moved inside the
/// skin, the abdomen out of every rib and inside the skin, repeated until a round moves
/// nothing.
pub fn prepare_all(
    skin: TriMesh,
    abdomen: Option<TriMesh>,
    ribs: Vec<(String, TriMesh)>,
    opts: &PrepareOptions,
) -> Result<(Prepared, PrepareReport)> {
    check_input("skin", &skin)?;
    if let Some(a) = &abdomen {
        check_input("abdomen", a)?;
    }
    for (n, m) in &ribs {
        check_input(n, m)?;
    }
    let mut times = StageTimes::default();
    let has_abdomen = abdomen.is_some();
    let mut surfaces: Vec<(String, TriMesh)> = vec![("skin".into(), skin)];
    if let Some(a) = abdomen {
        surfaces.push(("abdomen".into(), a));
    }
    let first_rib = surfaces.len();
    surfaces.extend(ribs);
    let mut reports: Vec<SurfaceReport> = surfaces
        .iter()
        .map(|(n, m)| {
            let info = MeshInfo::of(m);
            SurfaceReport {
                name: n.clone(),
                input: info.clone(),
                smoothing: None,
                holes_closed: 0,
                repair: RepairReport::default(),
                overlaps: Vec::new(),
                output: info,
            }
        })
        .collect();
    let t0 = Instant::now();
    if let Some(taubin) = &opts.taubin {
        for ((_, m), rep) in surfaces.iter_mut().zip(&mut reports) {
            rep.smoothing = Some(smooth_stage(m, taubin, opts.smooth_threshold)?);
        }
    }
    times.smoothing_ms = t0.elapsed().as_secs_f64() * 1e3;
    let t1 = Instant::now();
    for ((name, m), rep) in surfaces.iter_mut().zip(&mut reports) {
        if opts.close_holes && m.topology().boundary_edges > 0 {
            rep.holes_closed = fill_holes(m);
        }
        let ro = opts.repair.unwrap_or_else(|| RepairOptions::for_mesh(m));
        rep.repair =
            repair(m, &ro).map_err(|e| Error::State(format!("repair of the {name}: {e}")))?;
    }
    times.repair_ms = t1.elapsed().as_secs_f64() * 1e3;
    let t2 = Instant::now();
    let mut steps: Vec<(usize, usize, Relation)> = Vec::new();
    for r in first_rib..surfaces.len() {
        steps.push((r, 0, Relation::Inside));
    }
    if has_abdomen {
        for r in first_rib..surfaces.len() {
            steps.push((1, r, Relation::Outside));
        }
        steps.push((1, 0, Relation::Inside));
    }
    for round in 0..OVERLAP_ROUNDS {
        let mut moved = 0;
        for &(m, f, relation) in &steps {
            let fixed = surfaces[f].clone();
            let name = surfaces[m].0.clone();
            let moving = &mut surfaces[m].1;
            let mut oo = OverlapOptions::for_mesh(moving, relation);
            if let Some(margin) = opts.margin {
                oo.margin = margin;
            }
            let report = resolve_overlap(moving, &fixed.1, &oo).map_err(|e| {
                let rel = if relation == Relation::Inside {
                    "inside"
                } else {
                    "outside"
                };
                Error::State(format!("{name} {rel} the {}: {e}", fixed.0))
            })?;
            moved += report.vertices_moved;
            let mut removed = 0;
            if report.vertices_moved > 0 {
                let si = remove_self_intersections(moving, 6);
                if si.pairs_left > 0 {
                    return Err(Error::State(format!(
                        "{name}: {} self-intersecting pairs left after moving it against the {}",
                        si.pairs_left, fixed.0
                    )));
                }
                removed = si.pairs_found;
                moving.remove_unreferenced_vertices();
            }
            if round == 0 || report.vertices_moved > 0 {
                reports[m].overlaps.push(OverlapStep {
                    against: fixed.0.clone(),
                    relation,
                    report,
                    self_intersections_removed: removed,
                });
            }
        }
        if moved == 0 {
            break;
        }
    }
    times.overlap_ms = t2.elapsed().as_secs_f64() * 1e3;
    for ((_, m), rep) in surfaces.iter().zip(&mut reports) {
        rep.output = MeshInfo::of(m);
    }
    let ribs = surfaces.split_off(first_rib);
    let mut it = surfaces.into_iter().map(|(_, m)| m);
    let skin = it.next().unwrap_or_default();
    let abdomen = it.next();
    Ok((
        Prepared {
            skin,
            abdomen,
            ribs,
        },
        PrepareReport {
            surfaces: reports,
            times,
        },
    ))
}

/// Smooths `m` unless the filter would barely change its shape (see
/// [`PrepareOptions::smooth_threshold`]).
fn smooth_stage(m: &mut TriMesh, taubin: &Taubin, threshold: f64) -> Result<SmoothReport> {
    let before = m.clone();
    let mut smoothed = m.clone();
    taubin.smooth(&mut smoothed)?;
    let edge = before.mean_edge_length().max(f64::MIN_POSITIVE);
    // shape change only: distance of the smoothed vertices to the input surface (the
    // umbrella operator also slides vertices along the surface, which is harmless)
    let input = Bvh::new(&before);
    let sum: f64 = smoothed
        .vertices
        .iter()
        .filter_map(|p| input.closest(p))
        .map(|c| c.distance.powi(2))
        .sum();
    let rms = (sum / before.vertices.len().max(1) as f64).sqrt() / edge;
    let skipped = rms < threshold;
    if !skipped {
        *m = smoothed;
    }
    let v0 = before.volume();
    Ok(SmoothReport {
        taubin: *taubin,
        volume_change: if v0 != 0.0 {
            m.volume() / v0 - 1.0
        } else {
            0.0
        },
        hausdorff: hausdorff(&before, m),
        rms_displacement: rms,
        skipped,
    })
}

impl PrepareReport {
    /// Markdown rendering of the report.
    pub fn to_markdown(&self) -> String {
        let mut s = String::from("# Mesh preparation report\n\n");
        let _ = writeln!(
            s,
            "Stage times: smoothing {:.1} ms, repair {:.1} ms, overlap {:.1} ms.\n",
            self.times.smoothing_ms, self.times.repair_ms, self.times.overlap_ms
        );
        for r in &self.surfaces {
            let _ = writeln!(s, "## {}\n", r.name);
            s.push_str("| | input | output |\n|---|---|---|\n");
            let (a, b) = (&r.input, &r.output);
            let _ = writeln!(s, "| vertices | {} | {} |", a.vertices, b.vertices);
            let _ = writeln!(s, "| triangles | {} | {} |", a.triangles, b.triangles);
            let _ = writeln!(s, "| volume | {:.6e} | {:.6e} |", a.volume, b.volume);
            let _ = writeln!(s, "| area | {:.6e} | {:.6e} |", a.area, b.area);
            let _ = writeln!(
                s,
                "| closed | {} | {} |",
                a.topology.is_closed(),
                b.topology.is_closed()
            );
            let _ = writeln!(
                s,
                "| self-intersections | {} | {} |\n",
                a.self_intersections, b.self_intersections
            );
            if let Some(sm) = &r.smoothing {
                let _ = writeln!(
                    s,
                    "Smoothing: lambda {:.4}, mu {:.4}, N {}; RMS displacement {:.3} edges{}; \
                     volume change {:+.3} %, Hausdorff {:.3e}.\n",
                    sm.taubin.lambda,
                    sm.taubin.mu,
                    sm.taubin.iterations,
                    sm.rms_displacement,
                    if sm.skipped {
                        " (already smooth: kept)"
                    } else {
                        ""
                    },
                    100.0 * sm.volume_change,
                    sm.hausdorff
                );
            }
            if r.holes_closed > 0 {
                let _ = writeln!(s, "Openings closed with {} triangles.\n", r.holes_closed);
            }
            let rp = &r.repair;
            let _ = writeln!(
                s,
                "Repair: {} edges collapsed, {} flipped, {} opposite faces removed, {} intersecting pairs \
                 ({} triangles removed, {} added, {} pairs left).\n",
                rp.collapsed_edges,
                rp.flipped_edges,
                rp.opposite_faces_removed,
                rp.intersecting_pairs,
                rp.triangles_removed,
                rp.triangles_added,
                rp.intersecting_pairs_left
            );
            for o in &r.overlaps {
                let rel = if o.relation == Relation::Inside {
                    "inside"
                } else {
                    "outside"
                };
                let p = &o.report;
                let _ = writeln!(
                    s,
                    "Overlap, {rel} the {}: {} violating vertices and {} crossing pairs at the start; \
                     {} vertices moved (at most {:.3e}) in {} rounds.\n",
                    o.against,
                    p.penetrating_at_start,
                    p.crossing_pairs_at_start,
                    p.vertices_moved,
                    p.max_displacement,
                    p.iterations
                );
            }
        }
        s
    }
}

/// Writes `skin.obj`, `abdomen.obj` (if any), `ribs/<name>.obj`, `report.json` and
/// `report.md` into `dir`
/// (created if missing): the layout a prepared subject mesh directory has.
pub fn write_prepared(
    dir: impl AsRef<Path>,
    prepared: &Prepared,
    report: &PrepareReport,
) -> Result<()> {
    let dir = dir.as_ref();
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    io::write(&prepared.skin, dir.join("skin.obj"))?;
    if let Some(a) = &prepared.abdomen {
        io::write(a, dir.join("abdomen.obj"))?;
    }
    if !prepared.ribs.is_empty() {
        let rd = dir.join("ribs");
        std::fs::create_dir_all(&rd).map_err(|e| Error::io(&rd, e))?;
        for (name, m) in &prepared.ribs {
            io::write(m, rd.join(format!("{name}.obj")))?;
        }
    }
    let json = serde_json::to_string_pretty(report)
        .map_err(|e| Error::State(format!("report serialisation: {e}")))?;
    let p = dir.join("report.json");
    std::fs::write(&p, json).map_err(|e| Error::io(&p, e))?;
    let p = dir.join("report.md");
    std::fs::write(&p, report.to_markdown()).map_err(|e| Error::io(&p, e))
}

/// Reads a prepared directory written by [`write_prepared`].
pub fn read_prepared(dir: impl AsRef<Path>) -> Result<Prepared> {
    let dir = dir.as_ref();
    let skin = io::read(dir.join("skin.obj"))?;
    let a = dir.join("abdomen.obj");
    let abdomen = if a.exists() {
        Some(io::read(&a)?)
    } else {
        None
    };
    let rd = dir.join("ribs");
    let ribs = if rd.is_dir() {
        read_surface_dir(&rd)?
    } else {
        Vec::new()
    };
    Ok(Prepared {
        skin,
        abdomen,
        ribs,
    })
}

/// Reads every surface file (obj, stl, off, vtk) of a directory, sorted by file name, named
/// by its file stem.
pub fn read_surface_dir(dir: impl AsRef<Path>) -> Result<Vec<(String, TriMesh)>> {
    let dir = dir.as_ref();
    let mut files: Vec<std::path::PathBuf> = std::fs::read_dir(dir)
        .map_err(|e| Error::io(dir, e))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| io::Format::from_path(p).is_ok())
        .collect();
    files.sort();
    files
        .into_iter()
        .map(|p| {
            let name = p
                .file_stem()
                .and_then(|s| s.to_str())
                .unwrap_or("surface")
                .to_string();
            io::read(&p).map(|m| (name, m))
        })
        .collect()
}

/// Whether every vertex of `inner` lies inside `outer` (ray parity).
pub fn is_inside(inner: &TriMesh, outer: &TriMesh) -> bool {
    let b = Bvh::new(outer);
    inner.vertices.iter().all(|p| b.contains(p))
        && b.intersections_with(&Bvh::new(inner)).is_empty()
}
