# SPDX-License-Identifier: Apache-2.0
"""Shared fixtures of the Python module's tests (run by ctest: tests/python/CMakeLists.txt).

PYTHONPATH holds <build>/python (the voxhap package); VOXHAP_BIN names the
command-line program the results are compared with, when it was built.
"""
import json
import os
import subprocess

import pytest


@pytest.fixture(scope="session")
def voxhap_bin():
    path = os.environ.get("VOXHAP_BIN", "")
    if not path or not os.access(path, os.X_OK):
        pytest.skip("the voxhap program was not built (VOXHAP_WITH_RENDER or VOXHAP_WITH_IGTL off): "
                    "nothing to compare with")
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
