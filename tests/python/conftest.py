# SPDX-License-Identifier: Apache-2.0
"""Shared fixtures of the Python module's tests (run by ctest: tests/python/CMakeLists.txt).

PYTHONPATH holds <build>/python (the voxhap package); VOXHAP_BIN names the
command-line program the results are compared with, when it was built.

A missing prerequisite (the program, the shared data) skips a test locally and
fails it when VOXHAP_REQUIRE_ALL is set (CI: .ci/run), naming what is missing.
"""
import json
import os
import subprocess

import pytest


def missing(what):
    """Skip the calling test (locally) or fail it (VOXHAP_REQUIRE_ALL), naming @p what."""
    if os.environ.get("VOXHAP_REQUIRE_ALL"):
        pytest.fail(f"missing prerequisite: {what} (VOXHAP_REQUIRE_ALL is set)")
    pytest.skip(f"{what} (skipped locally; VOXHAP_REQUIRE_ALL fails it)")


_skipped = []


def pytest_runtest_logreport(report):
    if report.skipped:
        _skipped.append(report.nodeid)


def pytest_sessionfinish(session, exitstatus):
    # A run that passed but skipped a test exits 77, which ctest counts as skipped
    # (tests/python/CMakeLists.txt): a skip never shows as a pass. Failures keep their status.
    if exitstatus == 0 and _skipped:
        session.exitstatus = 77


@pytest.fixture(scope="session")
def voxhap_bin():
    path = os.environ.get("VOXHAP_BIN", "")
    if not path or not os.access(path, os.X_OK):
        missing("the voxhap program to compare with (VOXHAP_BIN: a build with VOXHAP_WITH_RENDER and "
                "VOXHAP_WITH_IGTL)")
    return path


@pytest.fixture(scope="session")
def cli(voxhap_bin):
    """Run `voxhap ARGS --json` and return its parsed JSON (a failure shows stderr)."""
    def run(*args):
        p = subprocess.run([voxhap_bin, *map(str, args), "--json"], capture_output=True, text=True, check=False)
        assert p.returncode == 0, f"voxhap {' '.join(map(str, args))}: {p.stderr}"
        return json.loads(p.stdout)
    return run


@pytest.fixture(scope="session")
def source_dir():
    return os.environ["VOXHAP_SOURCE_DIR"]
