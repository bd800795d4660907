"""BreathingTorso.fmu on a subject mesh directory through fmpy: `subject.mesh_dir` refuses a
missing directory with a message naming it (the instance carries on), then accepts a directory
written by `torso mesh prepare` and breathes on it.

The FMU and the `torso` binary are built by scripts/test.sh before pytest runs.
"""

import pathlib
import subprocess

import pytest
from fmpy.fmi1 import FMICallException
from test_fmu_calls import ROOT, Host

TORSO = ROOT / "target" / "release" / "torso"


@pytest.fixture(scope="module")
def prepared(tmp_path_factory):
    assert TORSO.is_file(), f"{TORSO} missing: run `cargo build --release`"
    d = tmp_path_factory.mktemp("subject")
    subprocess.run([str(TORSO), "export-obj", "--lod", "0", str(d / "gen")], check=True)
    subprocess.run([str(TORSO), "mesh", "prepare", "--skin", str(d / "gen" / "skin.obj"),
                    "--abdomen", str(d / "gen" / "abdomen.obj"), "--out", str(d / "prepared")],
                   check=True, stdout=subprocess.DEVNULL)
    return d / "prepared"


def test_subject_mesh_dir_bad_then_good(prepared, tmp_path):
    h = Host()
    try:
        f = h.instantiate()
        vr = h.vr["subject.mesh_dir"]
        missing = str(tmp_path / "no_such_subject")
        with pytest.raises(FMICallException):
            f.setString([vr], [missing])
        assert "subject.mesh_dir" in h.last_error() and "no_such_subject" in h.last_error()
        f.setString([vr], [str(prepared)])
        f.setInteger([h.vr["scene.level_of_detail"]], [0])
        f.setReal([h.vr["drive.diaphragm.amplitude"]], [0.25])
        f.setReal([h.vr["drive.ribs.amplitude"]], [0.2])
        f.setupExperiment(startTime=0.0)
        f.enterInitializationMode()
        assert f.getString([vr]) == [str(prepared).encode()]
        f.exitInitializationMode()
        lung = []
        t = 0.0
        for _ in range(40):
            f.doStep(currentCommunicationPoint=t, communicationStepSize=0.25)
            t += 0.25
            lung.append(f.getReal([h.vr["volume.lung"]])[0])
        swing = max(lung[16:]) - min(lung[16:])
        assert 0.35 <= swing <= 0.8, swing
        # Fixed after initialisation: refused, and the run goes on.
        with pytest.raises(FMICallException):
            f.setString([vr], [""])
        f.doStep(currentCommunicationPoint=t, communicationStepSize=0.25)
    finally:
        h.close()
