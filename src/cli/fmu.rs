//! `torso fmu`: packages the FMI 2.0 co-simulation FMU and writes its model description.

use crate::fmi::package::{build_fmu, default_library};
use crate::fmi::xml::model_description;
use crate::{Error, Result};
use clap::{Args, Subcommand};
use std::path::PathBuf;

/// Arguments of `torso fmu`.
#[derive(Args, Debug)]
pub struct FmuArgs {
    /// What to do.
    #[command(subcommand)]
    pub command: FmuCommand,
}

/// Subcommands of `torso fmu`.
#[derive(Subcommand, Debug)]
pub enum FmuCommand {
    /// Write BreathingTorso.fmu (model description, shared library, resources, documentation).
    Build {
        /// Where to write the FMU.
        #[arg(long, default_value = "fmu/BreathingTorso.fmu")]
        out: PathBuf,
        /// The cdylib to package (default: the newer of the one beside this executable,
        /// written by `cargo build --release`, and the one in its deps/ folder, refreshed by
        /// `cargo run` and `cargo test`).
        #[arg(long)]
        lib: Option<PathBuf>,
        /// A folder copied into the FMU's resources/.
        #[arg(long)]
        resources: Option<PathBuf>,
    },
    /// Write modelDescription.xml (generated from the variable table).
    ModelDescription {
        /// Where to write it.
        #[arg(long, default_value = "modelDescription.xml")]
        out: PathBuf,
    },
}

/// Runs `torso fmu ...`.
pub fn run(args: FmuArgs) -> Result<()> {
    match args.command {
        FmuCommand::Build {
            out,
            lib,
            resources,
        } => {
            let lib = match lib {
                Some(l) => l,
                None => default_library()?,
            };
            let p = build_fmu(&lib, resources.as_deref(), &out)?;
            println!(
                "wrote {} ({} bytes): {}",
                p.path.display(),
                p.bytes,
                p.entries.join(", ")
            );
            Ok(())
        }
        FmuCommand::ModelDescription { out } => {
            std::fs::write(&out, model_description()).map_err(|e| Error::io(&out, e))?;
            println!("wrote {}", out.display());
            Ok(())
        }
    }
}
