"""The packaged FMU's <ModelStructure> against its behaviour, through fmpy: every output
declares its input dependencies, and the ones declared empty are measured: setting every input
to 1 at a communication point, without a step, leaves those outputs unchanged (in
initialization mode and after breathing steps), while the next step responds to the inputs.
The alveolar, pleural and mouth pressures declare the airway-opening pressure and the
occlusion, and move with the former; the airflow declares the occlusion.

Needs fmu/BreathingTorso.fmu (scripts/test.sh builds it).
"""

import pathlib
import shutil
import tempfile

import pytest
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave

ROOT = pathlib.Path(__file__).resolve().parents[2]
FMU = ROOT / "fmu" / "BreathingTorso.fmu"


@pytest.fixture(scope="module")
def md():
    assert FMU.is_file(), f"{FMU} missing: build it with `bash scripts/deploy.sh` (scripts/test.sh does)"
    return read_model_description(str(FMU))


@pytest.fixture
def slave(md):
    directory = extract(str(FMU), tempfile.mkdtemp(prefix="bt_structure_"))
    fmu = FMU2Slave(guid=md.guid, unzipDirectory=directory,
                    modelIdentifier=md.coSimulation.modelIdentifier, instanceName="structure")
    fmu.instantiate()
    yield fmu
    fmu.freeInstance()
    shutil.rmtree(directory, ignore_errors=True)


def read_outputs(fmu, md):
    """Every output as {name: value}, Reals and Integers."""
    values = {}
    for kind, get in (("Real", fmu.getReal), ("Integer", fmu.getInteger)):
        outs = [u.variable for u in md.outputs if u.variable.type == kind]
        for v, x in zip(outs, get([v.valueReference for v in outs])):
            values[v.name] = x
    return values


def false_claims(md, before, after):
    """Outputs declared free of the inputs whose value changed."""
    free = {u.variable.name for u in md.outputs if u.dependencies == []}
    return sorted(n for n in free if before[n] != after[n])


FED_THROUGH = {"pressure.pleural", "pressure.alveolar", "pressure.mouth"}


def declared(name):
    """The inputs an output depends on at once: the airway opening and the occlusion for the
    pressures, the occlusion alone for the airflow (0 behind it)."""
    if name in FED_THROUGH:
        return ["pressure.airway_opening", "airway.occluded"]
    return ["airway.occluded"] if name == "flow.airway" else []


def test_every_output_declares_its_dependencies(md):
    inputs = {v.name for v in md.modelVariables if v.causality == "input"}
    outputs = [v for v in md.modelVariables if v.causality == "output"]
    assert len(md.outputs) == len(outputs) == 26 + 3 * 60  # 60 markers: the default 10 x 6 grid
    for u in md.outputs:
        assert u.dependencies is not None, f"{u.variable.name} would depend on all knowns"
        assert [d.name for d in u.dependencies] == declared(u.variable.name), u.variable.name
    for u in md.initialUnknowns:
        assert u.dependencies, u.variable.name
        own = declared(u.variable.name)
        assert all(d.causality == "parameter" or d.name in own
                   for d in u.dependencies), u.variable.name
        assert (inputs & {d.name for d in u.dependencies}) == set(own)


def test_setting_every_input_without_a_step_changes_no_output(md, slave):
    vr = {v.name: v.valueReference for v in md.modelVariables}
    # the Real inputs (airway.occluded, the one Boolean, is tests/occlusion.rs's)
    inputs = [v.valueReference for v in md.modelVariables
              if v.causality == "input" and v.type == "Real"]
    n = len(inputs)
    assert n == 10  # the nine muscle groups' activations and pressure.airway_opening
    slave.setupExperiment(startTime=0.0)
    slave.setReal([vr["drive.ribs.amplitude"], vr["drive.diaphragm.amplitude"]], [0.12, 0.30])
    slave.enterInitializationMode()
    before = read_outputs(slave, md)
    slave.setReal(inputs, [1.0] * n)
    assert false_claims(md, before, read_outputs(slave, md)) == []
    slave.setReal(inputs, [0.0] * n)
    slave.exitInitializationMode()

    t, h = 0.0, 0.05
    for _ in range(3):
        for _ in range(4):
            slave.doStep(currentCommunicationPoint=t, communicationStepSize=h)
            t += h
        state = slave.getFMUstate()
        before = read_outputs(slave, md)
        slave.setReal(inputs, [1.0] * n)
        after = read_outputs(slave, md)
        assert false_claims(md, before, after) == [], f"t = {t}"
        for name in FED_THROUGH:  # 1 Pa at the airway opening, at once
            assert abs(after[name] - before[name] - 1.0) < 1e-9, name
        slave.doStep(currentCommunicationPoint=t, communicationStepSize=h)
        driven = read_outputs(slave, md)["volume.lung"]
        slave.setFMUstate(state)
        slave.doStep(currentCommunicationPoint=t, communicationStepSize=h)
        held = read_outputs(slave, md)["volume.lung"]
        assert driven != held, "the inputs reach the state within a step"
        slave.setFMUstate(state)
        slave.freeFMUstate(state)
