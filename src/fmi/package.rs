//! Packaging of `BreathingTorso.fmu`: a zip with `modelDescription.xml` at its root, the
//! shared library as `binaries/<platform>/BreathingTorso.<ext>` (no `lib` prefix),
//! `resources/` (files the model reads at run time, if any) and `documentation/index.html`.
//! Entries are written in a fixed order with a fixed timestamp, so the same inputs give the
//! same archive.

use super::variables::MODEL_IDENTIFIER;
use super::xml::{documentation_html, model_description};
use crate::{Error, Result};
use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};
use zip::write::SimpleFileOptions;
use zip::{CompressionMethod, DateTime, ZipWriter};

/// FMI platform folder and shared-library extension of the platform this crate is built for.
pub fn platform() -> (&'static str, &'static str) {
    if cfg!(all(target_os = "linux", target_pointer_width = "64")) {
        ("linux64", "so")
    } else if cfg!(target_os = "linux") {
        ("linux32", "so")
    } else if cfg!(target_os = "macos") {
        ("darwin64", "dylib")
    } else if cfg!(all(windows, target_pointer_width = "64")) {
        ("win64", "dll")
    } else {
        ("win32", "dll")
    }
}

/// File name of the cdylib as cargo writes it (`libbreathing_torso.so` on Linux).
pub fn cargo_library_name() -> String {
    let (_, ext) = platform();
    if cfg!(windows) {
        format!("breathing_torso.{ext}")
    } else {
        format!("libbreathing_torso.{ext}")
    }
}

/// The cdylib built with the running executable: the newer of the one beside it
/// (`target/release/libbreathing_torso.so`, which `cargo build` writes) and the one in its
/// `deps/` folder (which `cargo run` and `cargo test` refresh without copying it up); see
/// [`newest_library`].
pub fn default_library() -> Result<PathBuf> {
    let exe = std::env::current_exe().map_err(|e| Error::io("current executable", e))?;
    let dir = exe
        .parent()
        .ok_or_else(|| Error::State("the executable has no folder".into()))?;
    Ok(newest_library(dir))
}

/// The newer (by modification time) of `dir/<library>` and `dir/deps/<library>`, the first
/// when neither exists (so that an error names where it was looked for).
///
/// Building only the executable (`cargo run --release -- demo`, `cargo test`) compiles the
/// library as both rlib and cdylib but leaves the cdylib in `deps/`; a
/// `libbreathing_torso.so` beside the executable may then be older than the code the
/// executable runs, and an FMU packaged from it would disagree with the command-line tool.
pub fn newest_library(dir: &Path) -> PathBuf {
    let name = cargo_library_name();
    let beside = dir.join(&name);
    let deps = dir.join("deps").join(&name);
    let modified = |p: &Path| fs::metadata(p).and_then(|m| m.modified()).ok();
    match (modified(&beside), modified(&deps)) {
        (Some(a), Some(b)) if b > a => deps,
        (None, Some(_)) => deps,
        _ => beside,
    }
}

/// What [`build_fmu`] wrote.
#[derive(Clone, Debug)]
pub struct Packaged {
    /// The `.fmu` written.
    pub path: PathBuf,
    /// Its entries, in order.
    pub entries: Vec<String>,
    /// Its size in bytes.
    pub bytes: u64,
}

/// Writes the FMU to `out` from the shared library `library` and the optional folder
/// `resources` (copied into `resources/`, recursively).
pub fn build_fmu(library: &Path, resources: Option<&Path>, out: &Path) -> Result<Packaged> {
    let lib = fs::read(library).map_err(|e| {
        Error::io(
            library,
            std::io::Error::new(
                e.kind(),
                format!("{e} (build it first: cargo build --release --lib)"),
            ),
        )
    })?;
    if let Some(dir) = out.parent().filter(|d| !d.as_os_str().is_empty()) {
        fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    }
    let file = fs::File::create(out).map_err(|e| Error::io(out, e))?;
    let zip_err = |e: zip::result::ZipError| Error::io(out, std::io::Error::other(e.to_string()));
    let io_err = |e: std::io::Error| Error::io(out, e);
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
        zip.write_all(data).map_err(io_err)?;
        entries.push(name);
        Ok(())
    };
    add(
        &mut zip,
        &mut entries,
        "modelDescription.xml".into(),
        model_description().as_bytes(),
        0o644,
    )?;
    let (platform, ext) = platform();
    add(
        &mut zip,
        &mut entries,
        format!("binaries/{platform}/{MODEL_IDENTIFIER}.{ext}"),
        &lib,
        0o755,
    )?;
    add(
        &mut zip,
        &mut entries,
        "documentation/index.html".into(),
        documentation_html().as_bytes(),
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

/// Files under `dir`, as (path relative to `root` with forward slashes, full path).
fn collect_files(root: &Path, dir: &Path, out: &mut Vec<(String, PathBuf)>) -> Result<()> {
    for entry in fs::read_dir(dir).map_err(|e| Error::io(dir, e))? {
        let path = entry.map_err(|e| Error::io(dir, e))?.path();
        if path.is_dir() {
            collect_files(root, &path, out)?;
        } else {
            let rel = path.strip_prefix(root).unwrap_or(&path);
            let rel: Vec<String> = rel
                .components()
                .map(|c| c.as_os_str().to_string_lossy().into_owned())
                .collect();
            out.push((rel.join("/"), path));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::{Duration, SystemTime};

    fn touch(path: &Path, at: SystemTime) {
        fs::create_dir_all(path.parent().unwrap()).unwrap();
        let f = fs::File::create(path).unwrap();
        f.set_modified(at).unwrap();
    }

    #[test]
    fn the_newer_of_the_two_cargo_libraries_is_packaged() {
        let dir = std::env::temp_dir().join(format!("bt_newest_library_{}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        let name = cargo_library_name();
        let (beside, deps) = (dir.join(&name), dir.join("deps").join(&name));
        // neither: the error will name the one beside the executable
        assert_eq!(newest_library(&dir), beside);
        let t0 = SystemTime::UNIX_EPOCH + Duration::from_secs(1_800_000_000);
        touch(&deps, t0);
        assert_eq!(newest_library(&dir), deps, "only in deps/");
        touch(&beside, t0 + Duration::from_secs(60));
        assert_eq!(newest_library(&dir), beside, "beside is newer");
        touch(&deps, t0 + Duration::from_secs(120));
        assert_eq!(newest_library(&dir), deps, "deps/ is newer");
        fs::remove_dir_all(&dir).unwrap();
    }
}
