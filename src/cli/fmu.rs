//! `torso fmu`: packages the FMI 2.0 or FMI 3.0 co-simulation FMU and writes the FMI 2.0 model
//! description.

use crate::fmi::fmi3::package::build_fmu3_for;
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
        /// Where to write the FMU (default: fmu/BreathingTorso.fmu, with --fmi-version 3
        /// fmu/BreathingTorso3.fmu).
        #[arg(long)]
        out: Option<PathBuf>,
        /// FMI version of the FMU: 2 or 3 (the same library exports both interfaces).
        #[arg(long = "fmi-version", default_value_t = 2, value_parser = clap::value_parser!(u8).range(2..=3))]
        fmi_version: u8,
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
            fmi_version,
        } => {
            let out = out.unwrap_or_else(|| match fmi_version {
                3 => PathBuf::from("fmu/BreathingTorso3.fmu"),
                _ => PathBuf::from("fmu/BreathingTorso.fmu"),
            });
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
            let p = match fmi_version {
                3 => build_fmu3_for(&packaged, resources.as_deref(), &out)?,
                _ => build_fmu_for(&packaged, resources.as_deref(), &out)?,
            };
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
