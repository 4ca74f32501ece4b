# SPDX-License-Identifier: Apache-2.0
"""A pytest case whose prerequisite is missing on purpose, and one that fails on
request (VOXHAP_PROBE_FAIL), for tests/prerequisites/CheckSwitch.sh. Not one of
the module's tests: its name is not test_*.py and no ctest entry runs it."""
import os

from conftest import missing


def test_missing_prerequisite():
    missing("the probe's missing tool")


def test_fails_on_request():
    assert "VOXHAP_PROBE_FAIL" not in os.environ, "failed on request"
