"""Personalised FMUs through fmpy: a short skin fit of the bundled recording baked into an FMU
with `torso fmu build --subject`. fmpy validates it; its start values are the fit's; it
simulated with no parameter set gives the same lung volume and markers as the generic FMU
(built from the same library) with the `.ssv` written beside it applied as start values
(within 1e-12 relative); every `.ssv` parameter is a parameter of both FMUs with the same
type; packaged with the distributable binaries it stays at most 4 MB; a state serialized in
one unpack folder restores in a copy unpacked in another (the first one deleted) and continues
identically.
"""

import json
import shutil
import subprocess
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

import numpy as np
import pytest
from fmpy import extract, read_model_description, simulate_fmu
from fmpy.fmi2 import FMU2Slave
from fmpy.validation import validate_fmu

ROOT = Path(__file__).resolve().parents[2]
TORSO = ROOT / "target" / "release" / "torso"
SHIPPED = ROOT / "fmu" / "BreathingTorso.fmu"
RECORDING = ROOT / "data" / "recordings" / "demo_quiet.csv"
SSV = "{http://ssp-standard.org/SSP1/SystemStructureParameterValues}"
MAX_BYTES = 4_000_000


def torso(*args):
    assert TORSO.is_file(), f"{TORSO} missing: cargo build --release"
    out = subprocess.run([str(TORSO), *map(str, args)], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr + out.stdout
    return out.stdout


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    d = tmp_path_factory.mktemp("personal")
    fit = d / "fit" / "result.json"
    fit.parent.mkdir()
    torso("fit", "--slp", RECORDING, "--lod", "0", "--max-evals", "50", "--skin-fit",
          "--threads", "1", "--out", fit)
    personal = d / "subject.fmu"
    torso("fmu", "build", "--subject", fit, "--out", personal)
    generic = d / "generic.fmu"
    torso("fmu", "build", "--out", generic)
    return {"dir": d, "fit": fit, "personal": personal, "generic": generic,
            "ssv": personal.with_suffix(".ssv")}


def ssv_values(path):
    """name -> (type, Python value) of an SSP 1.0 parameter set."""
    root = ET.parse(path).getroot()
    assert root.tag == SSV + "ParameterSet" and root.get("version") == "1.0"
    out = {}
    for p in root.iter(SSV + "Parameter"):
        (v,) = list(p)
        ty = v.tag.removeprefix(SSV)
        text = v.get("value")
        out[p.get("name")] = (ty, {"Real": float, "Integer": int, "String": str,
                                   "Boolean": lambda s: s in ("true", "1")}[ty](text))
    return out


def test_both_fmus_validate(built):
    assert validate_fmu(str(built["personal"])) == []
    assert validate_fmu(str(built["generic"])) == []


def test_start_values_are_the_fits(built):
    fit = json.loads(built["fit"].read_text())
    md = read_model_description(str(built["personal"]))
    generic = read_model_description(str(built["generic"]))
    assert md.guid != generic.guid
    var = {v.name: v for v in md.modelVariables}
    drive = [k for k in fit if k.startswith("drive.")]
    assert len(drive) == 8
    for k in drive:
        assert float(var[k].start) == fit[k], k
    for k, v in fit["subject"].items():
        if isinstance(v, str):
            v = {"Male": 0, "Female": 1, "Standing": 0, "Sitting": 1, "Supine": 2}[v]
        assert float(var[k].start) == v, k
    rows, cols = fit["model"]["grid.rows"], fit["model"]["grid.cols"]
    markers = [n for n in var if n.startswith("marker[")]
    assert len(markers) == 3 * rows * cols
    assert var["slp.reference"].start == "subject/result_reference.csv"
    with zipfile.ZipFile(built["personal"]) as z:
        names = z.namelist()
    assert "resources/subject/result_reference.csv" in names
    assert "documentation/fit.json" in names


def test_ssv_parameters_exist_in_both_fmus_with_their_types(built):
    values = ssv_values(built["ssv"])
    assert len(values) >= 17
    for path in (built["personal"], built["generic"]):
        var = {v.name: v for v in read_model_description(str(path)).modelVariables}
        for name, (ty, _) in values.items():
            assert name in var, f"{name} not in {path.name}"
            assert var[name].type == ty, name
            assert var[name].causality == "parameter", name


def test_personalised_fmu_equals_generic_with_the_ssv(built):
    outputs = ["volume.lung", "marker[1].x", "marker[60].y"]
    kw = dict(stop_time=2.0, output_interval=0.05, output=outputs)
    personal = simulate_fmu(str(built["personal"]), **kw)
    start = {name: v for name, (_, v) in ssv_values(built["ssv"]).items()}
    generic = simulate_fmu(str(built["generic"]), start_values=start, **kw)
    plain = simulate_fmu(str(built["generic"]), **kw)
    for name in outputs:
        a, g = personal[name], generic[name]
        assert np.all(np.abs(a - g) <= 1e-12 * np.abs(g)), (name, np.max(np.abs(a - g)))
    assert np.ptp(generic["volume.lung"]) > 0.05
    # Without the parameter set the generic FMU is another subject.
    assert np.max(np.abs(plain["marker[1].x"] - generic["marker[1].x"])) > 1e-6


def test_a_state_serialized_in_one_unpack_folder_restores_in_another(built, tmp_path):
    """Importers unpack an FMU to a fresh folder per run, and FMI 2.0 lets a serialized state
    be restored in another instance: the skin reference, relative to resources/, must not tie
    the state to the folder it was saved in."""
    md = read_model_description(str(built["personal"]))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    outputs = [vr["volume.lung"], vr["marker[1].x"]]
    h = 0.05

    def slave(folder):
        extract(str(built["personal"]), str(folder))
        fmu = FMU2Slave(guid=md.guid, unzipDirectory=str(folder),
                        modelIdentifier=md.coSimulation.modelIdentifier, instanceName=folder.name)
        fmu.instantiate()
        fmu.setupExperiment(startTime=0.0)
        fmu.enterInitializationMode()
        fmu.exitInitializationMode()
        return fmu

    def run(fmu, k0, k1):
        out = []
        for k in range(k0, k1):
            fmu.doStep(currentCommunicationPoint=k * h, communicationStepSize=h)
            out.append(fmu.getReal(outputs))
        return out

    u1, u2 = tmp_path / "u1", tmp_path / "u2"
    a = slave(u1)
    run(a, 0, 10)
    state = a.getFMUstate()
    data = a.serializeFMUstate(state)
    a.freeFMUstate(state)
    expected = run(a, 10, 30)
    a.terminate()
    a.freeInstance()
    shutil.rmtree(u1)
    b = slave(u2)
    try:
        state = b.deSerializeFMUstate(data)
        b.setFMUstate(state)  # raises on fmi2Error
        b.freeFMUstate(state)
        assert run(b, 10, 30) == expected
        [reference] = b.getString([vr["slp.reference"]])
        assert reference == b"subject/result_reference.csv"
    finally:
        b.terminate()
        b.freeInstance()


def test_packaged_with_the_distributable_binaries_it_is_at_most_4_mb(built, tmp_path):
    assert SHIPPED.is_file(), f"{SHIPPED} missing: build it with `bash scripts/deploy.sh` (scripts/test.sh does)"
    args = []
    with zipfile.ZipFile(SHIPPED) as z:
        for n in z.namelist():
            if n.startswith("binaries/") and not n.endswith("/"):
                platform = n.split("/")[1]
                path = tmp_path / platform / Path(n).name
                path.parent.mkdir(parents=True, exist_ok=True)
                path.write_bytes(z.read(n))
                args += ["--binary", f"{platform}={path}"]
    assert args
    out = tmp_path / "subject.fmu"
    torso("fmu", "build", "--subject", built["fit"], "--out", out, *args)
    assert out.stat().st_size <= MAX_BYTES, f"{out.stat().st_size} bytes"
    assert validate_fmu(str(out)) == []


CHEST30 = ROOT / "data" / "recordings" / "chest30_lab.c3d"


@pytest.fixture(scope="module")
def named(tmp_path_factory):
    """A short fit of the laboratory recording of the 30-marker chest set (named markers, level
    of detail 0) made into a personalised FMU."""
    d = tmp_path_factory.mktemp("named")
    fit = d / "fit.json"
    torso("fit", "--slp", CHEST30, "--lod", "0", "--max-evals", "12", "--threads", "1", "--out", fit)
    fmu = d / "named.fmu"
    torso("fmu", "build", "--subject", fit, "--out", fmu)
    return {"fit": fit, "fmu": fmu, "ssv": fmu.with_suffix(".ssv"), "json": json.loads(fit.read_text())}


def test_a_named_marker_sets_fmu_validates_and_names_its_markers_by_label(named):
    assert validate_fmu(str(named["fmu"])) == []
    md = read_model_description(str(named["fmu"]))
    labels = named["json"]["marker_set"]["labels_bound"]
    assert len(labels) >= 20
    markers = sorted((v.valueReference, v.name) for v in md.modelVariables if v.name.startswith("marker"))
    assert [n for _, n in markers] == [f"marker.{l}.{a}" for l in labels for a in "xyz"]
    assert [vr for vr, _ in markers] == list(range(2000, 2000 + 3 * len(labels)))
    with zipfile.ZipFile(named["fmu"]) as z:
        assert "resources/subject/markers.json" in z.namelist()


def test_a_named_marker_sets_outputs_are_the_native_skin_at_the_bindings(named):
    """The FMU's marker outputs, simulated by fmpy, against the native C library run with the
    same parameters: its deformed skin (bt_read_skin) at each marker's barycentric binding from
    the fit result."""
    import ctypes
    import sys
    sys.path.insert(0, str(ROOT / "python"))
    from bench_scipy import Config, load_library

    labels = named["json"]["marker_set"]["labels_bound"]
    bindings = named["json"]["marker_set"]["bindings"]
    assert [b["label"] for b in bindings] == labels
    h, steps = 0.25, 8
    outputs = [f"marker.{l}.{a}" for l in labels for a in "xyz"]
    r = simulate_fmu(str(named["fmu"]), stop_time=h * steps, output_interval=h, output=outputs)
    fmu = np.array([[row[n] for n in outputs] for row in r]).reshape(len(r), len(labels), 3)

    lib = load_library()
    lib.bt_skin_sizes.argtypes = [ctypes.c_void_p, ctypes.POINTER(ctypes.c_size_t), ctypes.POINTER(ctypes.c_size_t)]
    lib.bt_read_skin.argtypes = [ctypes.c_void_p, ctypes.c_void_p, ctypes.c_size_t, ctypes.c_void_p, ctypes.c_size_t]
    c = Config()
    assert lib.bt_config_default(ctypes.byref(c)) == 0
    for name, (ty, value) in ssv_values(named["ssv"]).items():
        if ty == "String":
            assert value == "", name  # no skin reference, no subject mesh for a named set
            continue
        assert lib.bt_config_set(ctypes.byref(c), name.encode(), float(value)) == 0, lib.bt_creation_error()
    handle = lib.bt_create(ctypes.byref(c))
    assert handle, lib.bt_creation_error()
    try:
        nv, nt = ctypes.c_size_t(), ctypes.c_size_t()
        assert lib.bt_skin_sizes(handle, ctypes.byref(nv), ctypes.byref(nt)) == 0
        vertices = np.zeros((nv.value, 3))
        triangles = np.zeros((nt.value, 3), dtype=np.uint32)
        tri = np.array([b["triangle"] for b in bindings])
        bary = np.array([b["barycentric"] for b in bindings])
        worst, native = 0.0, []
        for k in range(len(r)):
            if r["time"][k] > 0:
                assert lib.bt_advance_to(handle, float(r["time"][k]), None) == 0, lib.bt_last_error(handle)
            assert lib.bt_read_skin(handle, vertices.ctypes.data, vertices.size,
                                    triangles.ctypes.data, triangles.size) == 0
            points = np.einsum("mk,mkd->md", bary, vertices[triangles[tri]])
            native.append(points)
            worst = max(worst, float(np.max(np.abs(points - fmu[k]))))
    finally:
        lib.bt_destroy(handle)
    native = np.array(native)
    print(f"{len(labels)} markers: largest |FMU - native skin at the binding| {worst:.3g} m, "
          f"largest excursion {np.max(np.abs(native - native[0])):.3g} m")
    assert np.max(np.abs(native - native[0])) > 1e-4, "the markers move with breathing"
    assert worst <= 1e-9
