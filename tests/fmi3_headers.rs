//! The exported FMI 3.0 functions, as cbindgen reads them from `src/fmi/fmi3/ffi.rs` and
//! `src/fmi/fmi3/types.rs`, are declared in one translation unit after the official FMI 3.0
//! headers (shipped in the fmpy wheel, `fmpy/c-code/`): a parameter or return type that
//! differs from the standard's is a "conflicting types" error, a typedef redefined with another
//! type is an error, and the values and size of `fmi3Status` are checked with static
//! assertions generated from the Rust definition. The TU also takes the address of every
//! function through the standard's `fmi3XxxTYPE` function types.
//!
//! Every function of the header is exported (importers such as fmpy resolve them all when
//! they load the library); those this FMU does not provide return `fmi3Error` with a log line.
//! Those are written one line each, as invocations of the `not_provided!` and
//! `no_variables!` macros, which cbindgen does not expand: [`macro_declarations`] writes out
//! the function each line declares (the macros' fixed leading parameters, then the line's),
//! and cbindgen reads those too.

use breathing_torso::fmi::fmi3::types::fmi3Status;
use std::mem::size_of;
use std::path::PathBuf;
use std::process::Command;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// `fmpy/c-code` inside the project's venv (made by scripts/python-env.sh).
fn official_headers() -> Option<PathBuf> {
    let lib = root().join(".venv/lib");
    let entries = std::fs::read_dir(&lib).ok()?;
    entries
        .filter_map(|e| e.ok())
        .map(|e| e.path().join("site-packages/fmpy/c-code"))
        .find(|p| p.join("fmi3Functions.h").is_file())
}

/// Function names declared by the official `fmi3Functions.h`.
fn official_function_names(dir: &std::path::Path) -> Vec<String> {
    let text = std::fs::read_to_string(dir.join("fmi3Functions.h")).unwrap();
    let mut all: Vec<String> = text
        .lines()
        .filter_map(|l| l.trim().strip_prefix("FMI3_Export"))
        .filter_map(|rest| rest.split_whitespace().nth(1))
        .map(|n| n.trim_end_matches(';').to_string())
        .collect();
    all.sort();
    all.dedup();
    all
}

/// The exported functions declared one line each through the `not_provided!` and
/// `no_variables!` macros of `src/fmi/fmi3/ffi.rs`, written out as Rust functions with the
/// signatures the macros give them: `not_provided!` puts `instance: fmi3Instance` first,
/// `no_variables!` also the value references and their count.
fn macro_declarations() -> String {
    let source = std::fs::read_to_string(root().join("src/fmi/fmi3/ffi.rs")).unwrap();
    let mut out = String::from("use super::types::*;\n");
    let mut leading = None;
    let mut count = 0;
    for line in source.lines() {
        let line = line.trim();
        if line == "not_provided! {" {
            leading = Some("instance: fmi3Instance");
            continue;
        }
        if line == "no_variables! {" {
            leading = Some(
                "instance: fmi3Instance, valueReferences: *const fmi3ValueReference, \
                 nValueReferences: usize",
            );
            continue;
        }
        let Some(first) = leading else { continue };
        if line == "}" {
            leading = None;
            continue;
        }
        let (name, rest) = line
            .split_once('(')
            .expect("a macro line: name(arguments) => ...");
        let (arguments, _) = rest
            .split_once(") =>")
            .expect("a macro line: name(arguments) => ...");
        let arguments = if arguments.is_empty() {
            first.to_string()
        } else {
            format!("{first}, {arguments}")
        };
        out.push_str(&format!(
            "#[unsafe(no_mangle)]\npub unsafe extern \"C\" fn {name}({arguments}) -> fmi3Status {{}}\n"
        ));
        count += 1;
    }
    assert!(
        count > 40,
        "{count} macro-declared functions found in src/fmi/fmi3/ffi.rs"
    );
    out
}

fn generate_declarations() -> String {
    let mut config = cbindgen::Config {
        language: cbindgen::Language::C,
        no_includes: true,
        usize_is_size_t: true,
        ..Default::default()
    };
    // The enumerations come from the official headers (the status is asserted below); the
    // preemption callbacks are declared there without a prototype (`void (*)()`), which is
    // compatible with ours but not the same typedef.
    config.export.exclude = [
        "fmi3Status",
        "fmi3DependencyKind",
        "fmi3IntervalQualifier",
        "fmi3LockPreemptionCallback",
        "fmi3UnlockPreemptionCallback",
    ]
    .map(String::from)
    .to_vec();
    config.export.include = [
        "fmi3LogMessageCallback",
        "fmi3IntermediateUpdateCallback",
        "fmi3ClockUpdateCallback",
    ]
    .map(String::from)
    .to_vec();
    let expanded = std::env::temp_dir().join(format!("bt_fmi3_macros_{}.rs", std::process::id()));
    std::fs::write(&expanded, macro_declarations()).unwrap();
    let bindings = cbindgen::Builder::new()
        .with_config(config)
        .with_src(root().join("src/fmi/fmi3/types.rs"))
        .with_src(root().join("src/fmi/fmi3/ffi.rs"))
        .with_src(&expanded)
        .generate()
        .expect("cbindgen reads the FMI 3.0 sources");
    let mut out = Vec::new();
    bindings.write(&mut out);
    String::from_utf8(out).unwrap()
}

fn layout_assertions() -> String {
    use fmi3Status::*;
    let mut s = String::new();
    for (name, v) in [
        ("fmi3OK", fmi3OK),
        ("fmi3Warning", fmi3Warning),
        ("fmi3Discard", fmi3Discard),
        ("fmi3Error", fmi3Error),
        ("fmi3Fatal", fmi3Fatal),
    ] {
        s.push_str(&format!(
            "_Static_assert({name} == {}, \"{name}\");\n",
            v as i32
        ));
    }
    s.push_str(&format!(
        "_Static_assert(sizeof(fmi3Status) == {}, \"sizeof(fmi3Status)\");\n",
        size_of::<fmi3Status>()
    ));
    for e in ["fmi3DependencyKind", "fmi3IntervalQualifier"] {
        s.push_str(&format!(
            "_Static_assert(sizeof({e}) == {}, \"sizeof({e})\");\n",
            size_of::<std::os::raw::c_int>()
        ));
    }
    s
}

#[test]
fn exported_functions_match_the_official_fmi3_headers() {
    let Some(headers) = official_headers() else {
        println!(
            "SKIPPED: no .venv with fmpy (run scripts/python-env.sh, as scripts/test.sh does)"
        );
        return;
    };
    let names = official_function_names(&headers);
    // Every function of the FMI 3.0 header (common, model exchange, co-simulation,
    // scheduled execution).
    assert_eq!(names.len(), 75, "official header lists {names:?}");
    let decls = generate_declarations();
    for n in &names {
        assert!(
            decls.contains(&format!(" {n}(")) || decls.contains(&format!("*{n}(")),
            "{n} is not exported by src/fmi/fmi3/ffi.rs"
        );
    }
    let tmp = std::env::temp_dir().join(format!("bt_fmi3_{}", std::process::id()));
    std::fs::create_dir_all(&tmp).unwrap();
    std::fs::write(tmp.join("bt_fmi3_decls.h"), &decls).unwrap();
    let mut tu = String::from(
        "#include <stddef.h>\n#include \"fmi3Functions.h\"\n#include \"bt_fmi3_decls.h\"\n",
    );
    tu.push_str(&layout_assertions());
    tu.push_str("void *bt_fmi3_addresses[] = {\n");
    for n in &names {
        tu.push_str(&format!(
            "    (void *)(fmi3{}TYPE *){n},\n",
            n.trim_start_matches("fmi3")
        ));
    }
    tu.push_str("};\n");
    std::fs::write(tmp.join("tu.c"), &tu).unwrap();
    let out = Command::new("gcc")
        .args([
            "-std=c11",
            "-Wall",
            "-Wextra",
            "-Werror",
            "-Wno-pedantic",
            "-c",
            "-o",
        ])
        .arg(tmp.join("tu.o"))
        .arg("-I")
        .arg(&headers)
        .arg("-I")
        .arg(&tmp)
        .arg(tmp.join("tu.c"))
        .output()
        .expect("gcc runs");
    assert!(
        out.status.success(),
        "the exported functions do not match the official FMI 3.0 types:\n{}\n--- declarations ---\n{decls}",
        String::from_utf8_lossy(&out.stderr)
    );
}
