//! A [`Subject`] (sex, age, stature, mass, breast size, posture) turned into geometry: spine
//! joint centres, ribs with their hinge axes, sternum, cartilage joints, the abdominal cavity
//! surface, the rib-cage lining and the muscle element layouts. Nothing here knows about time
//! or forces: [`Anatomy::build`] returns rest-pose geometry that `dynamics` compiles.
//!
//! Every point the dynamics moves is an [`Anchor`]: a rest position plus the [`Body`] that
//! carries it (ground, a rib, the sternum, or a free vertex of the abdominal surface).

mod abdomen;
mod data;
mod layout;
mod lining;
mod muscles;
pub mod prepared;
mod skeleton;
pub mod skin;
mod subject;

pub use abdomen::{Abdomen, VertexRole, azimuth};
pub use layout::{
    ABDOMINAL_FORCES, CENTRAL_TENDON, DIAPHRAGM_FORCE, EXTERNAL_INTERCOSTAL_DRIVE_BY_SPACE,
    INTERCOSTAL_TENSION, Joint, MuscleElement, SCM_FORCE_PER_SIDE, external_intercostal_drive,
};
pub use muscles::MuscleGroup;
pub use prepared::{CavityFit, SubjectMesh};
pub use skeleton::{Rib, Scale, Side, Spine, Sternum, rib_index};
pub use subject::{Posture, SUBJECT_RANGES, Sex, Subject};

use crate::Result;
use nalgebra::Point3;
use std::sync::Arc;

/// The body that carries a point.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Body {
    /// Fixed in space (spine, pelvis, back of the abdomen).
    Ground,
    /// Rib by body index (0-11 right levels 1-12, 12-23 left).
    Rib(u8),
    /// The sternum.
    Sternum,
    /// A free vertex of the abdominal surface, by index among the free vertices.
    Vertex(u32),
}

/// A point of the model: where it is at rest and what carries it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Anchor {
    /// Carrier.
    pub body: Body,
    /// Rest position [m].
    pub rest: Point3<f64>,
}

/// Number of abdominal-surface subdivisions per level of detail (icosphere of 162, 642, 2562
/// vertices).
pub const LOD_SUBDIVISIONS: [u32; 3] = [2, 3, 4];
/// Muscle element counts per level of detail, as fractions of the thesis's.
/// Numerical: a resolution setting.
pub const LOD_MUSCLE_FRACTION: [f64; 3] = [0.25, 0.5, 1.0];

/// The subject's anatomy in the rest pose.
#[derive(Clone, Debug)]
pub struct Anatomy {
    /// The subject it was built for.
    pub subject: Subject,
    /// Level of detail it was built at (0, 1, 2).
    pub level_of_detail: u32,
    /// Scale factors from the reference rib cage.
    pub scale: Scale,
    /// Spine joint centres.
    pub spine: Spine,
    /// 24 ribs, by body index.
    pub ribs: Vec<Rib>,
    /// The sternum.
    pub sternum: Sternum,
    /// Every point of the model.
    pub anchors: Vec<Anchor>,
    /// The abdominal cavity.
    pub abdomen: Abdomen,
    /// Triangles (anchor indices) of the rib-cage lining: inlet cap, rings of ribs 1-7 and the
    /// band down to the costal margin, outward-oriented as part of the thoracic cavity.
    pub lining_triangles: Vec<[u32; 3]>,
    /// Muscle elements of all groups.
    pub muscles: Vec<MuscleElement>,
    /// Cartilage joints (ball joints as stiff zero-length springs).
    pub joints: Vec<Joint>,
    /// The subject's own surfaces the skin and cavity were fitted to (`None`: generated).
    pub subject_mesh: Option<Arc<SubjectMesh>>,
    /// How the cavity was fitted to the subject's (`None`: generated cavity).
    pub cavity_fit: Option<CavityFit>,
}

impl Anatomy {
    /// Builds the anatomy of `subject` at `level_of_detail` (0, 1 or 2).
    pub fn build(subject: &Subject, level_of_detail: u32) -> Result<Anatomy> {
        Anatomy::build_with(subject, level_of_detail, None)
    }

    /// Builds the anatomy on a prepared subject directory (see [`prepared`]) when `mesh_dir`
    /// is given: its skin replaces the generated skin and its cavity (if any) the generated
    /// cavity; the skeleton is the subject's generated one.
    pub fn build_on(
        subject: &Subject,
        level_of_detail: u32,
        mesh_dir: Option<&std::path::Path>,
    ) -> Result<Anatomy> {
        let mesh = mesh_dir.map(SubjectMesh::load).transpose()?;
        Anatomy::build_with(subject, level_of_detail, mesh.map(Arc::new))
    }

    /// Builds the anatomy of `subject` at `level_of_detail`, fitted to the subject's own
    /// surfaces when given: the generated cavity is re-sampled onto `abdomen.obj` (insertions
    /// re-derived by geometry) before the muscles are laid out on it.
    pub fn build_with(
        subject: &Subject,
        level_of_detail: u32,
        subject_mesh: Option<Arc<SubjectMesh>>,
    ) -> Result<Anatomy> {
        subject.validate()?;
        let lod = level_of_detail.min(2) as usize;
        let ansur = data::ansur2();
        let masses = data::body_masses();
        let scale = Scale::for_subject(subject, &ansur);
        let spine = skeleton::build_spine(&scale);
        let sternum = skeleton::build_sternum(subject, &scale, &masses);
        let ribs = skeleton::build_ribs(subject, &scale, &sternum, &masses);
        let mut anchors = Vec::new();
        let abdomen = abdomen::build(
            subject,
            &scale,
            &ribs,
            &sternum,
            &spine,
            &masses,
            LOD_SUBDIVISIONS[lod],
            &mut anchors,
        )?;
        let mut abdomen = abdomen;
        // The lining is zipped to the generated rim (its topology stays the layout's); the
        // fit then moves the rim's anchors, and with them the lining's lower edge.
        let lining_triangles = lining::build(&ribs, &sternum, &abdomen, &mut anchors);
        let mut cavity_fit = None;
        if let Some(mesh) = &subject_mesh {
            match &mesh.abdomen {
                Some(surface) => {
                    let margin =
                        abdomen::costal_margin(&ribs, &sternum, &spine, abdomen.axis_x, &scale);
                    cavity_fit = Some(prepared::fit_cavity(
                        &mut abdomen,
                        &mut anchors,
                        surface,
                        &margin,
                        &mesh.dir.join("abdomen.obj"),
                    )?);
                }
                None => prepared::check_cavity_inside(
                    &abdomen,
                    &anchors,
                    &mesh.skin,
                    &mesh.dir.join("skin.obj"),
                )?,
            }
        }
        let joints = layout::cartilage_joints(&ribs, &mut anchors);
        let muscles = layout::muscles(
            &ribs,
            &sternum,
            &spine,
            &abdomen,
            LOD_MUSCLE_FRACTION[lod],
            &mut anchors,
        );
        Ok(Anatomy {
            subject: subject.clone(),
            level_of_detail: lod as u32,
            scale,
            spine,
            ribs,
            sternum,
            anchors,
            abdomen,
            lining_triangles,
            muscles,
            joints,
            subject_mesh,
            cavity_fit,
        })
    }

    /// Rest position of anchor `i`.
    pub fn rest(&self, i: u32) -> Point3<f64> {
        self.anchors[i as usize].rest
    }

    /// Triangles of the closed thoracic cavity: the lining plus the diaphragm dome reversed.
    pub fn thorax_triangles(&self) -> Vec<[u32; 3]> {
        let mut t = self.lining_triangles.clone();
        t.extend(self.abdomen.dome_triangles().map(|[a, b, c]| [a, c, b]));
        t
    }
}

/// Appends an anchor and returns its index.
pub(crate) fn push_anchor(anchors: &mut Vec<Anchor>, body: Body, rest: Point3<f64>) -> u32 {
    anchors.push(Anchor { body, rest });
    (anchors.len() - 1) as u32
}
