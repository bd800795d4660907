//! Triangle surfaces and the preparation of subject-specific meshes (Peeters & Pronost 2013):
//! the [`TriMesh`] type with its geometry and topology, file formats, Taubin smoothing,
//! repair, overlap resolution, geometric attachments and tetrahedral volume meshing. This
//! module is the lowest layer of the crate and knows nothing of anatomy or dynamics.
//!
//! | file | owns |
//! |---|---|
//! | `trimesh` | [`TriMesh`]: area, signed volume, centroid, normals, adjacency, topology checks, transforms, [`TriMesh::icosphere`] |
//! | [`io`] | OBJ, STL (binary, ASCII, welding), OFF, VTK PolyData; located parse errors |
//! | [`geom`], [`bvh`] | triangle predicates (closest point, Moller triangle-triangle); the [`Bvh`]: closest point, signed distance, point-in-mesh, self-intersections, Hausdorff distance |
//! | [`smooth`] | Taubin lambda/mu filter and its design from k_PB, k_SB, delta_PB, delta_SB (paper section 3.3) |
//! | [`repair`](mod@repair) | short-edge collapse, sliver flips, opposite faces, self-intersection removal (section 3.5) |
//! | [`overlap`] | one surface inside (or outside) another with a margin (section 3.6) |
//! | [`attach`] | attachment areas by geometry, missing-attachment extrusion (sections 3.4, 3.8) |
//! | [`tetra`] | isosurface stuffing into tetrahedra, quality, VTK and Gmsh output (section 3.7) |
//! | [`pipeline`] | the preparation run behind `torso mesh prepare` and its report |
//!
//! A prepared subject directory (written by [`pipeline::write_prepared`], read by
//! [`pipeline::read_prepared`]) holds `skin.obj`, `abdomen.obj` (optional), `ribs/<name>.obj`
//! (optional), `report.json` and `report.md`; an `attachments.json` written by
//! [`attach::save`] may sit beside them. Coordinates are whatever the input files use; the
//! model expects metres in its frame (x anterior, y superior, z right), so a user converts
//! (e.g. with [`TriMesh::transform`]) before preparing.

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
pub use pipeline::{MeshInfo, PrepareOptions, PrepareReport, Prepared, prepare, prepare_all};
pub use repair::{RepairOptions, RepairReport, repair};
pub use smooth::{FilterSpec, Taubin, Weights};
pub use tetra::{StuffOptions, TetMesh, TetQuality, stuff};
pub use trimesh::{Aabb, Adjacency, MAX_ICOSPHERE_SUBDIVISIONS, Topology, TriMesh, edge_key};
