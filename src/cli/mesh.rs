//! `torso mesh`: prepare subject surfaces (smoothing, repair, overlaps), summarise a surface
//! file, and fill a closed surface with tetrahedra.

use std::path::PathBuf;

use clap::Subcommand;

use crate::mesh::pipeline::{
    MeshInfo, PrepareOptions, prepare_all, read_surface_dir, write_prepared,
};
use crate::mesh::{StuffOptions, Taubin, Weights, io, stuff};
use crate::{Error, Result};

/// Subcommands of `torso mesh`.
#[derive(Subcommand, Debug)]
pub enum MeshCommand {
    /// Smooth, repair and resolve overlaps of a skin (with abdominal cavity and ribs); writes
    /// skin.obj, abdomen.obj, ribs/*.obj, report.json and report.md into the output directory.
    Prepare {
        /// Skin surface (OBJ, STL, OFF or VTK).
        #[arg(long)]
        skin: PathBuf,
        /// Abdominal cavity surface, kept inside the skin.
        #[arg(long)]
        abdomen: Option<PathBuf>,
        /// Directory of rib (bone) surfaces, kept inside the skin and out of the abdomen.
        #[arg(long)]
        ribs: Option<PathBuf>,
        /// Output directory.
        #[arg(long)]
        out: PathBuf,
        /// Skip smoothing.
        #[arg(long)]
        no_smooth: bool,
        /// Taubin lambda (0 < lambda < 1).
        #[arg(long, default_value_t = 0.5)]
        lambda: f64,
        /// Taubin pass-band frequency k_PB (eq. 2 gives mu).
        #[arg(long, default_value_t = 0.05)]
        k_pb: f64,
        /// Taubin iterations N.
        #[arg(long, default_value_t = 50)]
        iterations: usize,
        /// Clearance between abdomen and skin, in file units (default: half an edge).
        #[arg(long)]
        margin: Option<f64>,
        /// Use cotangent instead of umbrella Laplacian weights.
        #[arg(long)]
        cotangent: bool,
        /// Leave the openings of open surfaces open (inside tests then need closed surfaces).
        #[arg(long)]
        keep_open: bool,
    },
    /// Print counts, volume, area, closedness and self-intersections of a surface file.
    Info {
        /// Surface file (OBJ, STL, OFF or VTK).
        file: PathBuf,
        /// Print JSON instead of text.
        #[arg(long)]
        json: bool,
    },
    /// Fill a closed surface with tetrahedra (isosurface stuffing) and report their quality.
    Tetra {
        /// Closed surface file.
        file: PathBuf,
        /// Output volume mesh (.vtk UnstructuredGrid or .msh Gmsh 2.2).
        #[arg(long)]
        out: PathBuf,
        /// Lattice cubes along the longest bounding-box side.
        #[arg(long, default_value_t = 30)]
        cells: usize,
        /// Lattice spacing in file units (overrides --cells).
        #[arg(long)]
        spacing: Option<f64>,
    },
}

/// Runs a `torso mesh` subcommand.
pub fn run(cmd: MeshCommand) -> Result<()> {
    match cmd {
        MeshCommand::Prepare {
            skin,
            abdomen,
            ribs,
            out,
            no_smooth,
            lambda,
            k_pb,
            iterations,
            margin,
            cotangent,
            keep_open,
        } => {
            let skin = io::read(&skin)?;
            let abdomen = abdomen.map(io::read).transpose()?;
            let mut taubin = Taubin::from_pass_band(lambda, k_pb, iterations)?;
            if cotangent {
                taubin.weights = Weights::Cotangent;
            }
            let opts = PrepareOptions {
                taubin: (!no_smooth).then_some(taubin),
                margin,
                close_holes: !keep_open,
                ..PrepareOptions::default()
            };
            let ribs = ribs.map(read_surface_dir).transpose()?.unwrap_or_default();
            let (prepared, report) = prepare_all(skin, abdomen, ribs, &opts)?;
            write_prepared(&out, &prepared, &report)?;
            print!("{}", report.to_markdown());
            println!("written to {}", out.display());
            Ok(())
        }
        MeshCommand::Info { file, json } => {
            let m = io::read(&file)?;
            let info = MeshInfo::of(&m);
            if json {
                let s =
                    serde_json::to_string_pretty(&info).map_err(|e| Error::State(e.to_string()))?;
                println!("{s}");
            } else {
                println!("{}", file.display());
                print!("{}", info.to_text());
            }
            Ok(())
        }
        MeshCommand::Tetra {
            file,
            out,
            cells,
            spacing,
        } => {
            let m = io::read(&file)?;
            if cells == 0 {
                return Err(Error::invalid("--cells", cells, "[1, inf)"));
            }
            let mut opts = StuffOptions::with_cells(&m, cells);
            if let Some(h) = spacing {
                opts.spacing = h;
            }
            let t = std::time::Instant::now();
            let tm = stuff(&m, &opts)?;
            let ms = t.elapsed().as_secs_f64() * 1e3;
            tm.write(&out)?;
            let q = tm.quality();
            println!(
                "{} tetrahedra, {} vertices, volume {:.6e} (surface {:.6e}); dihedral angles {:.2} .. {:.2} deg; \
                 radius-edge ratio max {:.3}, mean {:.3}; spacing {:.4e}; {:.0} ms",
                q.tets,
                q.vertices,
                q.volume,
                m.volume(),
                q.min_dihedral_deg,
                q.max_dihedral_deg,
                q.max_radius_edge,
                q.mean_radius_edge,
                opts.spacing,
                ms
            );
            println!("written to {}", out.display());
            Ok(())
        }
    }
}
