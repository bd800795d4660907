//! `torso fmu`: packages the FMI 2.0 co-simulation FMU and writes its model description.

use crate::fmi::package::{Binary, build_fmu_for, default_library, has_debug_info};
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
        /// A library for another platform, as PLATFORM=PATH (linux64, win64, ...); may be
        /// repeated. Without --lib, only these are packaged. `scripts/deploy.sh` packages the
        /// stripped linux64 (glibc 2.17) and win64 builds this way.
        #[arg(long = "binary", value_name = "PLATFORM=PATH")]
        binaries: Vec<String>,
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
            binaries,
            resources,
        } => {
            let mut packaged = Vec::new();
            match lib {
                Some(l) => packaged.push(Binary::host(&l)),
                None if binaries.is_empty() => packaged.push(Binary::host(&default_library()?)),
                None => {}
            }
            for b in &binaries {
                packaged.push(Binary::parse(b)?);
            }
            for b in &packaged {
                // A missing file is reported by the packager, with how to build it.
                if let Ok(bytes) = std::fs::read(&b.path)
                    && has_debug_info(&bytes) == Some(true)
                {
                    println!(
                        "note: {} carries debug information ({} bytes); `bash scripts/deploy.sh` packages stripped builds",
                        b.path.display(),
                        bytes.len()
                    );
                }
            }
            let p = build_fmu_for(&packaged, resources.as_deref(), &out)?;
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
