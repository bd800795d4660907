//! `torso fmu`: packages the FMI 2.0 or FMI 3.0 co-simulation FMU and writes the FMI 2.0 model
//! description.

use crate::fmi::fmi3::package::build_fmu3_for;
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
        /// Where to write the FMU (default: fmu/BreathingTorso.fmu, with --fmi-version 3
        /// fmu/BreathingTorso3.fmu, with --subject FIT.json fmu/FIT.fmu).
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
            fmi_version,
        } => {
            // A personalised FMU is named after its fit result, so that it never replaces the
            // generic FMU by default.
            let out = out.unwrap_or_else(|| match (&subject, fmi_version) {
                (Some(fit), _) => PathBuf::from("fmu").join(
                    fit.with_extension("fmu")
                        .file_name()
                        .unwrap_or(std::ffi::OsStr::new("Subject.fmu")),
                ),
                (None, 3) => PathBuf::from("fmu/BreathingTorso3.fmu"),
                (None, _) => PathBuf::from("fmu/BreathingTorso.fmu"),
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
            let Some(fit) = subject else {
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
                return Ok(());
            };
            if fmi_version == 3 {
                return Err(Error::invalid(
                    "--fmi-version",
                    "3 with --subject",
                    "2: personalised FMUs are FMI 2.0 FMUs (the FMI 3.0 FMU is generic)",
                ));
            }
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
