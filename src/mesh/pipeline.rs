//! The preparation pipeline of subject surfaces (Peeters & Pronost 2013, figure 1, for the
//! torso's skin and abdominal cavity): Taubin smoothing, repair, overlap resolution, with a
//! report of what each stage did and how long it took; and the summary printed by
//! `torso mesh info`.

use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

use super::overlap::{OverlapOptions, OverlapReport, Relation, resolve_overlap};
use super::repair::{RepairOptions, RepairReport, repair, self_intersections};
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
    /// Repair.
    pub repair: RepairReport,
    /// Overlap resolution against the skin (abdomen only).
    pub overlap: Option<OverlapReport>,
    /// Measures of the output.
    pub output: MeshInfo,
}

/// Wall time of each stage [ms].
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
    /// The abdominal cavity, inside the skin.
    pub abdomen: Option<TriMesh>,
}

fn check_input(name: &str, m: &TriMesh) -> Result<()> {
    m.validate()?;
    if m.triangles.is_empty() {
        return Err(Error::invalid(name, "no triangle", "a non-empty surface"));
    }
    Ok(())
}

/// Runs smoothing, repair and (with an abdomen) overlap resolution; see the module doc.
pub fn prepare(
    skin: TriMesh,
    abdomen: Option<TriMesh>,
    opts: &PrepareOptions,
) -> Result<(Prepared, PrepareReport)> {
    check_input("skin", &skin)?;
    if let Some(a) = &abdomen {
        check_input("abdomen", a)?;
    }
    let mut times = StageTimes::default();
    let mut surfaces: Vec<(String, TriMesh)> = vec![("skin".into(), skin)];
    if let Some(a) = abdomen {
        surfaces.push(("abdomen".into(), a));
    }
    let mut reports: Vec<SurfaceReport> = surfaces
        .iter()
        .map(|(n, m)| {
            let info = MeshInfo::of(m);
            SurfaceReport {
                name: n.clone(),
                input: info.clone(),
                smoothing: None,
                repair: RepairReport::default(),
                overlap: None,
                output: info,
            }
        })
        .collect();
    let t0 = Instant::now();
    if let Some(taubin) = &opts.taubin {
        for ((_, m), rep) in surfaces.iter_mut().zip(&mut reports) {
            let before = m.clone();
            let mut smoothed = m.clone();
            taubin.smooth(&mut smoothed)?;
            let edge = before.mean_edge_length().max(f64::MIN_POSITIVE);
            // shape change only: distance of the smoothed vertices to the input surface
            // (the umbrella operator also slides vertices along the surface, which is harmless)
            let input = Bvh::new(&before);
            let rms = (smoothed
                .vertices
                .iter()
                .filter_map(|p| input.closest(p))
                .map(|c| c.distance.powi(2))
                .sum::<f64>()
                / before.vertices.len().max(1) as f64)
                .sqrt()
                / edge;
            let skipped = rms < opts.smooth_threshold;
            if !skipped {
                *m = smoothed;
            }
            let v0 = before.volume();
            rep.smoothing = Some(SmoothReport {
                taubin: *taubin,
                volume_change: if v0 != 0.0 {
                    m.volume() / v0 - 1.0
                } else {
                    0.0
                },
                hausdorff: hausdorff(&before, m),
                rms_displacement: rms,
                skipped,
            });
        }
    }
    times.smoothing_ms = t0.elapsed().as_secs_f64() * 1e3;
    let t1 = Instant::now();
    for ((name, m), rep) in surfaces.iter_mut().zip(&mut reports) {
        let ro = opts.repair.unwrap_or_else(|| RepairOptions::for_mesh(m));
        rep.repair =
            repair(m, &ro).map_err(|e| Error::State(format!("repair of the {name}: {e}")))?;
    }
    times.repair_ms = t1.elapsed().as_secs_f64() * 1e3;
    let t2 = Instant::now();
    if surfaces.len() > 1 {
        let (first, rest) = surfaces.split_at_mut(1);
        let skin = &first[0].1;
        let abd = &mut rest[0].1;
        let mut oo = OverlapOptions::for_mesh(abd, Relation::Inside);
        if let Some(m) = opts.margin {
            oo.margin = m;
        }
        reports[1].overlap = Some(
            resolve_overlap(abd, skin, &oo)
                .map_err(|e| Error::State(format!("abdomen inside the skin: {e}")))?,
        );
    }
    times.overlap_ms = t2.elapsed().as_secs_f64() * 1e3;
    for ((_, m), rep) in surfaces.iter().zip(&mut reports) {
        rep.output = MeshInfo::of(m);
    }
    let mut it = surfaces.into_iter().map(|(_, m)| m);
    let skin = it.next().unwrap_or_default();
    let abdomen = it.next();
    Ok((
        Prepared { skin, abdomen },
        PrepareReport {
            surfaces: reports,
            times,
        },
    ))
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
            if let Some(o) = &r.overlap {
                let _ = writeln!(
                    s,
                    "Overlap with the skin: {} penetrating vertices and {} crossing pairs at the start; \
                     {} vertices moved (at most {:.3e}) in {} rounds.\n",
                    o.penetrating_at_start,
                    o.crossing_pairs_at_start,
                    o.vertices_moved,
                    o.max_displacement,
                    o.iterations
                );
            }
        }
        s
    }
}

/// Writes `skin.obj`, `abdomen.obj` (if any), `report.json` and `report.md` into `dir`
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
    Ok(Prepared { skin, abdomen })
}

/// Whether every vertex of `inner` lies inside `outer` (ray parity).
pub fn is_inside(inner: &TriMesh, outer: &TriMesh) -> bool {
    let b = Bvh::new(outer);
    inner.vertices.iter().all(|p| b.contains(p))
        && b.intersections_with(&Bvh::new(inner)).is_empty()
}
