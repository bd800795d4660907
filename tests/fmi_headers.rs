//! Our 34 exported FMI functions, as cbindgen reads them from `src/fmi/ffi.rs` and
//! `src/fmi/types.rs`, are declared in one translation unit after the official FMI 2.0 headers
//! (shipped in the fmpy wheel, `fmpy/c-code/`): a parameter or return type that differs from
//! the standard's is a "conflicting types" error, a typedef redefined with another type is an
//! error, and the layouts of the enums and of `fmi2CallbackFunctions` are checked with static
//! assertions generated from the Rust definitions. The TU also takes the address of every
//! function through the standard's `fmi2XxxTYPE` pointer types.

use breathing_torso::fmi::types::*;
use std::mem::{offset_of, size_of};
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
        .find(|p| p.join("fmi2Functions.h").is_file())
}

/// Functions of model exchange only (this FMU is co-simulation only).
const MODEL_EXCHANGE_ONLY: [&str; 10] = [
    "fmi2EnterEventMode",
    "fmi2NewDiscreteStates",
    "fmi2EnterContinuousTimeMode",
    "fmi2CompletedIntegratorStep",
    "fmi2SetTime",
    "fmi2SetContinuousStates",
    "fmi2GetDerivatives",
    "fmi2GetEventIndicators",
    "fmi2GetContinuousStates",
    "fmi2GetNominalsOfContinuousStates",
];

/// The 34 common and co-simulation function names, read from the official `fmi2Functions.h`.
fn official_function_names(dir: &std::path::Path) -> Vec<String> {
    let text = std::fs::read_to_string(dir.join("fmi2Functions.h")).unwrap();
    let mut names: Vec<String> = text
        .lines()
        .filter_map(|l| l.trim().strip_prefix("FMI2_Export"))
        .filter_map(|rest| rest.split_whitespace().nth(1))
        .map(|n| n.trim_end_matches(';').to_string())
        .filter(|n| !MODEL_EXCHANGE_ONLY.contains(&n.as_str()))
        .collect();
    names.sort();
    names.dedup();
    names
}

fn generate_declarations() -> String {
    let mut config = cbindgen::Config {
        language: cbindgen::Language::C,
        no_includes: true,
        usize_is_size_t: true,
        ..Default::default()
    };
    // Enumerations and the struct come from the official headers (their layouts are asserted
    // below); redefining them would clash even when equal.
    config.export.exclude = [
        "fmi2Status",
        "fmi2Type",
        "fmi2StatusKind",
        "fmi2CallbackFunctions",
        "fmi2ModelExchange",
        "fmi2CoSimulation",
        "fmi2DoStepStatus",
        "fmi2PendingStatus",
        "fmi2LastSuccessfulTime",
        "fmi2Terminated",
    ]
    .map(String::from)
    .to_vec();
    // The callback types are used only inside the struct: emit them so that they are checked
    // as typedef redefinitions too.
    config.export.include = [
        "fmi2CallbackLogger",
        "fmi2CallbackAllocateMemory",
        "fmi2CallbackFreeMemory",
        "fmi2StepFinished",
    ]
    .map(String::from)
    .to_vec();
    let bindings = cbindgen::Builder::new()
        .with_config(config)
        .with_src(root().join("src/fmi/types.rs"))
        .with_src(root().join("src/fmi/ffi.rs"))
        .generate()
        .expect("cbindgen reads the FMI sources");
    let mut out = Vec::new();
    bindings.write(&mut out);
    String::from_utf8(out).unwrap()
}

fn layout_assertions() -> String {
    use fmi2Status::*;
    let mut s = String::new();
    let mut a = |cond: String| {
        s.push_str(&format!(
            "_Static_assert({cond}, \"{}\");\n",
            cond.replace('"', "'")
        ))
    };
    for (name, v) in [
        ("fmi2OK", fmi2OK),
        ("fmi2Warning", fmi2Warning),
        ("fmi2Discard", fmi2Discard),
        ("fmi2Error", fmi2Error),
        ("fmi2Fatal", fmi2Fatal),
        ("fmi2Pending", fmi2Pending),
    ] {
        a(format!("{name} == {}", v as i32));
    }
    a(format!("sizeof(fmi2Status) == {}", size_of::<fmi2Status>()));
    a(format!("sizeof(fmi2Type) == {}", size_of::<fmi2Type>()));
    a(format!(
        "sizeof(fmi2StatusKind) == {}",
        size_of::<fmi2StatusKind>()
    ));
    for (name, v) in [
        ("fmi2ModelExchange", fmi2ModelExchange),
        ("fmi2CoSimulation", fmi2CoSimulation),
        ("fmi2DoStepStatus", fmi2DoStepStatus),
        ("fmi2PendingStatus", fmi2PendingStatus),
        ("fmi2LastSuccessfulTime", fmi2LastSuccessfulTime),
        ("fmi2Terminated", fmi2Terminated),
    ] {
        a(format!("{name} == {v}"));
    }
    a(format!(
        "sizeof(fmi2CallbackFunctions) == {}",
        size_of::<fmi2CallbackFunctions>()
    ));
    for (field, off) in [
        ("logger", offset_of!(fmi2CallbackFunctions, logger)),
        (
            "allocateMemory",
            offset_of!(fmi2CallbackFunctions, allocateMemory),
        ),
        ("freeMemory", offset_of!(fmi2CallbackFunctions, freeMemory)),
        (
            "stepFinished",
            offset_of!(fmi2CallbackFunctions, stepFinished),
        ),
        (
            "componentEnvironment",
            offset_of!(fmi2CallbackFunctions, componentEnvironment),
        ),
    ] {
        a(format!("offsetof(fmi2CallbackFunctions, {field}) == {off}"));
    }
    s
}

#[test]
fn exported_functions_match_the_official_fmi2_headers() {
    let Some(headers) = official_headers() else {
        println!(
            "SKIPPED: no .venv with fmpy (run scripts/python-env.sh, as scripts/test.sh does)"
        );
        return;
    };
    let names = official_function_names(&headers);
    assert_eq!(names.len(), 34, "official header lists {names:?}");
    let decls = generate_declarations();
    for n in &names {
        assert!(
            decls.contains(&format!(" {n}(")) || decls.contains(&format!("*{n}(")),
            "{n} is not exported by src/fmi/ffi.rs"
        );
    }
    let tmp = std::env::temp_dir().join(format!("bt_fmi2_{}", std::process::id()));
    std::fs::create_dir_all(&tmp).unwrap();
    std::fs::write(tmp.join("bt_fmi2_decls.h"), &decls).unwrap();
    let mut tu = String::from(
        "#include <stddef.h>\n#include \"fmi2Functions.h\"\n#include \"bt_fmi2_decls.h\"\n",
    );
    tu.push_str(&layout_assertions());
    tu.push_str("void *bt_fmi2_addresses[] = {\n");
    for n in &names {
        tu.push_str(&format!(
            "    (void *)(fmi2{}TYPE *){n},\n",
            n.trim_start_matches("fmi2")
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
        "the exported functions do not match the official FMI 2.0 types:\n{}\n--- declarations ---\n{decls}",
        String::from_utf8_lossy(&out.stderr)
    );
}
