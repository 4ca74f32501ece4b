#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""`voxhap regress --junit FILE` writes well-formed JUnit XML (issue 29 item 4).

Runs a few cases of the built-in suite against a tissue table whose skin
cutting force is raised by 5 %: the Senac cases (which cut the skin) fail and
the Kyung slab (voxel damping only) passes. The XML must parse, its counts must
match its test cases, and each failing case must carry a <failure> that names
the edited parameter.

usage: check_junit.py VOXHAP TISSUES_JSON WORKDIR
"""
import json
import os
import subprocess
import sys
import xml.etree.ElementTree as ET

voxhap, tissues, work = sys.argv[1:4]
os.makedirs(work, exist_ok=True)
table = json.load(open(tissues))
for t in table["tissues"]:
    if t["name"] == "skin":
        t["cutting_force"]["value"] = round(t["cutting_force"]["value"] * 1.05, 6)
edited = os.path.join(work, "tissues-skin-cutting.json")
json.dump(table, open(edited, "w"), indent=1)
xml_file = os.path.join(work, "report.xml")
if os.path.exists(xml_file):
    os.remove(xml_file)

run = subprocess.run([voxhap, "regress", "--only", "senac-average,senac-calcified,slab-servo", "--tissues", edited,
                      "--junit", xml_file, "--no-plots"], capture_output=True, text=True)
assert run.returncode == 1, f"expected exit 1 (a regression), got {run.returncode}: {run.stderr}"

root = ET.parse(xml_file).getroot()  # raises on malformed XML
assert root.tag == "testsuites", root.tag
cases = root.findall("./testsuite/testcase")
failures = root.findall("./testsuite/testcase/failure")
assert int(root.get("tests")) == len(cases), (root.get("tests"), len(cases))
assert int(root.get("failures")) == len(failures), (root.get("failures"), len(failures))
by_name = {c.get("name"): c for c in cases}
assert by_name["slab-servo"].find("failure") is None, "the Kyung slab has no cutting term"
for name in ("senac-average", "senac-calcified"):
    f = by_name[name].find("failure")
    assert f is not None, f"{name} should fail: it cuts the skin"
    assert "skin.cutting_force" in f.text, f.text
print(f"ok: {len(cases)} test cases, {len(failures)} failures")
