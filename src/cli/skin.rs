//! Skin and marker exports of the `torso` tool: `torso export-obj DIR` (rest geometry as
//! OBJ), `torso render-skin` (picture of the skin and markers at rest and at
//! end-inspiration) and the VTK animation written by `torso simulate --export-vtk DIR`.

use super::common::{
    DriveArgs, MethodAlias, SolverArgs, SubjectArgs, prepare_output_dir, prepare_output_file,
};
use crate::anatomy::skin::export::{MeshPart, PolylinePart, VtkSeries, write_obj};
use crate::anatomy::skin::render::{RenderOptions, RgbImage, render_rgb};
use crate::model::run::{Frame, frame};
use crate::model::{Drive, Torso};
use crate::observe::markers::MarkerModel;
use crate::observe::skinning::{HandleKind, HandlePose};
use crate::{Error, Result};
use clap::Args;
use nalgebra::Point3;
use std::path::{Path, PathBuf};

/// Options of `torso export-obj`: the rest geometry needs no solver, so it takes none.
#[derive(Args, Debug)]
pub struct ExportObjArgs {
    /// The subject and scene.
    #[command(flatten)]
    pub subject: SubjectArgs,
    /// Output directory: skin.obj, abdomen.obj, ribs.obj, sternum.obj, markers.obj.
    pub dir: PathBuf,
}

/// Options of `torso render-skin`.
#[derive(Args, Debug)]
pub struct RenderSkinArgs {
    /// The subject and scene.
    #[command(flatten)]
    pub subject: SubjectArgs,
    /// The ODE solver.
    #[command(flatten)]
    pub solver: SolverArgs,
    /// `--method`, the former name of `--solver`.
    #[command(flatten)]
    pub method: MethodAlias,
    /// The drive whose end-inspiration is shown (default: quiet breathing).
    #[command(flatten)]
    pub drive: DriveArgs,
    /// Magnification of the marker displacements drawn as arrows.
    #[arg(long, default_value_t = 10.0)]
    pub magnify: f64,
    /// Output PNG (docs/results.md's picture is `--out docs/skin.png`).
    #[arg(long, default_value = "skin.png")]
    pub out: PathBuf,
}

/// Grid lines between neighbouring markers (index pairs).
pub fn grid_links(rows: usize, cols: usize) -> Vec<(usize, usize)> {
    let mut links = Vec::new();
    for r in 0..rows {
        for c in 0..cols {
            let i = r * cols + c;
            if c + 1 < cols {
                links.push((i, i + 1));
            }
            if r + 1 < rows {
                links.push((i, i + cols));
            }
        }
    }
    links
}

/// Rigid bones (ribs, sternum, spine) posed at the current state: (name, polyline).
fn posed_bones(model: &MarkerModel, y: &[f64]) -> Result<Vec<(String, Vec<Point3<f64>>)>> {
    let mut poses = Vec::new();
    model.handle_poses(y, &mut poses)?;
    Ok(model
        .handles()
        .iter()
        .zip(&poses)
        .filter(|(h, _)| h.kind == HandleKind::Rigid)
        .map(|(h, p)| {
            let pts = match p {
                HandlePose::Rigid(iso) => h.points.iter().map(|q| iso * q).collect(),
                HandlePose::Translation(d) => h.points.iter().map(|q| q + d).collect(),
            };
            (h.name.clone(), pts)
        })
        .collect())
}

/// The default solver options, for a configuration that is never integrated.
fn default_solver() -> SolverArgs {
    SolverArgs {
        solver: "dopri5".into(),
        rtol: crate::model::Config::default().solver.rtol,
    }
}

/// Runs `torso export-obj`: the rest geometry (model frame, metres) as OBJ files.
pub fn export_obj(args: &ExportObjArgs) -> Result<()> {
    let config = args.subject.config(&default_solver(), Drive::default())?;
    prepare_output_dir(&args.dir)?;
    let mut torso = Torso::new(config)?;
    let model = torso.marker_model()?;
    let y = torso.current_state().to_vec();
    let dir = &args.dir;
    let skin = model.skin();
    write_obj(
        &dir.join("skin.obj"),
        &[MeshPart {
            name: "skin",
            vertices: &skin.vertices,
            triangles: &skin.triangles,
        }],
        &[],
    )?;
    let compiled = torso.compiled().clone();
    let anatomy = &compiled.anatomy;
    let ab_vertices: Vec<Point3<f64>> = anatomy
        .abdomen
        .anchor
        .iter()
        .map(|&a| anatomy.rest(a))
        .collect();
    write_obj(
        &dir.join("abdomen.obj"),
        &[MeshPart {
            name: "abdomen",
            vertices: &ab_vertices,
            triangles: &anatomy.abdomen.triangles,
        }],
        &[],
    )?;
    let bones = posed_bones(&model, &y)?;
    let parts = |f: &dyn Fn(&str) -> bool| -> Vec<PolylinePart> {
        bones
            .iter()
            .filter(|(n, _)| f(n))
            .map(|(n, p)| PolylinePart { name: n, points: p })
            .collect()
    };
    write_obj(
        &dir.join("ribs.obj"),
        &[],
        &parts(&|n| n.starts_with("rib")),
    )?;
    write_obj(
        &dir.join("sternum.obj"),
        &[],
        &parts(&|n| n == "sternum" || n == "spine"),
    )?;
    let markers = torso.markers()?.to_vec();
    let grid = model.grid();
    let names: Vec<String> = (0..grid.rows)
        .map(|r| format!("marker_row{}", r + 1))
        .collect();
    let rows: Vec<PolylinePart> = (0..grid.rows)
        .map(|r| PolylinePart {
            name: &names[r],
            points: &markers[r * grid.cols..(r + 1) * grid.cols],
        })
        .collect();
    write_obj(&dir.join("markers.obj"), &[], &rows)?;
    println!(
        "wrote skin.obj ({} vertices), abdomen.obj, ribs.obj, sternum.obj (with the spine), markers.obj ({} x {}) in {}",
        skin.vertices.len(),
        grid.rows,
        grid.cols,
        dir.display()
    );
    Ok(())
}

/// Writes the current state of `torso` into the four VTK series (skin, markers, abdomen,
/// bones), all in the model frame.
struct VtkWriter {
    skin: VtkSeries,
    markers: VtkSeries,
    abdomen: VtkSeries,
    bones: VtkSeries,
    scratch: Vec<Point3<f64>>,
}

impl VtkWriter {
    fn new(dir: &Path) -> Self {
        VtkWriter {
            skin: VtkSeries::new(dir, "skin"),
            markers: VtkSeries::new(dir, "markers"),
            abdomen: VtkSeries::new(dir, "abdomen"),
            bones: VtkSeries::new(dir, "bones"),
            scratch: Vec::new(),
        }
    }

    fn add(&mut self, torso: &mut Torso) -> Result<()> {
        let t = torso.time();
        let model = torso.marker_model()?;
        let y = torso.current_state().to_vec();
        let mut scratch = Default::default();
        model.skin_model_frame(&y, &mut scratch, &mut self.scratch)?;
        let rest = model.skinning().rest();
        let disp: Vec<f64> = self
            .scratch
            .iter()
            .zip(rest)
            .map(|(p, q)| (p - q).norm())
            .collect();
        self.skin.add_frame(
            t,
            &self.scratch,
            &model.skin().triangles,
            &[],
            &[("displacement", &disp)],
        )?;
        let mut markers = Vec::new();
        model.markers_model_frame(&y, &mut scratch, &mut markers)?;
        let g = model.grid();
        let mut lines: Vec<Vec<u32>> = (0..g.rows)
            .map(|r| ((r * g.cols) as u32..((r + 1) * g.cols) as u32).collect())
            .collect();
        lines.extend((0..g.cols).map(|c| (0..g.rows).map(|r| (r * g.cols + c) as u32).collect()));
        let mdisp: Vec<f64> = markers
            .iter()
            .zip(model.bound().rest())
            .map(|(p, q)| (p - q).norm())
            .collect();
        self.markers
            .add_frame(t, &markers, &[], &lines, &[("displacement", &mdisp)])?;
        let compiled = torso.compiled().clone();
        let ab = &compiled.anatomy.abdomen;
        let pos = torso.anchor_positions();
        let ab_pts: Vec<Point3<f64>> = ab.anchor.iter().map(|&a| pos[a as usize]).collect();
        self.abdomen
            .add_frame(t, &ab_pts, &ab.triangles, &[], &[])?;
        let bones = posed_bones(&model, &y)?;
        let mut pts = Vec::new();
        let mut lines = Vec::new();
        for (_, p) in &bones {
            let start = pts.len() as u32;
            pts.extend_from_slice(p);
            lines.push((start..pts.len() as u32).collect());
        }
        self.bones.add_frame(t, &pts, &[], &lines, &[])
    }

    fn finish(&self) -> Result<Vec<PathBuf>> {
        Ok(vec![
            self.skin.finish()?,
            self.markers.finish()?,
            self.abdomen.finish()?,
            self.bones.finish()?,
        ])
    }
}

/// Advances `torso` by `duration` at `rate` like [`crate::model::run::run`], writing every
/// `stride`-th frame (the first included) of the skin, markers, abdominal surface and bones
/// as VTK series (`DIR/{skin,markers,abdomen,bones}.pvd`, model frame, metres).
pub fn run_with_vtk(
    torso: &mut Torso,
    duration: f64,
    rate: f64,
    dir: &Path,
    stride: usize,
) -> Result<Vec<Frame>> {
    if stride == 0 {
        return Err(Error::invalid("--vtk-stride", stride, "1 or more"));
    }
    let mut vtk = VtkWriter::new(dir);
    let t0 = torso.time();
    let n = (duration * rate).round() as usize;
    let mut frames = Vec::with_capacity(n + 1);
    frames.push(frame(torso)?);
    vtk.add(torso)?;
    for i in 1..=n {
        torso.advance_to(t0 + i as f64 / rate)?;
        frames.push(frame(torso)?);
        if i % stride == 0 {
            vtk.add(torso)?;
        }
    }
    for p in vtk.finish()? {
        println!("wrote {}", p.display());
    }
    Ok(frames)
}

/// Markers and skin of `torso` at rest and at end-inspiration (the largest lung volume of
/// the second breath, the first settling), model frame.
pub struct BreathExtremes {
    /// Markers at the start (rest state).
    pub rest_markers: Vec<Point3<f64>>,
    /// Skin at the start.
    pub rest_skin: Vec<Point3<f64>>,
    /// Time of end-expiration in the second breath [s].
    pub expiration_time: f64,
    /// Markers at end-expiration of the second breath.
    pub expiration_markers: Vec<Point3<f64>>,
    /// Time of end-inspiration in the second breath [s].
    pub inspiration_time: f64,
    /// Markers at end-inspiration.
    pub inspiration_markers: Vec<Point3<f64>>,
    /// Skin at end-inspiration.
    pub inspiration_skin: Vec<Point3<f64>>,
    /// Tidal lung volume of the second breath [L].
    pub tidal_volume: f64,
}

/// Simulates two breaths of `torso`'s drive sampled at `rate` and returns the rest,
/// end-expiration and end-inspiration markers of the second breath (see
/// [`BreathExtremes`]).
pub fn breath_extremes(torso: &mut Torso, rate: f64) -> Result<BreathExtremes> {
    let model = torso.marker_model()?;
    let mut scratch = Default::default();
    let (mut rest_markers, mut rest_skin) = (Vec::new(), Vec::new());
    let y0 = torso.current_state().to_vec();
    model.markers_model_frame(&y0, &mut scratch, &mut rest_markers)?;
    model.skin_model_frame(&y0, &mut scratch, &mut rest_skin)?;
    let period = 1.0 / torso.config().drive.frequency;
    let t0 = torso.time();
    let n = (2.0 * period * rate).round() as usize;
    let (mut lo, mut hi) = (
        (f64::INFINITY, 0.0, Vec::new()),
        (f64::NEG_INFINITY, 0.0, Vec::new()),
    );
    for i in 1..=n {
        let t = t0 + i as f64 / rate;
        torso.advance_to(t)?;
        if t - t0 < period - 1e-9 {
            continue;
        }
        let v = torso.read(crate::Quantity::LungVolume)?;
        if v < lo.0 {
            lo = (v, t, torso.current_state().to_vec());
        }
        if v > hi.0 {
            hi = (v, t, torso.current_state().to_vec());
        }
    }
    if lo.2.is_empty() || hi.2.is_empty() {
        return Err(Error::State("breath too short to sample".into()));
    }
    let (mut expiration_markers, mut inspiration_markers, mut inspiration_skin) =
        (Vec::new(), Vec::new(), Vec::new());
    model.markers_model_frame(&lo.2, &mut scratch, &mut expiration_markers)?;
    model.markers_model_frame(&hi.2, &mut scratch, &mut inspiration_markers)?;
    model.skin_model_frame(&hi.2, &mut scratch, &mut inspiration_skin)?;
    Ok(BreathExtremes {
        rest_markers,
        rest_skin,
        expiration_time: lo.1,
        expiration_markers,
        inspiration_time: hi.1,
        inspiration_markers,
        inspiration_skin,
        tidal_volume: hi.0 - lo.0,
    })
}

/// Runs `torso render-skin`: two panels, the skin and grid at rest, and at end-inspiration
/// of the drive with the markers' displacement since end-expiration drawn magnified.
pub fn render_skin(args: &RenderSkinArgs) -> Result<()> {
    if !(args.magnify > 0.0 && args.magnify <= 1000.0) {
        return Err(Error::invalid("--magnify", args.magnify, "(0, 1000]"));
    }
    let drive = args.drive.drive(args.subject.law()?)?;
    let config = args
        .subject
        .config(&args.solver.with_alias(&args.method), drive)?;
    prepare_output_file(&args.out)?;
    // the rest image is the rest pose (muscles relaxed), not the drive's start
    let mut torso = Torso::new_at_rest(config)?;
    let model = torso.marker_model()?;
    let b = breath_extremes(&mut torso, 56.0)?;
    let g = model.grid();
    let links = grid_links(g.rows, g.cols);
    let tris = &model.skin().triangles;
    let options = RenderOptions::default();
    let rest = render_rgb(&b.rest_skin, tris, &b.rest_markers, &links, &[], &options)?;
    let arrows: Vec<(Point3<f64>, Point3<f64>)> = b
        .expiration_markers
        .iter()
        .zip(&b.inspiration_markers)
        .map(|(e, i)| (*i, i + (i - e) * args.magnify))
        .collect();
    let insp = render_rgb(
        &b.inspiration_skin,
        tris,
        &b.inspiration_markers,
        &links,
        &arrows,
        &options,
    )?;
    RgbImage::hstack(&[rest, insp])?.write_png(&args.out)?;
    let d: Vec<f64> = b
        .expiration_markers
        .iter()
        .zip(&b.inspiration_markers)
        .map(|(e, i)| (i - e).norm() * 1e3)
        .collect();
    println!(
        "end-expiration t = {:.2} s, end-inspiration t = {:.2} s, tidal volume {:.3} L; marker displacement {:.2}-{:.2} mm (arrows x{})",
        b.expiration_time,
        b.inspiration_time,
        b.tidal_volume,
        d.iter().cloned().fold(f64::INFINITY, f64::min),
        d.iter().cloned().fold(0.0, f64::max),
        args.magnify
    );
    println!("wrote {}", args.out.display());
    Ok(())
}
