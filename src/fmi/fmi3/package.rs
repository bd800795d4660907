//! Packaging of `BreathingTorso3.fmu`, the FMI 3.0 co-simulation FMU: `modelDescription.xml`
//! (FMI 3.0), one shared library per platform as
//! `binaries/<platform tuple>/BreathingTorso.<ext>` (the same library as the FMI 2.0 FMU's,
//! which exports both interfaces), `terminalsAndIcons/terminalsAndIcons.xml` and
//! `resources/`. The archive is written by the FMI 2.0 packager's [`Archive`] (a fixed order
//! and timestamp) from libraries checked by the same [`read_binaries`].

use super::xml::{TERMINALS_PATH, model_description, terminals_and_icons};
use crate::Result;
use crate::fmi::package::{Archive, Binary, Packaged, read_binaries};
use std::path::Path;

/// FMI 3.0 platform tuple of an FMI 2.0 platform folder (`linux64` -> `x86_64-linux`).
/// `darwin64` is taken as Intel (`x86_64-darwin`).
pub fn platform_tuple(platform: &str) -> Option<&'static str> {
    match platform {
        "linux64" => Some("x86_64-linux"),
        "linux32" => Some("x86-linux"),
        "win64" => Some("x86_64-windows"),
        "win32" => Some("x86-windows"),
        "darwin64" => Some("x86_64-darwin"),
        _ => None,
    }
}

/// Writes the FMI 3.0 FMU with `binaries` (platforms named as for FMI 2.0: `linux64`,
/// `win64`, ...) and the files of `resources`, if any, under `resources/`.
pub fn build_fmu3_for(
    binaries: &[Binary],
    resources: Option<&Path>,
    out: &Path,
) -> Result<Packaged> {
    let libraries = read_binaries(binaries, &|platform| {
        platform_tuple(platform).map(str::to_string)
    })?;
    let mut zip = Archive::create(out)?;
    zip.add(
        "modelDescription.xml",
        model_description().as_bytes(),
        0o644,
    )?;
    for (name, lib) in &libraries {
        zip.add(name, lib, 0o755)?;
    }
    zip.add(TERMINALS_PATH, terminals_and_icons().as_bytes(), 0o644)?;
    zip.add_resources(resources)?;
    zip.finish()
}
