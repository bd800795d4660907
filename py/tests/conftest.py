"""Shared fixtures of the installed package's tests (scripts/test-wheel.sh runs them from a
fresh venv outside the source tree).

BT_TORSO names the `torso` command-line tool the package is compared with (the same source),
BT_DATA the repository's data/ folder (the bundled recordings). A recording made once by
`torso synth` (level of detail 0, 12 s at 20 Hz) serves every fit test.
"""

import os
import subprocess
from pathlib import Path

import pytest


def _env_path(name):
    value = os.environ.get(name)
    if not value:
        pytest.fail(f"{name} is not set (scripts/test-wheel.sh sets it)")
    path = Path(value)
    assert path.exists(), f"{name}={value} does not exist"
    return path


@pytest.fixture(scope="session")
def torso_cli():
    """The `torso` executable built from the same source as the wheel."""
    return _env_path("BT_TORSO")


@pytest.fixture(scope="session")
def data_dir():
    """The repository's data/ folder."""
    return _env_path("BT_DATA")


def run_cli(torso_cli, *args, cwd=None):
    """Runs `torso args...`; fails the test with its stderr when it fails."""
    done = subprocess.run(
        [str(torso_cli), *map(str, args)], cwd=cwd, capture_output=True, text=True
    )
    assert done.returncode == 0, f"torso {' '.join(map(str, args))} failed:\n{done.stderr}"
    return done


@pytest.fixture(scope="session")
def synth_recording(torso_cli, tmp_path_factory):
    """A grid recording of the default subject at level of detail 0 (12 s, 20 Hz, 1 %
    dropout), made by `torso synth`."""
    d = tmp_path_factory.mktemp("synth")
    run_cli(
        torso_cli, "synth", "--out", d / "rec.csv", "--truth", d / "truth.json", "--lod", "0",
        "--duration", "12", "--rate", "20", "--seed", "3", "--dropout", "0.01",
    )
    return d / "rec.csv"
