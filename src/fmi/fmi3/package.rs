//! Packaging of `BreathingTorso3.fmu`, the FMI 3.0 co-simulation FMU: `modelDescription.xml`
//! (FMI 3.0), one shared library per platform as
//! `binaries/<platform tuple>/BreathingTorso.<ext>` (the same library as the FMI 2.0 FMU's,
//! which exports both interfaces), `terminalsAndIcons/terminalsAndIcons.xml` and
//! `resources/`. Entries are written in a fixed order with a fixed timestamp, and each
//! library is checked to be a binary of its platform's format, as for the FMI 2.0 FMU.

use super::xml::{TERMINALS_PATH, model_description, terminals_and_icons};
use crate::fmi::package::{Binary, Packaged, collect_files, read_binaries};
use crate::{Error, Result};
use std::fs;
use std::io::Write;
use std::path::Path;
use zip::write::SimpleFileOptions;
use zip::{CompressionMethod, DateTime, ZipWriter};

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
    if let Some(dir) = out.parent().filter(|d| !d.as_os_str().is_empty()) {
        fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    }
    let file = fs::File::create(out).map_err(|e| Error::io(out, e))?;
    let zip_err = |e: zip::result::ZipError| Error::io(out, std::io::Error::other(e.to_string()));
    let options = SimpleFileOptions::default()
        .compression_method(CompressionMethod::Deflated)
        .last_modified_time(DateTime::default())
        .unix_permissions(0o644);
    let mut zip = ZipWriter::new(file);
    let mut entries = Vec::new();
    let add = |zip: &mut ZipWriter<fs::File>,
               entries: &mut Vec<String>,
               name: String,
               data: &[u8],
               mode: u32|
     -> Result<()> {
        zip.start_file(name.as_str(), options.unix_permissions(mode))
            .map_err(zip_err)?;
        zip.write_all(data).map_err(|e| Error::io(out, e))?;
        entries.push(name);
        Ok(())
    };
    let description = model_description();
    add(
        &mut zip,
        &mut entries,
        "modelDescription.xml".into(),
        description.as_bytes(),
        0o644,
    )?;
    for (name, lib) in &libraries {
        add(&mut zip, &mut entries, name.clone(), lib, 0o755)?;
    }
    let terminals = terminals_and_icons();
    add(
        &mut zip,
        &mut entries,
        TERMINALS_PATH.into(),
        terminals.as_bytes(),
        0o644,
    )?;
    zip.add_directory("resources/", options).map_err(zip_err)?;
    entries.push("resources/".into());
    if let Some(dir) = resources {
        let mut files = Vec::new();
        collect_files(dir, dir, &mut files)?;
        files.sort();
        for (rel, path) in files {
            let data = fs::read(&path).map_err(|e| Error::io(&path, e))?;
            add(
                &mut zip,
                &mut entries,
                format!("resources/{rel}"),
                &data,
                0o644,
            )?;
        }
    }
    zip.finish().map_err(zip_err)?;
    let bytes = fs::metadata(out).map_err(|e| Error::io(out, e))?.len();
    Ok(Packaged {
        path: out.to_path_buf(),
        entries,
        bytes,
    })
}
