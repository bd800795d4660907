"""BreathingTorso.fmu through fmpy: static validation, the call-sequence state machine,
rejected inputs, GUID check, doStep time checks, FMU state errors, reset and logging.

The FMU is built by scripts/test.sh (`torso fmu build`) before pytest runs.
"""

import itertools
import math
import pathlib
import shutil
import tempfile
from ctypes import byref

import pytest
from fmpy import extract, read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import (
    FMU2Slave,
    calloc,
    fmi2CallbackAllocateMemoryTYPE,
    fmi2CallbackFreeMemoryTYPE,
    fmi2CallbackFunctions,
    fmi2CallbackLoggerTYPE,
    free,
)
from fmpy.logging import addLoggerProxy
from fmpy.validation import validate_fmu

ROOT = pathlib.Path(__file__).resolve().parents[2]
FMU = ROOT / "fmu" / "BreathingTorso.fmu"


def fmu_path():
    assert FMU.is_file(), f"{FMU} missing: build it with `target/release/torso fmu build` (scripts/test.sh does)"
    return str(FMU)


# fmpy's logger proxy keeps one global pointer to the last Python logger it wrapped, so the
# tests use one logger for the whole session (never freed) and sort messages by instance name.
_MESSAGES = {}
_COUNTER = itertools.count()


def _log(env, name, status, category, message):
    _MESSAGES.setdefault(name.decode(), []).append((status, category.decode(), message.decode()))


CALLBACKS = fmi2CallbackFunctions()
CALLBACKS.logger = fmi2CallbackLoggerTYPE(_log)
CALLBACKS.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
CALLBACKS.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
addLoggerProxy(byref(CALLBACKS))


class Host:
    """One FMU2Slave whose log messages are recorded."""

    def __init__(self, guid=None, logging_on=False):
        self.md = read_model_description(fmu_path())
        self.dir = extract(fmu_path(), tempfile.mkdtemp(prefix="bt_fmu_"))
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.name = f"torso{next(_COUNTER)}"
        self.messages = _MESSAGES.setdefault(self.name, [])
        self.callbacks = CALLBACKS
        self.fmu = FMU2Slave(
            guid=guid or self.md.guid,
            unzipDirectory=self.dir,
            modelIdentifier=self.md.coSimulation.modelIdentifier,
            instanceName=self.name,
        )
        self.logging_on = logging_on

    def instantiate(self):
        self.fmu.instantiate(callbacks=self.callbacks, loggingOn=self.logging_on)
        return self.fmu

    def initialize(self, start_values=None, start=0.0):
        f = self.instantiate()
        f.setupExperiment(startTime=start)
        f.enterInitializationMode()
        for name, value in (start_values or {}).items():
            if isinstance(value, bool):
                f.setBoolean([self.vr[name]], [value])
            elif isinstance(value, int):
                f.setInteger([self.vr[name]], [value])
            else:
                f.setReal([self.vr[name]], [value])
        f.exitInitializationMode()
        return f

    def last_error(self):
        return self.messages[-1][2] if self.messages else ""

    def close(self):
        try:
            self.fmu.freeInstance()
        finally:
            shutil.rmtree(self.dir, ignore_errors=True)


@pytest.fixture
def host():
    h = Host()
    yield h
    h.close()


def test_validate_fmu_reports_no_problems():
    assert validate_fmu(fmu_path()) == []


def test_model_description_contract():
    md = read_model_description(fmu_path())
    names = {v.name: v for v in md.modelVariables}
    assert md.coSimulation.modelIdentifier == "BreathingTorso"
    assert md.variableNamingConvention == "structured"
    for group in ["diaphragm", "external_intercostals", "internal_intercostals", "scalenes",
                  "transversus_abdominis", "rectus_abdominis", "external_obliques", "internal_obliques",
                  "sternocleidomastoids"]:
        v = names[f"activation.{group}"]
        assert (v.causality, v.type, float(v.min), float(v.max), float(v.start)) == ("input", "Real", 0.0, 1.0, 0.0)
    for n in ["volume.lung", "volume.thorax", "volume.abdomen", "volume.trunk", "volume.rib_cage_displaced",
              "volume.abdomen_displaced"]:
        assert names[n].unit == "L" and names[n].causality == "output"
    assert names["pressure.abdomen"].unit == "Pa"
    assert names["marker[60].z"].unit == "m"
    # The default 10 x 6 grid's 60 markers are the generic FMU's marker outputs (issue 22).
    assert sum(n.startswith("marker[") for n in names) == 3 * 60
    assert names["solver.steps"].type == "Integer"
    assert names["slp.reference"].type == "String"
    assert names["drive.ribs.phase"].variability == "tunable"
    assert names["subject.age"].variability == "fixed"
    for flag in ["canHandleVariableCommunicationStepSize", "canGetAndSetFMUstate", "canSerializeFMUstate",
                 "canNotUseMemoryManagementFunctions"]:
        assert getattr(md.coSimulation, flag)
    assert not md.coSimulation.providesDirectionalDerivative


def test_wrong_guid_is_rejected():
    h = Host(guid="{00000000-0000-0000-0000-000000000000}")
    try:
        with pytest.raises(Exception, match="instantiate"):
            h.instantiate()
        assert any("GUID" in m for _, _, m in h.messages), h.messages
    finally:
        shutil.rmtree(h.dir, ignore_errors=True)


def test_illegal_call_sequences_are_rejected(host):
    f = host.instantiate()
    with pytest.raises(FMICallException):
        f.doStep(currentCommunicationPoint=0.0, communicationStepSize=0.1)
    assert "illegal call sequence" in host.last_error()
    with pytest.raises(FMICallException):
        f.exitInitializationMode()
    with pytest.raises(FMICallException):
        f.getReal([host.vr["volume.lung"]])
    f.setupExperiment(startTime=0.0)
    f.enterInitializationMode()
    with pytest.raises(FMICallException):
        f.setupExperiment(startTime=0.0)
    f.exitInitializationMode()
    with pytest.raises(FMICallException):
        f.enterInitializationMode()
    # A fixed parameter cannot change after initialization; a tunable one can.
    with pytest.raises(FMICallException):
        f.setReal([host.vr["subject.age"]], [40.0])
    assert "subject.age" in host.last_error() and "fixed" in host.last_error()
    f.setReal([host.vr["drive.frequency"]], [0.3])
    assert f.getReal([host.vr["drive.frequency"]]) == [0.3]
    with pytest.raises(FMICallException):
        f.setInteger([host.vr["grid.rows"]], [12])
    # Outputs cannot be set; unknown references and wrong types are errors.
    with pytest.raises(FMICallException):
        f.setReal([host.vr["volume.lung"]], [1.0])
    with pytest.raises(FMICallException):
        f.getReal([999999])
    with pytest.raises(FMICallException):
        f.getReal([host.vr["solver.steps"]])
    assert "Integer" in host.last_error()
    f.terminate()
    with pytest.raises(FMICallException):
        f.doStep(currentCommunicationPoint=0.0, communicationStepSize=0.1)


@pytest.mark.parametrize("value", [math.nan, math.inf, -0.1, 1.5])
def test_bad_inputs_are_rejected_and_change_nothing(host, value):
    f = host.initialize()
    vr = host.vr["activation.diaphragm"]
    f.setReal([vr], [0.25])
    with pytest.raises(FMICallException):
        f.setReal([vr], [value])
    assert "activation.diaphragm" in host.last_error() and "[0, 1]" in host.last_error()
    assert f.getReal([vr]) == [0.25]
    # A batch with one bad value changes nothing at all.
    with pytest.raises(FMICallException):
        f.setReal([host.vr["activation.scalenes"], vr], [0.5, value])
    assert f.getReal([host.vr["activation.scalenes"], vr]) == [0.0, 0.25]


@pytest.mark.parametrize("name,value", [("subject.age", 5.0), ("subject.stature", math.nan),
                                        ("solver.rtol", 1.0), ("drive.frequency", -1.0),
                                        ("lung.ratio", 2.0)])
def test_bad_parameters_are_rejected(host, name, value):
    f = host.instantiate()
    with pytest.raises(FMICallException):
        f.setReal([host.vr[name]], [value])
    assert name in host.last_error(), host.messages
    f.setupExperiment(startTime=0.0)
    f.enterInitializationMode()
    default = next(v for v in host.md.modelVariables if v.name == name).start
    assert f.getReal([host.vr[name]]) == [float(default)]


def test_bad_integer_parameters_are_rejected(host):
    f = host.instantiate()
    for name, value in [("subject.sex", 2), ("posture", -1), ("grid.rows", 17), ("solver.method", 9)]:
        with pytest.raises(FMICallException):
            f.setInteger([host.vr[name]], [value])
        assert name in host.last_error()


def test_inconsistent_subject_fails_at_initialization(host):
    f = host.instantiate()
    f.setupExperiment(startTime=0.0)
    f.enterInitializationMode()
    f.setReal([host.vr["subject.stature"], host.vr["subject.mass"]], [1.4, 160.0])
    with pytest.raises(FMICallException):
        f.exitInitializationMode()
    assert "subject.mass" in host.last_error()
    f.setReal([host.vr["subject.mass"]], [60.0])
    f.exitInitializationMode()


def test_missing_slp_reference_is_rejected(host):
    f = host.instantiate()
    with pytest.raises(FMICallException):
        f.setString([host.vr["slp.reference"]], ["no/such/recording.csv"])
    assert "slp.reference" in host.last_error()


def test_do_step_checks_time_and_step_size(host):
    f = host.initialize(start=1.5)
    with pytest.raises(FMICallException):
        f.doStep(currentCommunicationPoint=1.0, communicationStepSize=0.1)
    assert "currentCommunicationPoint" in host.last_error()
    with pytest.raises(FMICallException):
        f.doStep(currentCommunicationPoint=1.5, communicationStepSize=0.0)
    with pytest.raises(FMICallException):
        f.doStep(currentCommunicationPoint=1.5, communicationStepSize=-0.1)
    with pytest.raises(FMICallException):
        f.doStep(currentCommunicationPoint=1.5, communicationStepSize=math.nan)
    assert f.getReal([host.vr["time"]]) == [1.5]


def test_markers_beyond_the_grid_read_zero(host):
    f = host.initialize({"grid.rows": 4, "grid.cols": 5})
    assert f.getReal([host.vr["marker[21].x"], host.vr["marker[60].z"]]) == [0.0, 0.0]
    assert f.getReal([host.vr["marker[20].z"]]) != [0.0]


def test_a_grid_beyond_the_marker_outputs_is_refused(host):
    with pytest.raises(FMICallException):
        host.initialize({"grid.rows": 16, "grid.cols": 16})
    message = host.last_error()
    assert "grid.rows x grid.cols" in message and "at most 60" in message and "--subject" in message, message


def test_serialized_garbage_is_rejected(host):
    f = host.initialize()
    for garbage in [b"", b"BTFMUST\0", b"\x00" * 64, b"BTFMUST\0\x01\x00\x00\x00" + b"\xff" * 40]:
        with pytest.raises(FMICallException):
            f.deSerializeFMUstate(garbage)
        assert "FMU state" in host.last_error() or "NULL" in host.last_error(), host.messages


def test_fmu_state_round_trip_of_parameters_and_inputs(host):
    f = host.initialize()
    f.setReal([host.vr["activation.scalenes"], host.vr["drive.ribs.amplitude"]], [0.4, 0.3])
    state = f.getFMUstate()
    data = f.serializeFMUstate(state)
    f.setReal([host.vr["activation.scalenes"], host.vr["drive.ribs.amplitude"]], [0.9, 0.8])
    f.setFMUstate(state)
    assert f.getReal([host.vr["activation.scalenes"], host.vr["drive.ribs.amplitude"]]) == [0.4, 0.3]
    f.setReal([host.vr["activation.scalenes"]], [0.1])
    restored = f.deSerializeFMUstate(data)
    f.setFMUstate(restored)
    assert f.getReal([host.vr["activation.scalenes"]]) == [0.4]
    f.freeFMUstate(state)
    f.freeFMUstate(restored)


def test_reset_restores_start_values(host):
    f = host.initialize({"subject.age": 60.0, "grid.rows": 8})
    f.setReal([host.vr["activation.diaphragm"]], [0.7])
    f.reset()
    f.setupExperiment(startTime=0.0)
    f.enterInitializationMode()
    assert f.getReal([host.vr["subject.age"], host.vr["activation.diaphragm"], host.vr["time"]]) == [30.0, 0.0, 0.0]
    assert f.getInteger([host.vr["grid.rows"], host.vr["solver.steps"]]) == [10, 0]


def test_debug_logging_categories(host):
    f = host.instantiate()
    with pytest.raises(FMICallException):
        f.setDebugLogging(True, ["noSuchCategory"])
    assert "noSuchCategory" in host.last_error()
    f.setDebugLogging(True, ["logCalls"])
    n = len(host.messages)
    f.setupExperiment(startTime=0.0)
    assert any(c == "logCalls" and "fmi2SetupExperiment" in m for _, c, m in host.messages[n:])
    f.setDebugLogging(False, [])
    n = len(host.messages)
    with pytest.raises(FMICallException):
        f.setReal([host.vr["subject.age"]], [500.0])
    assert len(host.messages) == n  # every category switched off, errors included
    f.setDebugLogging(True, ["logStatusError"])
    with pytest.raises(FMICallException):
        f.setReal([host.vr["subject.age"]], [500.0])
    assert "subject.age" in host.last_error()


def test_logger_receives_percent_signs_verbatim(host):
    f = host.instantiate()
    with pytest.raises(FMICallException):
        f.setDebugLogging(True, ["%s%n%x%d"])
    assert "%s%n%x%d" in host.last_error()


def test_resource_location_is_parsed_as_a_uri():
    """Extracted into a folder whose name needs percent-escapes, a relative slp.reference is
    found in resources/ (fmpy passes file:///...%20... as the resource location)."""
    h = Host()
    try:
        spaced = pathlib.Path(tempfile.mkdtemp(prefix="bt fmu %20 ")) / "unzipped dir"
        shutil.copytree(h.dir, spaced)
        shutil.rmtree(h.dir, ignore_errors=True)
        h.dir = str(spaced)
        (spaced / "resources" / "first frame.csv").write_text("t,x\n0,0\n")
        h.fmu = FMU2Slave(guid=h.md.guid, unzipDirectory=h.dir, modelIdentifier="BreathingTorso", instanceName=h.name)
        f = h.instantiate()
        f.setString([h.vr["slp.reference"]], ["first frame.csv"])
        f.setupExperiment(startTime=0.0)
        f.enterInitializationMode()
        # Accepted because it is in resources/ (not in the working folder); the value stays
        # as given, relative to resources/, so that it means the same in any unpack folder.
        assert not pathlib.Path("first frame.csv").exists()
        assert f.getString([h.vr["slp.reference"]]) == [b"first frame.csv"]
        f.setString([h.vr["slp.reference"]], [""])
        assert f.getString([h.vr["slp.reference"]]) == [b""]
    finally:
        h.fmu.freeInstance()
        shutil.rmtree(pathlib.Path(h.dir).parent, ignore_errors=True)
