//! Packaging of `BreathingTorso.fmu`: a zip with `modelDescription.xml` at its root, one
//! shared library per platform as `binaries/<platform>/BreathingTorso.<ext>` (no `lib`
//! prefix), `resources/` (files the model reads at run time, if any) and
//! `documentation/index.html`. Entries are written in a fixed order with a fixed timestamp, so
//! the same inputs give the same archive. Each library is checked to be a binary of its
//! platform's format (ELF, PE or Mach-O) before it is packaged.

use super::variables::{MODEL_IDENTIFIER, Table, table};
use super::xml::{documentation_html_for, model_description_for};
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

/// FMI platform folders this packager knows, with their library extension and the
/// executable format their binaries must have.
pub const PLATFORMS: [(&str, &str, BinaryFormat); 5] = [
    ("linux64", "so", BinaryFormat::Elf64),
    ("linux32", "so", BinaryFormat::Elf32),
    ("win64", "dll", BinaryFormat::Pe),
    ("win32", "dll", BinaryFormat::Pe),
    ("darwin64", "dylib", BinaryFormat::MachO),
];

/// Executable file formats, told apart by their first bytes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BinaryFormat {
    /// 64-bit ELF (Linux).
    Elf64,
    /// 32-bit ELF (Linux).
    Elf32,
    /// PE/COFF (Windows; 32 or 64 bit).
    Pe,
    /// Mach-O (macOS; 64-bit or universal).
    MachO,
}

impl BinaryFormat {
    /// The format of `bytes`, if it is one of these.
    pub fn of(bytes: &[u8]) -> Option<BinaryFormat> {
        match bytes {
            [0x7f, b'E', b'L', b'F', 2, ..] => Some(BinaryFormat::Elf64),
            [0x7f, b'E', b'L', b'F', 1, ..] => Some(BinaryFormat::Elf32),
            [b'M', b'Z', ..] => Some(BinaryFormat::Pe),
            [0xcf, 0xfa, 0xed, 0xfe, ..] | [0xca, 0xfe, 0xba, 0xbe, ..] => {
                Some(BinaryFormat::MachO)
            }
            _ => None,
        }
    }
}

/// One shared library to package: the FMI platform folder it goes to and the file.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Binary {
    /// FMI platform folder (`linux64`, `win64`, ...).
    pub platform: String,
    /// The library file.
    pub path: PathBuf,
}

impl Binary {
    /// The library built for the platform this crate runs on.
    pub fn host(path: &Path) -> Binary {
        Binary {
            platform: platform().0.to_string(),
            path: path.to_path_buf(),
        }
    }

    /// Parses `PLATFORM=PATH` (the `torso fmu build --binary` syntax).
    pub fn parse(text: &str) -> Result<Binary> {
        let (platform, path) = text.split_once('=').ok_or_else(|| {
            Error::invalid(
                "--binary",
                text,
                "PLATFORM=PATH, e.g. win64=breathing_torso.dll",
            )
        })?;
        if !PLATFORMS.iter().any(|p| p.0 == platform) {
            let known: Vec<&str> = PLATFORMS.iter().map(|p| p.0).collect();
            return Err(Error::invalid(
                "--binary",
                text,
                format!("a platform among {}", known.join(", ")),
            ));
        }
        Ok(Binary {
            platform: platform.to_string(),
            path: PathBuf::from(path),
        })
    }
}

/// Whether a shared library still carries debug information: a section whose name starts
/// with `.debug` or `.zdebug` (DWARF, in ELF and in mingw's PE files). `None` when the file is
/// neither a 64-bit ELF nor a PE file, or its section table cannot be read.
pub fn has_debug_info(bytes: &[u8]) -> Option<bool> {
    let names = match BinaryFormat::of(bytes)? {
        BinaryFormat::Elf64 => elf64_section_names(bytes)?,
        BinaryFormat::Pe => pe_section_names(bytes)?,
        _ => return None,
    };
    Some(
        names
            .iter()
            .any(|n| n.starts_with(".debug") || n.starts_with(".zdebug")),
    )
}

fn u16_at(b: &[u8], at: usize) -> Option<usize> {
    Some(u16::from_le_bytes(b.get(at..at + 2)?.try_into().ok()?).into())
}

fn u32_at(b: &[u8], at: usize) -> Option<usize> {
    usize::try_from(u32::from_le_bytes(b.get(at..at + 4)?.try_into().ok()?)).ok()
}

fn u64_at(b: &[u8], at: usize) -> Option<usize> {
    usize::try_from(u64::from_le_bytes(b.get(at..at + 8)?.try_into().ok()?)).ok()
}

/// A NUL-terminated name at `at`.
fn c_name(b: &[u8], at: usize) -> Option<String> {
    let rest = b.get(at..)?;
    let end = rest.iter().position(|&c| c == 0)?;
    Some(String::from_utf8_lossy(&rest[..end]).into_owned())
}

/// Section names of a little-endian 64-bit ELF file (System V ABI section header table).
fn elf64_section_names(b: &[u8]) -> Option<Vec<String>> {
    if b.get(5) != Some(&1) {
        return None; // big-endian
    }
    let (shoff, shentsize) = (u64_at(b, 0x28)?, u16_at(b, 0x3a)?);
    let (shnum, shstrndx) = (u16_at(b, 0x3c)?, u16_at(b, 0x3e)?);
    let header = |i: usize| shoff.checked_add(i.checked_mul(shentsize)?);
    let strtab = u64_at(b, header(shstrndx)? + 0x18)?;
    (0..shnum)
        .map(|i| c_name(b, strtab.checked_add(u32_at(b, header(i)?)?)?))
        .collect()
}

/// Section names of a PE file: 8-byte names, or `/offset` into the COFF string table for
/// longer ones (as mingw writes `.debug_info`).
fn pe_section_names(b: &[u8]) -> Option<Vec<String>> {
    let pe = u32_at(b, 0x3c)?;
    if b.get(pe..pe + 4)? != b"PE\0\0" {
        return None;
    }
    let coff = pe + 4;
    let sections = u16_at(b, coff + 2)?;
    let strings = u32_at(b, coff + 8)?.checked_add(u32_at(b, coff + 12)?.checked_mul(18)?)?;
    let table = coff + 20 + u16_at(b, coff + 16)?;
    (0..sections)
        .map(|i| {
            let raw = b.get(table + 40 * i..table + 40 * i + 8)?;
            let short = String::from_utf8_lossy(raw)
                .trim_end_matches('\0')
                .to_string();
            match short.strip_prefix('/') {
                Some(offset) => c_name(b, strings.checked_add(offset.parse().ok()?)?),
                None => Some(short),
            }
        })
        .collect()
}

/// Writes the FMU to `out` from the shared library `library` (built for the platform this
/// crate runs on) and the optional folder `resources` (copied into `resources/`,
/// recursively).
pub fn build_fmu(library: &Path, resources: Option<&Path>, out: &Path) -> Result<Packaged> {
    build_fmu_for(&[Binary::host(library)], resources, out)
}

/// Writes the FMU to `out` with one shared library per platform (at least one, each platform
/// once, each file of its platform's format) and the optional folder `resources`.
pub fn build_fmu_for(
    binaries: &[Binary],
    resources: Option<&Path>,
    out: &Path,
) -> Result<Packaged> {
    build_fmu_with(binaries, resources, out, table(), &[])
}

/// Reads and checks the shared libraries of an FMU: at least one, each platform known
/// ([`PLATFORMS`]) and given once, each file of its platform's executable format. Returns
/// the zip entries `binaries/<folder>/BreathingTorso.<ext>` with their bytes, `folder`
/// naming a platform's folder (FMI 2.0: the platform itself; FMI 3.0: its platform tuple;
/// `None`: a platform the FMI version has no folder for).
pub(crate) fn read_binaries(
    binaries: &[Binary],
    folder: &dyn Fn(&str) -> Option<String>,
) -> Result<Vec<(String, Vec<u8>)>> {
    if binaries.is_empty() {
        return Err(Error::State("an FMU needs at least one binary".into()));
    }
    let known = || PLATFORMS.iter().map(|p| p.0).collect::<Vec<_>>().join(", ");
    let mut libraries = Vec::with_capacity(binaries.len());
    for (i, b) in binaries.iter().enumerate() {
        let Some((&(platform, ext, format), dir)) = PLATFORMS
            .iter()
            .find(|p| p.0 == b.platform)
            .and_then(|p| folder(p.0).map(|d| (p, d)))
        else {
            return Err(Error::invalid(
                "platform",
                &b.platform,
                format!("one of {}", known()),
            ));
        };
        if binaries[..i].iter().any(|o| o.platform == b.platform) {
            return Err(Error::State(format!(
                "platform {platform} is given twice; an FMU has one binary per platform"
            )));
        }
        let lib = fs::read(&b.path).map_err(|e| {
            Error::io(
                &b.path,
                std::io::Error::new(
                    e.kind(),
                    format!("{e} (build it first: cargo build --release --lib)"),
                ),
            )
        })?;
        let found = BinaryFormat::of(&lib);
        if found != Some(format) {
            return Err(Error::State(format!(
                "{} is {}, not a {platform} shared library ({format:?})",
                b.path.display(),
                found.map_or("no executable format".to_string(), |f| format!("{f:?}"))
            )));
        }
        libraries.push((format!("binaries/{dir}/{MODEL_IDENTIFIER}.{ext}"), lib));
    }
    Ok(libraries)
}

/// Writes the FMU whose variables are `table` (the generic one or a personalised one) to
/// `out`, as [`build_fmu_for`] does, with the `extra` entries (full entry name, content):
/// those under `documentation/` follow `documentation/index.html`, those under
/// `resources/` follow the folder `resources`' files. Any other name is refused.
pub fn build_fmu_with(
    binaries: &[Binary],
    resources: Option<&Path>,
    out: &Path,
    table: &Table,
    extra: &[(String, Vec<u8>)],
) -> Result<Packaged> {
    if let Some((name, _)) = extra
        .iter()
        .find(|(n, _)| !(n.starts_with("documentation/") || n.starts_with("resources/")))
    {
        return Err(Error::invalid(
            "FMU entry",
            name,
            "a file under documentation/ or resources/",
        ));
    }
    let libraries = read_binaries(binaries, &|platform| Some(platform.to_string()))?;
    let mut zip = Archive::create(out)?;
    zip.add(
        "modelDescription.xml",
        model_description_for(table).as_bytes(),
        0o644,
    )?;
    for (name, lib) in &libraries {
        zip.add(name, lib, 0o755)?;
    }
    zip.add(
        "documentation/index.html",
        documentation_html_for(table).as_bytes(),
        0o644,
    )?;
    for (name, data) in extra
        .iter()
        .filter(|(n, _)| n.starts_with("documentation/"))
    {
        zip.add(name, data, 0o644)?;
    }
    zip.add_resources(resources)?;
    for (name, data) in extra.iter().filter(|(n, _)| n.starts_with("resources/")) {
        if zip.contains(name) {
            return Err(Error::State(format!(
                "{name} is given twice (the --resources folder has a file of that name)"
            )));
        }
        zip.add(name, data, 0o644)?;
    }
    zip.finish()
}

/// An FMU archive being written, the same way for both FMI versions: entries in the order
/// they are added, deflated, with a fixed timestamp (so that the same inputs give the same
/// archive) and the given Unix mode.
pub(crate) struct Archive {
    zip: ZipWriter<fs::File>,
    out: PathBuf,
    options: SimpleFileOptions,
    entries: Vec<String>,
}

impl Archive {
    /// Creates `out` (and its folder).
    pub(crate) fn create(out: &Path) -> Result<Archive> {
        if let Some(dir) = out.parent().filter(|d| !d.as_os_str().is_empty()) {
            fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
        }
        let file = fs::File::create(out).map_err(|e| Error::io(out, e))?;
        Ok(Archive {
            zip: ZipWriter::new(file),
            out: out.to_path_buf(),
            options: SimpleFileOptions::default()
                .compression_method(CompressionMethod::Deflated)
                .last_modified_time(DateTime::default())
                .unix_permissions(0o644),
            entries: Vec::new(),
        })
    }

    fn zip_err(&self, e: zip::result::ZipError) -> Error {
        Error::io(&self.out, std::io::Error::other(e.to_string()))
    }

    /// Adds the file `name` with `data` and Unix mode `mode`.
    pub(crate) fn add(&mut self, name: &str, data: &[u8], mode: u32) -> Result<()> {
        let options = self.options.unix_permissions(mode);
        self.zip
            .start_file(name, options)
            .map_err(|e| self.zip_err(e))?;
        self.zip
            .write_all(data)
            .map_err(|e| Error::io(&self.out, e))?;
        self.entries.push(name.to_string());
        Ok(())
    }

    /// Adds the folder `resources/`, then the files of `dir`, if any, under it (recursively,
    /// in the order of their relative paths).
    pub(crate) fn add_resources(&mut self, dir: Option<&Path>) -> Result<()> {
        self.zip
            .add_directory("resources/", self.options)
            .map_err(|e| self.zip_err(e))?;
        self.entries.push("resources/".into());
        if let Some(dir) = dir {
            let mut files = Vec::new();
            collect_files(dir, dir, &mut files)?;
            files.sort();
            for (rel, path) in files {
                let data = fs::read(&path).map_err(|e| Error::io(&path, e))?;
                self.add(&format!("resources/{rel}"), &data, 0o644)?;
            }
        }
        Ok(())
    }

    /// Whether an entry `name` was added.
    pub(crate) fn contains(&self, name: &str) -> bool {
        self.entries.iter().any(|e| e == name)
    }

    /// Finishes the archive: its path, entries and size.
    pub(crate) fn finish(self) -> Result<Packaged> {
        let Archive {
            zip, out, entries, ..
        } = self;
        zip.finish()
            .map_err(|e| Error::io(&out, std::io::Error::other(e.to_string())))?;
        let bytes = fs::metadata(&out).map_err(|e| Error::io(&out, e))?.len();
        Ok(Packaged {
            path: out,
            entries,
            bytes,
        })
    }
}

/// Files under `dir`, as (path relative to `root` with forward slashes, full path).
pub(crate) fn collect_files(
    root: &Path,
    dir: &Path,
    out: &mut Vec<(String, PathBuf)>,
) -> Result<()> {
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

    /// A minimal 64-bit ELF file whose sections are named `names` (plus `.shstrtab`).
    fn elf_with_sections(names: &[&str]) -> Vec<u8> {
        let mut strtab = vec![0u8];
        let mut offsets = Vec::new();
        for n in names.iter().chain([&".shstrtab"]) {
            offsets.push(strtab.len() as u32);
            strtab.extend_from_slice(n.as_bytes());
            strtab.push(0);
        }
        let shoff = 64 + strtab.len();
        let mut b = vec![0u8; 64];
        b[..6].copy_from_slice(b"\x7fELF\x02\x01");
        b[0x28..0x30].copy_from_slice(&(shoff as u64).to_le_bytes());
        b[0x3a..0x3c].copy_from_slice(&64u16.to_le_bytes());
        b[0x3c..0x3e].copy_from_slice(&(offsets.len() as u16).to_le_bytes());
        b[0x3e..0x40].copy_from_slice(&(names.len() as u16).to_le_bytes());
        b.extend_from_slice(&strtab);
        for o in offsets {
            let mut h = [0u8; 64];
            h[..4].copy_from_slice(&o.to_le_bytes());
            h[0x18..0x20].copy_from_slice(&64u64.to_le_bytes());
            b.extend_from_slice(&h);
        }
        b
    }

    #[test]
    fn debug_sections_are_found_by_name() {
        let debug = elf_with_sections(&[".text", ".debug_info", ".debug_line"]);
        assert_eq!(has_debug_info(&debug), Some(true));
        // The name alone in the data (as std's backtrace code holds it) is not a section.
        let mut stripped = elf_with_sections(&[".text", ".rodata"]);
        stripped.extend_from_slice(b".debug_info\0");
        assert_eq!(has_debug_info(&stripped), Some(false));
        // The library this test links: built with the release profile's debug info, if any.
        if let Ok(lib) = fs::read(default_library().unwrap()) {
            let names = elf64_section_names(&lib).unwrap_or_default();
            assert!(names.iter().any(|n| n == ".text"), "{names:?}");
        }
    }

    #[test]
    fn binaries_are_checked_against_their_platform() {
        assert_eq!(
            Binary::parse("win64=a/b.dll").unwrap(),
            Binary {
                platform: "win64".into(),
                path: "a/b.dll".into()
            }
        );
        for bad in ["win64", "win65=a.dll"] {
            let e = Binary::parse(bad).unwrap_err().to_string();
            assert!(e.contains("--binary") && e.contains(bad), "{e}");
        }
        let dir = std::env::temp_dir().join(format!("bt_binaries_{}", std::process::id()));
        fs::create_dir_all(&dir).unwrap();
        let elf = dir.join("lib.so");
        fs::write(&elf, b"\x7fELF\x02\x01\x01rest").unwrap();
        let pe = dir.join("lib.dll");
        fs::write(&pe, b"MZ\x90\x00rest").unwrap();
        let out = dir.join("t.fmu");
        let b = |p: &str, f: &Path| Binary {
            platform: p.into(),
            path: f.to_path_buf(),
        };
        let p = build_fmu_for(&[b("linux64", &elf), b("win64", &pe)], None, &out).unwrap();
        assert!(
            p.entries
                .contains(&"binaries/linux64/BreathingTorso.so".to_string())
        );
        assert!(
            p.entries
                .contains(&"binaries/win64/BreathingTorso.dll".to_string())
        );
        let e = build_fmu_for(&[b("win64", &elf)], None, &out).unwrap_err();
        assert!(e.to_string().contains("not a win64 shared library"), "{e}");
        let e = build_fmu_for(&[b("linux64", &elf), b("linux64", &elf)], None, &out);
        assert!(e.unwrap_err().to_string().contains("twice"));
        assert!(build_fmu_for(&[], None, &out).is_err());
        assert_eq!(has_debug_info(&fs::read(&elf).unwrap()), None, "truncated");
        assert_eq!(has_debug_info(b"..\0.debug_info\0.."), None, "not a binary");
        fs::remove_dir_all(&dir).unwrap();
    }
}
