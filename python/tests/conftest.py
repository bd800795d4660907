"""Shared checks for the Python tests: no test may leave the process in another working
directory (fmpy loads an FMU's library with a process-wide chdir and back, and a test that
races it would leave later tests in a deleted folder)."""

import os

import pytest


@pytest.fixture(autouse=True)
def working_directory_is_kept():
    before = os.getcwd()
    yield
    after = os.getcwd()
    assert after == before, f"the test left the working directory at {after} (was {before})"
