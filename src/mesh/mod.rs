//! Triangle surfaces and the preparation of subject-specific meshes (Peeters & Pronost 2013):
//! the [`TriMesh`] type with its geometry and topology, file formats, Taubin smoothing,
//! repair, overlap resolution, geometric attachments and tetrahedral volume meshing. This
//! module is the lowest layer of the crate and knows nothing of anatomy or dynamics.

pub mod attach;
pub mod bvh;
pub mod geom;
pub mod io;
pub mod overlap;
pub mod pipeline;
pub mod repair;
pub mod smooth;
pub mod tetra;
mod trimesh;

pub use attach::{Attachment, Extrusion, Region, extrude_to_target};
pub use bvh::{Bvh, Closest, hausdorff, hausdorff_one_sided};
pub use overlap::{OverlapOptions, OverlapReport, Relation, resolve_overlap};
pub use pipeline::{MeshInfo, PrepareOptions, PrepareReport, Prepared, prepare};
pub use repair::{RepairOptions, RepairReport, repair};
pub use smooth::{FilterSpec, Taubin, Weights};
pub use tetra::{StuffOptions, TetMesh, TetQuality, stuff};
pub use trimesh::{Aabb, Adjacency, MAX_ICOSPHERE_SUBDIVISIONS, Topology, TriMesh, edge_key};
