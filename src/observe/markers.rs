//! The SLP marker grid of a compiled model (thesis chapter 3): the subject's skin generated
//! around its own bones, bone-heat skinning driven by the model's bodies, the R x C grid
//! bound to the skin, and, when a recording is given, the grid registered to its first
//! frame so that marker outputs are expressed in the recording's frame (thesis 3.2).
//!
//! Handles (thesis 3.3): one rigid handle per rib (its bone and cartilage polyline), the
//! sternum (jugular notch, sternal angle, xiphisternal joint), the fixed thoracic and lumbar
//! spine, and one translation handle per free vertex of the abdomen's lateral and ventral
//! wall. Their poses come straight from the state vector ([`crate::dynamics::Layout`]):
//!
//! - rib r turns by theta_r about its unit hinge axis u_r through its head h_r:
//!   `p -> h_r + R(u_r, theta_r) (p - h_r)`;
//! - the sternum is a free body with centre of mass x and orientation q:
//!   `p -> x + R(q) (p - x0)`;
//!
//! both computed by the dynamics' kinematics ([`crate::dynamics::kinematics::rib_pose`],
//! [`crate::dynamics::kinematics::sternum_pose`]);
//! - a wall vertex moves by its displacement from rest.
//!
//! Only the points bound to the skin (the markers) are blended per state; the whole skin is
//! deformed only on request (export, C ABI). Building a [`MarkerModel`] (skin, weights) takes
//! a few tenths of a second, so the facade builds it when markers are first read, once per
//! compiled model and grid ([`MarkerCache`]).

use super::skinning::{
    BoundPoints, Handle, HandleKind, HandlePose, Skinning, SkinningFrame, SkinningOptions,
};
use crate::anatomy::skin::{FitOptions, MarkerGrid, MarkerSet, Registration, Skin, SkinOptions};
use crate::anatomy::{Anatomy, Body, VertexRole};
use crate::dynamics::kinematics::{rib_pose, sternum_pose};
use crate::dynamics::{Layout, Model, RIBS};
use crate::recording::Recording;
use crate::{Error, Result};
use nalgebra::{Isometry3, Point3, Unit, Vector3};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

/// Largest number of markers a grid can have (16 x 16); the FMI layer exposes this many.
pub const MAX_MARKERS: usize = 256;

/// What moves a skinning handle.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HandleSource {
    /// Rib by body index (0-11 right levels 1-12, 12-23 left).
    Rib(usize),
    /// The sternum.
    Sternum,
    /// The thoracic and lumbar spine (fixed).
    Spine,
    /// A clavicle (fixed: the shoulder girdle does not take part in breathing here). The skin
    /// along the clavicle line is tethered to the clavicles, not to the first ribs below.
    Clavicle,
    /// A free vertex of the abdominal wall, by index among the free vertices.
    WallVertex(u32),
}

/// The skinning handles of an anatomy and what moves each: 24 ribs, the sternum, the spine
/// (rigid), the two clavicles (rigid, fixed), then the free lateral and ventral
/// abdominal-wall vertices (translation).
///
/// Without the clavicles the skin of the clavicle line took the nearest bones' motion, the
/// first and second ribs', which the scalenes turn most (8.6 deg in quiet breathing): the top
/// marker row moved 8-13 mm. The clavicles belong to the shoulder girdle, which the model
/// does not move (no arms, no scapulae); in quiet breathing it stays nearly still, only the
/// clavicles' medial ends following the manubrium a little. Held fixed, they keep the skin of
/// the clavicle line still as well (`cargo run --release --example rib_kinematics` prints the
/// upper rows' motion by handle).
pub fn anatomy_handles(anatomy: &Anatomy) -> (Vec<Handle>, Vec<HandleSource>) {
    let mut handles = Vec::new();
    let mut sources = Vec::new();
    for (name, points) in crate::anatomy::skin::bone_polylines(anatomy) {
        let source = match name.as_str() {
            "sternum" => HandleSource::Sternum,
            "spine" => HandleSource::Spine,
            _ => HandleSource::Rib(handles.len()),
        };
        handles.push(Handle {
            kind: HandleKind::Rigid,
            name,
            points,
            area: 0.0,
        });
        sources.push(source);
    }
    for (name, points) in crate::anatomy::skin::clavicles(anatomy) {
        handles.push(Handle {
            kind: HandleKind::Rigid,
            name,
            points,
            area: 0.0,
        });
        sources.push(HandleSource::Clavicle);
    }
    let ab = &anatomy.abdomen;
    // Each surface vertex stands for a third of its incident triangles' areas.
    let mut area = vec![0.0; ab.anchor.len()];
    for t in &ab.triangles {
        let [a, b, c] = t.map(|i| anatomy.anchors[ab.anchor[i as usize] as usize].rest);
        let third = (b - a).cross(&(c - a)).norm() / 6.0;
        for &i in t {
            area[i as usize] += third;
        }
    }
    for v in ab.with_role(VertexRole::Wall) {
        let anchor = anatomy.anchors[ab.anchor[v as usize] as usize];
        if let Body::Vertex(j) = anchor.body {
            handles.push(Handle {
                kind: HandleKind::Translation,
                name: format!("abdominal_wall_{v}"),
                points: vec![anchor.rest],
                area: area[v as usize],
            });
            sources.push(HandleSource::WallVertex(j));
        }
    }
    (handles, sources)
}

/// Rest-pose data needed to turn a state vector into handle poses.
#[derive(Clone, Debug)]
struct PoseRig {
    layout: Layout,
    rib_head: Vec<Point3<f64>>,
    rib_axis: Vec<Unit<Vector3<f64>>>,
    sternum_com: Point3<f64>,
    vertex_rest: Vec<Point3<f64>>,
}

impl PoseRig {
    fn new(model: &Model) -> Self {
        PoseRig {
            layout: model.layout,
            rib_head: model.rib_head.clone(),
            rib_axis: model
                .rib_axis
                .iter()
                .map(|a| Unit::new_normalize(*a))
                .collect(),
            sternum_com: model.sternum_com,
            vertex_rest: model
                .vertex_anchor
                .iter()
                .map(|&a| model.rest[a as usize])
                .collect(),
        }
    }

    fn check(&self, y: &[f64]) -> Result<()> {
        if y.len() != self.layout.len {
            return Err(Error::invalid(
                "state length",
                y.len(),
                format!("{} (the model's state)", self.layout.len),
            ));
        }
        Ok(())
    }

    /// The pose of every handle at state `y` (length checked by the caller).
    fn poses_into(&self, sources: &[HandleSource], y: &[f64], out: &mut Vec<HandlePose>) {
        let l = &self.layout;
        let sternum = sternum_pose(l, y, &self.sternum_com);
        out.clear();
        out.extend(sources.iter().map(|s| match *s {
            HandleSource::Rib(r) if r < RIBS => HandlePose::Rigid(rib_pose(
                &self.rib_head[r],
                &self.rib_axis[r],
                y[l.theta + r],
            )),
            HandleSource::Rib(_) | HandleSource::Spine | HandleSource::Clavicle => {
                HandlePose::Rigid(Isometry3::identity())
            }
            HandleSource::Sternum => HandlePose::Rigid(sternum),
            HandleSource::WallVertex(j) => {
                let k = l.vertex_x + 3 * j as usize;
                HandlePose::Translation(
                    Vector3::new(y[k], y[k + 1], y[k + 2]) - self.vertex_rest[j as usize].coords,
                )
            }
        }));
    }
}

/// Which markers a marker model carries: the grid's size and the recording it is
/// registered to, or another marker set bound to the rest skin.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct MarkerScene {
    /// Grid rows (1..=16).
    pub rows: usize,
    /// Grid columns (1..=16).
    pub cols: usize,
    /// SLP recording whose first frame registers the grid (`None`: the model's own frame).
    pub slp_reference: Option<PathBuf>,
    /// A marker set bound to the rest skin (model frame) read instead of the grid (`None`:
    /// the grid). Its bindings index the triangles of the skin generated for the anatomy;
    /// it cannot be combined with `slp_reference` (which registers the grid).
    pub set: Option<Arc<MarkerSet>>,
}

impl Default for MarkerScene {
    /// The thesis's 10 x 6 grid, unregistered.
    fn default() -> Self {
        MarkerScene {
            rows: 10,
            cols: 6,
            slp_reference: None,
            set: None,
        }
    }
}

/// Scratch memory of one marker evaluation (handle poses and influence motions).
#[derive(Clone, Debug, Default)]
pub struct MarkerScratch {
    poses: Vec<HandlePose>,
    frame: SkinningFrame,
}

/// The skin, its weights and the bound marker grid of one compiled model (immutable,
/// shareable).
#[derive(Clone, Debug)]
pub struct MarkerModel {
    skin: Skin,
    grid: MarkerGrid,
    set: MarkerSet,
    handles: Vec<Handle>,
    sources: Vec<HandleSource>,
    skinning: Skinning,
    bound: BoundPoints,
    registration: Option<Registration>,
    rig: PoseRig,
}

impl MarkerModel {
    /// Builds the marker model of `scene`: reads the recording's first frame when one is
    /// given ([`read_slp_first_frame`]), then [`MarkerModel::with_first_frame`].
    pub fn build(anatomy: &Anatomy, model: &Model, scene: &MarkerScene) -> Result<Self> {
        if let Some(set) = &scene.set {
            if scene.slp_reference.is_some() {
                return Err(Error::invalid(
                    "slp.reference",
                    "set together with a marker set other than the grid",
                    "no slp.reference (it registers the grid) or the grid",
                ));
            }
            return MarkerModel::with_set(anatomy, model, scene.rows, scene.cols, set);
        }
        let frame = match &scene.slp_reference {
            None => None,
            Some(path) => {
                let rec = read_slp_first_frame(path)?;
                if (rec.rows, rec.cols) != (scene.rows, scene.cols) {
                    return Err(Error::invalid(
                        "slp.reference",
                        format!("{} (a {} x {} grid)", path.display(), rec.rows, rec.cols),
                        format!(
                            "a recording of the model's {} x {} grid (grid.rows x grid.cols)",
                            scene.rows, scene.cols
                        ),
                    ));
                }
                Some(rec.points)
            }
        };
        MarkerModel::with_first_frame(anatomy, model, scene.rows, scene.cols, frame.as_deref())
    }

    /// Builds the skin around `anatomy`'s bones, places a `rows` x `cols` grid on it, and,
    /// given a recording's first frame (end-expiration; `None` = untracked point), registers
    /// the grid to it and fits the skin (thesis 3.2) before computing the bone-heat weights
    /// of the fitted skin (thesis 3.3).
    pub fn with_first_frame(
        anatomy: &Anatomy,
        model: &Model,
        rows: usize,
        cols: usize,
        first_frame: Option<&[Option<Point3<f64>>]>,
    ) -> Result<Self> {
        let mut skin = Skin::for_anatomy(anatomy, &SkinOptions::default())?;
        let grid = MarkerGrid::place(&skin, rows, cols)?;
        let registration = match first_frame {
            Some(frame) => Some(skin.register(&grid, frame, &FitOptions::default())?),
            None => None,
        };
        let set = MarkerSet::from_grid(&grid);
        MarkerModel::assemble(anatomy, model, skin, grid, set, registration)
    }

    /// Builds the skin around `anatomy`'s bones and binds `set` (bindings on that skin's
    /// triangles, e.g. from [`crate::anatomy::skin::register_to_surface`] or
    /// [`MarkerSet::builtin`]) instead of the grid; the `rows` x `cols` grid is still placed
    /// (for [`MarkerModel::grid`]) but not read. Outputs are in the model frame.
    pub fn with_set(
        anatomy: &Anatomy,
        model: &Model,
        rows: usize,
        cols: usize,
        set: &MarkerSet,
    ) -> Result<Self> {
        let skin = Skin::for_anatomy(anatomy, &SkinOptions::default())?;
        set.check(skin.triangles.len())?;
        let grid = MarkerGrid::place(&skin, rows, cols)?;
        MarkerModel::assemble(anatomy, model, skin, grid, set.clone(), None)
    }

    fn assemble(
        anatomy: &Anatomy,
        model: &Model,
        skin: Skin,
        grid: MarkerGrid,
        set: MarkerSet,
        registration: Option<Registration>,
    ) -> Result<Self> {
        let (handles, sources) = anatomy_handles(anatomy);
        let skinning = Skinning::new(
            &skin.vertices,
            &skin.triangles,
            &handles,
            &SkinningOptions::default(),
        )?;
        let bound = skinning.bind(&skin.triangles, &set.bindings)?;
        let rig = PoseRig::new(model);
        if sources.iter().any(|s| match s {
            HandleSource::WallVertex(j) => *j as usize >= rig.vertex_rest.len(),
            _ => false,
        }) {
            return Err(Error::State(
                "marker model: the anatomy's free vertices do not match the compiled model".into(),
            ));
        }
        Ok(MarkerModel {
            skin,
            grid,
            set,
            handles,
            sources,
            skinning,
            bound,
            registration,
            rig,
        })
    }

    /// The rest skin (fitted to the recording when registered), model frame.
    pub fn skin(&self) -> &Skin {
        &self.skin
    }

    /// The marker grid.
    pub fn grid(&self) -> &MarkerGrid {
        &self.grid
    }

    /// The markers read: the grid's (labels `marker[k]`) or the scene's set.
    pub fn set(&self) -> &MarkerSet {
        &self.set
    }

    /// Number of markers (rows x columns, or the set's).
    pub fn len(&self) -> usize {
        self.bound.len()
    }

    /// Whether the grid is empty (never, once built).
    pub fn is_empty(&self) -> bool {
        self.bound.is_empty()
    }

    /// The skinning handles, in the order of [`MarkerModel::sources`].
    pub fn handles(&self) -> &[Handle] {
        &self.handles
    }

    /// What moves each handle.
    pub fn sources(&self) -> &[HandleSource] {
        &self.sources
    }

    /// The weights.
    pub fn skinning(&self) -> &Skinning {
        &self.skinning
    }

    /// The markers' pre-combined weights.
    pub fn bound(&self) -> &BoundPoints {
        &self.bound
    }

    /// The registration to the recording, when one was given.
    pub fn registration(&self) -> Option<&Registration> {
        self.registration.as_ref()
    }

    /// Expresses a model-frame point in the output frame (the recording's when registered).
    pub fn to_output(&self, p: &Point3<f64>) -> Point3<f64> {
        match &self.registration {
            Some(r) => r.to_recording(p),
            None => *p,
        }
    }

    /// The pose of every handle at state `y`.
    pub fn handle_poses(&self, y: &[f64], out: &mut Vec<HandlePose>) -> Result<()> {
        self.rig.check(y)?;
        self.rig.poses_into(&self.sources, y, out);
        Ok(())
    }

    fn frame(&self, y: &[f64], scratch: &mut MarkerScratch) -> Result<()> {
        self.handle_poses(y, &mut scratch.poses)?;
        self.skinning.frame_into(&scratch.poses, &mut scratch.frame)
    }

    /// Marker positions at state `y` in the model frame (`out` resized to the grid).
    pub fn markers_model_frame(
        &self,
        y: &[f64],
        scratch: &mut MarkerScratch,
        out: &mut Vec<Point3<f64>>,
    ) -> Result<()> {
        self.frame(y, scratch)?;
        out.resize(self.bound.len(), Point3::origin());
        self.bound.evaluate(&scratch.frame, out);
        Ok(())
    }

    /// Marker positions at state `y` in the output frame (the recording's when registered).
    pub fn markers(
        &self,
        y: &[f64],
        scratch: &mut MarkerScratch,
        out: &mut Vec<Point3<f64>>,
    ) -> Result<()> {
        self.markers_model_frame(y, scratch, out)?;
        if let Some(r) = &self.registration {
            for p in out.iter_mut() {
                *p = r.to_recording(p);
            }
        }
        Ok(())
    }

    /// The whole deformed skin at state `y`, model frame.
    pub fn skin_model_frame(
        &self,
        y: &[f64],
        scratch: &mut MarkerScratch,
        out: &mut Vec<Point3<f64>>,
    ) -> Result<()> {
        self.frame(y, scratch)?;
        self.skinning.deform_all(&scratch.frame, out);
        Ok(())
    }

    /// The whole deformed skin at state `y` in the output frame (the markers' frame).
    pub fn skin_vertices(
        &self,
        y: &[f64],
        scratch: &mut MarkerScratch,
        out: &mut Vec<Point3<f64>>,
    ) -> Result<()> {
        self.skin_model_frame(y, scratch, out)?;
        if let Some(r) = &self.registration {
            for p in out.iter_mut() {
                *p = r.to_recording(p);
            }
        }
        Ok(())
    }
}

/// Marker models built for one compiled model, one per grid (size and registration), built
/// on first use and shared by every instance of that compiled model.
#[derive(Default)]
pub struct MarkerCache {
    built: Mutex<Vec<(MarkerScene, Arc<MarkerModel>)>>,
}

impl std::fmt::Debug for MarkerCache {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let n = self.built.lock().map(|b| b.len()).unwrap_or(0);
        write!(f, "MarkerCache({n} built)")
    }
}

impl MarkerCache {
    /// The marker model of `scene`, built now if not yet built (a failed build is not
    /// cached: its error is returned and the next call tries again).
    pub fn get_or_build(
        &self,
        scene: &MarkerScene,
        anatomy: &Anatomy,
        model: &Model,
    ) -> Result<Arc<MarkerModel>> {
        let mut built = self.built.lock().unwrap_or_else(|e| e.into_inner());
        if let Some((_, m)) = built.iter().find(|(s, _)| s == scene) {
            return Ok(m.clone());
        }
        let m = Arc::new(MarkerModel::build(anatomy, model, scene)?);
        built.push((scene.clone(), m.clone()));
        Ok(m)
    }
}

/// Per-instance marker outputs: the shared model, and the markers of the current state,
/// computed once per state (call [`MarkerOutputs::invalidate`] when the state changes).
#[derive(Clone, Debug, Default)]
pub struct MarkerOutputs {
    model: Option<Arc<MarkerModel>>,
    valid: bool,
    positions: Vec<Point3<f64>>,
    scratch: MarkerScratch,
}

impl MarkerOutputs {
    /// Marks the cached markers stale (after a step, restore or reset).
    pub fn invalidate(&mut self) {
        self.valid = false;
    }

    /// The marker model, fetched with `get` on first use.
    pub fn model(
        &mut self,
        get: impl FnOnce() -> Result<Arc<MarkerModel>>,
    ) -> Result<&Arc<MarkerModel>> {
        if self.model.is_none() {
            self.model = Some(get()?);
        }
        Ok(self.model.as_ref().expect("set above"))
    }

    /// Whether the markers of the current state have been computed (and
    /// [`MarkerOutputs::positions`] returns them without work).
    pub fn is_valid(&self) -> bool {
        self.valid
    }

    /// The markers last computed (those of the current state when
    /// [`MarkerOutputs::is_valid`]).
    pub fn cached(&self) -> &[Point3<f64>] {
        &self.positions
    }

    /// The markers at state `y` (output frame), computed once per state.
    pub fn positions(
        &mut self,
        get: impl FnOnce() -> Result<Arc<MarkerModel>>,
        y: &[f64],
    ) -> Result<&[Point3<f64>]> {
        if !self.valid {
            let m = self.model(get)?.clone();
            m.markers(y, &mut self.scratch, &mut self.positions)?;
            self.valid = true;
        }
        Ok(&self.positions)
    }

    /// The whole skin at state `y` (output frame) into `out`.
    pub fn skin(
        &mut self,
        get: impl FnOnce() -> Result<Arc<MarkerModel>>,
        y: &[f64],
        out: &mut Vec<Point3<f64>>,
    ) -> Result<()> {
        let m = self.model(get)?.clone();
        m.skin_vertices(y, &mut self.scratch, out)
    }
}

/// The grid size and first frame of an SLP recording.
#[derive(Clone, Debug, PartialEq)]
pub struct SlpFirstFrame {
    /// Grid rows.
    pub rows: usize,
    /// Grid columns.
    pub cols: usize,
    /// Time of the first frame [s].
    pub time: f64,
    /// Grid points of the first frame in metres (`None`: not tracked), row-major from the top
    /// row, column 1 on the subject's right.
    pub points: Vec<Option<Point3<f64>>>,
}

/// Reads the grid size and first frame of an SLP recording: the grid CSV of
/// [`crate::recording::grid_csv`], read and checked whole by [`Recording::read`] (its errors
/// name the file, line and character column), so that a reference is any recording the fit
/// reads.
pub fn read_slp_first_frame(path: &Path) -> Result<SlpFirstFrame> {
    let mut rec = Recording::read(path)?;
    // `Recording::read` refuses a recording of fewer than two frames
    let points = rec.frames.swap_remove(0);
    Ok(SlpFirstFrame {
        rows: rec.grid.0,
        cols: rec.grid.1,
        time: rec.times[0],
        points,
    })
}
