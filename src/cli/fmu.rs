//! `torso fmu`: packages the FMI 2.0 co-simulation FMU and writes its model description.

use crate::fmi::package::{Binary, build_fmu_for, build_fmu_with, default_library, has_debug_info};
use crate::fmi::personal::from_fit_json;
use crate::fmi::ssv::write as write_ssv;
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
        /// A fit result (the JSON `torso fit` writes) to bake into the FMU: its subject, drive
        /// and model become the parameters' start values, its skin reference and mesh folder
        /// go to resources/subject/, its report to documentation/, and only its grid's
        /// markers are outputs (docs/fmi.md, "Personalised FMUs").
        #[arg(long)]
        subject: Option<PathBuf>,
        /// Where to write the SSP parameter set of --subject for the generic FMU (default:
        /// the FMU's path with the extension .ssv).
        #[arg(long, requires = "subject")]
        ssv: Option<PathBuf>,
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
            subject,
            ssv,
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
            let Some(fit) = subject else {
                let p = build_fmu_for(&packaged, resources.as_deref(), &out)?;
                println!(
                    "wrote {} ({} bytes): {}",
                    p.path.display(),
                    p.bytes,
                    p.entries.join(", ")
                );
                return Ok(());
            };
            let personal = from_fit_json(&fit)?;
            let table = personal.table()?;
            let p = build_fmu_with(
                &packaged,
                resources.as_deref(),
                &out,
                &table,
                &personal.entries,
            )?;
            let ssv = ssv.unwrap_or_else(|| out.with_extension("ssv"));
            let name = fit
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_else(|| "subject".into());
            std::fs::write(&ssv, write_ssv(&name, &personal.generic))
                .map_err(|e| Error::io(&ssv, e))?;
            println!(
                "wrote {} ({} bytes, GUID {}, {} parameters from {}): {}",
                p.path.display(),
                p.bytes,
                table.guid(),
                personal.personalisation.starts.len(),
                fit.display(),
                p.entries.join(", ")
            );
            println!(
                "wrote {} (the same parameters for the generic FMU)",
                ssv.display()
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
