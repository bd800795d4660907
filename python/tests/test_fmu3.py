"""BreathingTorso3.fmu, the FMI 3.0 co-simulation FMU built from the same variable table and
library as BreathingTorso.fmu, through fmpy's FMI 3.0 API: schema and model validation
(fmpy validate, the terminals file against the standard's schema), agreement with the FMI 2.0
FMU (lung volume, markers, the posture enumeration), FMU state get/set and serialisation, and
refused calls with their log messages.

The FMUs are built by scripts/test.sh (`torso fmu build`, `torso fmu build --fmi-version 3`).
"""

import pathlib
import shutil
import tempfile

import numpy as np
import pytest
from fmpy import extract, read_model_description, simulate_fmu
from fmpy.fmi1 import FMICallException
from fmpy.fmi3 import FMU3Slave
from fmpy.validation import validate_fmu

from test_fmu_calls import Host, fmu_path

ROOT = pathlib.Path(__file__).resolve().parents[2]
FMU3 = ROOT / "fmu" / "BreathingTorso3.fmu"
QUIET = {"drive.ribs.amplitude": 0.2, "drive.diaphragm.amplitude": 0.25, "drive.diaphragm.phase": 0.1}
N_MARKERS = 60  # the default 10 x 6 grid's markers (the generic FMU's outputs)


def fmu3_path():
    assert FMU3.is_file(), (
        f"{FMU3} missing: build it with `target/release/torso fmu build --fmi-version 3` (scripts/test.sh does)"
    )
    return str(FMU3)


class Host3:
    """One FMU3Slave whose log messages are recorded."""

    def __init__(self, logging_on=False):
        self.md = read_model_description(fmu3_path())
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.dir = extract(fmu3_path(), tempfile.mkdtemp(prefix="bt_fmu3_"))
        self.messages = []

        def log(env, status, category, message):
            self.messages.append((status, category.decode(), message.decode()))

        self.fmu = FMU3Slave(guid=self.md.guid, unzipDirectory=self.dir,
                             modelIdentifier=self.md.coSimulation.modelIdentifier, instanceName="bt3")
        self.fmu.instantiate(loggingOn=logging_on, logMessage=log)

    def start(self, int64=None, float64=None, stop=None):
        self.fmu.enterInitializationMode(startTime=0.0, stopTime=stop)
        for name, v in (int64 or {}).items():
            self.fmu.setInt64([self.vr[name]], [v])
        for name, v in (float64 or {}).items():
            self.fmu.setFloat64([self.vr[name]], [v])
        self.fmu.exitInitializationMode()

    def run(self, t0, t1, h, names=("volume.lung",)):
        vrs = [self.vr[n] for n in names]
        out = []
        for k in range(int(round((t1 - t0) / h))):
            t = t0 + k * h
            flags = self.fmu.doStep(currentCommunicationPoint=t, communicationStepSize=t0 + (k + 1) * h - t)
            assert flags[:3] == (False, False, False), flags
            out.append(self.fmu.getFloat64(vrs))
        return np.array(out)

    def close(self):
        self.fmu.freeInstance()
        shutil.rmtree(self.dir, ignore_errors=True)


def test_fmpy_validates_the_fmi3_fmu_and_its_terminals():
    assert validate_fmu(fmu3_path()) == []
    md = read_model_description(fmu3_path())
    assert md.fmiVersion == "3.0"
    import fmpy
    import zipfile
    from lxml import etree
    schema_dir = pathlib.Path(fmpy.__file__).parent / "schema" / "fmi3"
    schema = etree.XMLSchema(etree.parse(str(schema_dir / "fmi3TerminalsAndIcons.xsd")))
    with zipfile.ZipFile(fmu3_path()) as z:
        terminals = etree.fromstring(z.read("terminalsAndIcons/terminalsAndIcons.xml"))
    assert schema.validate(terminals), schema.error_log
    by_name = {v.name: v for v in md.modelVariables}
    buses = {t.get("name"): t for t in terminals.iter("Terminal")}
    assert set(buses) == {"activation", "volumes"}
    for bus, causality in [("activation", "input"), ("volumes", "output")]:
        members = list(buses[bus].iter("TerminalMemberVariable"))
        assert members, bus
        for m in members:
            assert by_name[m.get("variableName")].causality == causality, m.get("variableName")
    activations = [v.name for v in md.modelVariables if v.name.startswith("activation.")]
    assert sorted(m.get("variableName") for m in buses["activation"].iter("TerminalMemberVariable")) == sorted(activations)


def test_the_model_descriptions_agree():
    md2 = read_model_description(fmu_path())
    md3 = read_model_description(fmu3_path())
    v2 = {v.name: v for v in md2.modelVariables}
    v3 = {v.name: v for v in md3.modelVariables}
    assert md3.guid == md2.guid
    scalars2 = {n for n in v2 if not n.startswith("marker[")}
    assert set(v3) == scalars2 | {"marker"}
    for n in scalars2:
        a, b = v2[n], v3[n]
        assert (a.valueReference, a.causality, a.variability, a.unit, a.start) == \
            (b.valueReference, b.causality, b.variability, b.unit, b.start), n
    assert v3["marker"].type == "Float64"
    assert [int(d.start) for d in v3["marker"].dimensions] == [N_MARKERS, 3]
    for n, items in [("subject.sex", ["male", "female"]), ("posture", ["standing", "sitting", "supine"])]:
        assert v3[n].type == "Enumeration"
        assert [i.name for i in v3[n].declaredType.items] == items
    assert v3["solver.method"].type == "Enumeration"
    # The same outputs, with the same direct dependencies, in both ModelStructures.
    out2 = {u.variable.name: sorted(d.name for d in u.dependencies) for u in md2.outputs}
    out3 = {u.variable.name: sorted(d.name for d in u.dependencies) for u in md3.outputs}
    assert {n: d for n, d in out2.items() if not n.startswith("marker[")} == \
        {n: d for n, d in out3.items() if n != "marker"}
    assert out3["marker"] == [] and all(out2[f"marker[{i}].{a}"] == [] for i in (1, N_MARKERS) for a in "xyz")


def test_simulate_agrees_with_the_fmi2_fmu():
    kw = dict(stop_time=4.0, output_interval=0.02, start_values=QUIET, output=["volume.lung", "pressure.pleural"])
    r3 = simulate_fmu(fmu3_path(), **kw)
    r2 = simulate_fmu(fmu_path(), **kw)
    assert r3["time"][-1] == pytest.approx(4.0)
    assert np.array_equal(r3["time"], r2["time"])
    rel = np.max(np.abs(r3["volume.lung"] / r2["volume.lung"] - 1.0))
    assert rel <= 1e-12, f"volume.lung of the FMI 3.0 and 2.0 FMUs differ by {rel:e} (relative)"
    assert np.ptp(r3["volume.lung"]) > 0.0
    assert np.max(np.abs(r3["pressure.pleural"] - r2["pressure.pleural"])) <= 1e-12 * np.max(np.abs(r2["pressure.pleural"]))


def test_markers_read_as_one_array_equal_to_the_fmi2_scalars():
    h3 = Host3()
    h2 = Host()
    try:
        h3.start(float64=QUIET)
        h2.initialize(start_values=QUIET)
        for k in range(25):
            h3.fmu.doStep(currentCommunicationPoint=0.04 * k, communicationStepSize=0.04)
            h2.fmu.doStep(currentCommunicationPoint=0.04 * k, communicationStepSize=0.04)
        markers = np.array(h3.fmu.getFloat64([h3.vr["marker"]], nValues=N_MARKERS * 3)).reshape(N_MARKERS, 3)
        scalars = np.array(h2.fmu.getReal([h2.vr[f"marker[{i + 1}].{a}"] for i in range(N_MARKERS) for a in "xyz"]))
        assert np.array_equal(markers, scalars.reshape(N_MARKERS, 3))
        rows = h3.fmu.getInt32([h3.vr["grid.rows"]])[0]
        cols = h3.fmu.getInt32([h3.vr["grid.cols"]])[0]
        used = rows * cols
        assert np.all(np.linalg.norm(markers[:used], axis=1) > 0.01), "markers of the grid lie on the skin"
        assert np.all(markers[used:] == 0.0)
        # The array mixed with scalars in one call: values in order, nValues their total.
        mixed = h3.fmu.getFloat64([h3.vr["volume.lung"], h3.vr["marker"]], nValues=1 + N_MARKERS * 3)
        assert mixed[0] == h3.fmu.getFloat64([h3.vr["volume.lung"]])[0]
        assert np.array_equal(np.array(mixed[1:]).reshape(N_MARKERS, 3), markers)
    finally:
        h3.close()
        h2.close()


def test_simulate_records_the_marker_array_as_markers_by_3():
    kw = dict(stop_time=0.5, output_interval=0.05, start_values=QUIET)
    r3 = simulate_fmu(fmu3_path(), output=["marker"], **kw)
    scalars = [f"marker[{i + 1}].{a}" for i in range(N_MARKERS) for a in "xyz"]
    r2 = simulate_fmu(fmu_path(), output=scalars, **kw)
    assert r3["marker"].shape == (len(r2), N_MARKERS, 3)
    fmi2 = np.stack([r2[n] for n in scalars], axis=1).reshape(len(r2), N_MARKERS, 3)
    assert np.array_equal(r3["marker"], fmi2)
    assert np.ptp(r3["marker"][:, 0, :], axis=0).max() > 0.0, "marker 1 does not move"


def test_fmu_state_and_serialisation_replay_the_trajectory():
    h = Host3()
    try:
        h.start(float64=QUIET)
        h.run(0.0, 1.0, 0.05)
        state = h.fmu.getFMUState()
        first = h.run(1.0, 2.0, 0.05, names=("volume.lung", "volume.abdomen"))
        h.fmu.setFMUState(state)
        again = h.run(1.0, 2.0, 0.05, names=("volume.lung", "volume.abdomen"))
        assert np.array_equal(first, again)
        blob = h.fmu.serializeFMUState(state)
        h.fmu.freeFMUState(state)
        restored = h.fmu.deserializeFMUState(blob)
        h.fmu.setFMUState(restored)
        assert h.fmu.getFloat64([h.vr["time"]])[0] == pytest.approx(1.0)
        replay = h.run(1.0, 2.0, 0.05, names=("volume.lung", "volume.abdomen"))
        assert np.array_equal(first, replay)
        h.fmu.freeFMUState(restored)
    finally:
        h.close()
    # In another instance, from the bytes alone.
    other = Host3()
    try:
        other.start(float64=QUIET)
        s = other.fmu.deserializeFMUState(blob)
        other.fmu.setFMUState(s)
        assert np.array_equal(first, other.run(1.0, 2.0, 0.05, names=("volume.lung", "volume.abdomen")))
    finally:
        other.close()
    # In an instance of the FMI 2.0 FMU (same library, same state format and GUID).
    h2 = Host()
    try:
        f = h2.initialize(start_values=QUIET)
        f.setFMUstate(f.deSerializeFMUstate(blob))
        vrs = [h2.vr["volume.lung"], h2.vr["volume.abdomen"]]
        out = []
        for k in range(20):
            t = 1.0 + k * 0.05
            f.doStep(currentCommunicationPoint=t, communicationStepSize=1.0 + (k + 1) * 0.05 - t)
            out.append(f.getReal(vrs))
        assert np.array_equal(first, np.array(out))
    finally:
        h2.close()


def test_posture_enumeration_changes_the_result_as_in_fmi2():
    def lung3(posture):
        h = Host3()
        try:
            h.start(int64={"posture": posture}, float64=QUIET)
            assert h.fmu.getInt64([h.vr["posture"]]) == [posture]
            return h.run(0.0, 2.0, 0.05)[:, 0]
        finally:
            h.close()

    standing, supine = lung3(0), lung3(2)
    assert np.max(np.abs(standing - supine)) > 1e-3, "supine and standing breathe alike"
    kw = dict(stop_time=2.0, output_interval=0.05, output=["volume.lung"])
    r2 = simulate_fmu(fmu_path(), start_values={**QUIET, "posture": 2}, **kw)
    rel = np.max(np.abs(supine / r2["volume.lung"][1:] - 1.0))
    assert rel <= 1e-12, f"supine differs from FMI 2.0 by {rel:e}"
    # fmpy's simulate_fmu sets the enumeration by its start value too.
    r3 = simulate_fmu(fmu3_path(), start_values={**QUIET, "posture": 2}, **kw)
    assert np.array_equal(r3["volume.lung"], r2["volume.lung"])


def test_refused_calls_are_errors_with_a_message():
    h = Host3()
    try:
        h.start()
        with pytest.raises(FMICallException):
            h.fmu.setInt32([h.vr["posture"]], [2])
        assert "fmi3SetInt32" in h.messages[-1][2] and "Int64" in h.messages[-1][2], h.messages[-1]
        with pytest.raises(FMICallException):
            h.fmu.setInt64([h.vr["posture"]], [7])
        message = h.messages[-1][2]
        assert message.startswith("fmi3SetInt64") and "posture" in message, message
        with pytest.raises(FMICallException):
            h.fmu.getFloat64([h.vr["marker"]], nValues=3)
        assert str(3 * N_MARKERS) in h.messages[-1][2], h.messages[-1]
        with pytest.raises(FMICallException):
            h.fmu.setFloat64([h.vr["activation.diaphragm"]], [1.5])
        message = h.messages[-1][2]
        assert message.startswith("fmi3SetFloat64") and "activation.diaphragm" in message, message
        with pytest.raises(FMICallException):
            h.fmu.enterEventMode()
        assert "fmi3EnterEventMode: not provided" in h.messages[-1][2]
        with pytest.raises(FMICallException):
            h.fmu.doStep(currentCommunicationPoint=5.0, communicationStepSize=0.1)
        assert h.messages[-1][2].startswith("fmi3DoStep"), h.messages[-1]
        # The instance still steps after the refused calls.
        h.run(0.0, 0.2, 0.1)
    finally:
        h.close()


def test_resource_path_is_native_and_strings_round_trip():
    """fmpy passes FMI 3.0's resourcePath as a native path (here with spaces and a percent
    sign, which FMI 2.0's URI would escape); a relative slp.reference is found in it."""
    h = Host3()
    try:
        h.fmu.freeInstance()
        spaced = pathlib.Path(tempfile.mkdtemp(prefix="bt fmu3 %20 ")) / "unzipped dir"
        shutil.copytree(h.dir, spaced)
        shutil.rmtree(h.dir, ignore_errors=True)
        h.dir = str(spaced)
        (spaced / "resources" / "first frame.csv").write_text("t,x\n0,0\n")
        h.fmu = FMU3Slave(guid=h.md.guid, unzipDirectory=h.dir, modelIdentifier="BreathingTorso", instanceName="bt3")
        h.fmu.instantiate(logMessage=lambda *a: h.messages.append(a))
        h.fmu.setString([h.vr["slp.reference"]], ["first frame.csv"])
        h.fmu.enterInitializationMode(startTime=0.0)
        # Accepted because it is in resources/ (not in the working folder); the value stays
        # as given, relative to resources/.
        assert not pathlib.Path("first frame.csv").exists()
        assert h.fmu.getString([h.vr["slp.reference"]]) == ["first frame.csv"]
        h.fmu.setString([h.vr["slp.reference"]], [""])
        assert h.fmu.getString([h.vr["slp.reference"]]) == [""]
        assert h.fmu.getBoolean([h.vr["drive.enabled"]]) == [True]
        h.fmu.setBoolean([h.vr["drive.enabled"]], [False])
        assert h.fmu.getBoolean([h.vr["drive.enabled"]]) == [False]
    finally:
        h.fmu.freeInstance()
        shutil.rmtree(pathlib.Path(h.dir).parent, ignore_errors=True)


def test_both_fmus_ship_the_same_binaries():
    """One library exports both interfaces: every platform of the FMI 2.0 FMU is in the FMI 3.0
    FMU under its platform tuple, byte for byte (development and distributable builds alike:
    scripts/test.sh and scripts/deploy.sh package both from the same files)."""
    import zipfile
    tuples = {"linux64": "x86_64-linux", "linux32": "x86-linux", "win64": "x86_64-windows",
              "win32": "x86-windows", "darwin64": "x86_64-darwin"}

    def binaries(path):
        with zipfile.ZipFile(path) as z:
            return {n.split("/")[1]: z.read(n) for n in z.namelist()
                    if n.startswith("binaries/") and not n.endswith("/")}

    b2, b3 = binaries(fmu_path()), binaries(fmu3_path())
    assert b2 and {tuples[p] for p in b2} == set(b3)
    for p, data in b2.items():
        assert b3[tuples[p]] == data, p


def test_reset_debug_logging_and_version():
    h = Host3()
    try:
        assert h.fmu.getVersion() == "3.0"
        h.start(float64=QUIET)
        first = h.run(0.0, 0.5, 0.05)
        h.fmu.setDebugLogging(True, ["logCalls"])
        h.fmu.reset()
        h.start(float64=QUIET)
        calls = [m for s, c, m in h.messages if c == "logCalls"]
        assert calls[0].startswith("fmi3Reset(") and any(m.startswith("fmi3EnterInitializationMode(") for m in calls), calls[:5]
        h.fmu.setDebugLogging(False, [])
        n = len(h.messages)
        assert np.array_equal(first, h.run(0.0, 0.5, 0.05)), "a reset instance replays differently"
        assert len(h.messages) == n, "messages after logging was switched off"
        with pytest.raises(FMICallException):
            h.fmu.setDebugLogging(True, ["noSuchCategory"])
    finally:
        h.close()
