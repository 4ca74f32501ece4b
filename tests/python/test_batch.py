# SPDX-License-Identifier: Apache-2.0
"""voxhap.batch (batch/Batch.h): the cohort runner of `voxhap batch` from Python.

Jobs run by the voxhap program Python names give the records and cohort table
the command line's own run gives; a done job is kept, a forced one runs again;
without the program the call is refused in one line.
"""
import json

import pytest

import voxhap
import voxhap.batch  # noqa: F401  (the submodule imports by name too)

MANIFEST = {
    "schema": "voxhap-batch/1",
    "defaults": {"simulate": ["--no-plot"]},
    "jobs": [
        {"id": "conci-sim", "command": "simulate", "args": ["--scene", "conci"]},
        {"id": "lost-seg", "command": "segment", "volume": "missing.vdb"},
    ],
}


def write_manifest(folder, output):
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / "m.json"
    path.write_text(json.dumps(dict(MANIFEST, output=output)))
    return path


def test_refused_without_the_program(tmp_path):
    manifest = write_manifest(tmp_path, "out")
    with pytest.raises(ValueError, match="program: the path of the voxhap executable is required"):
        voxhap.batch.run(manifest)
    # Control: a path that is not a program is refused too, naming it, before any job starts.
    with pytest.raises(OSError, match="is not an executable file"):
        voxhap.batch.run(manifest, program=manifest)
    assert not (tmp_path / "out").exists()


def test_jobs_run_kept_and_merged_as_the_command_line_does(tmp_path, voxhap_bin):
    import subprocess

    ours = write_manifest(tmp_path / "py", "out")
    theirs = write_manifest(tmp_path / "cli", "out")
    runs = voxhap.batch.run(ours, program=voxhap_bin)
    p = subprocess.run([voxhap_bin, "batch", str(theirs), "--json"], capture_output=True, text=True, check=False)
    assert p.returncode == 1, p.stderr  # one job fails: exit 1
    cli_runs = json.loads(p.stdout)["jobs"]
    assert [(r["id"], r["status"], r["exit_code"]) for r in runs] == [
        (r["id"], r["status"], r["exit_code"]) for r in cli_runs
    ]
    assert [r["status"] for r in runs] == ["done", "failed"]
    assert "missing.vdb" in runs[1]["error"] and runs[1]["error"] == cli_runs[1]["error"].replace("/cli/", "/py/")
    # The done job's record: the same fingerprint and the same simulation as the command line's.
    rec = json.loads((tmp_path / "py/out/conci-sim/job.json").read_text())
    cli_rec = json.loads((tmp_path / "cli/out/conci-sim/job.json").read_text())
    assert rec["fingerprint"] == cli_rec["fingerprint"]
    for key in ("pops", "peak_force_n", "max_depth_mm"):
        if key in cli_rec["result"]:
            assert rec["result"][key] == cli_rec["result"][key], key

    # Done jobs are kept on a rerun; forced, they run again; the failed one runs again.
    again = voxhap.batch.run(ours, program=voxhap_bin)
    assert [r["status"] for r in again] == ["kept", "failed"]
    forced = voxhap.batch.run(ours, program=voxhap_bin, index=0, force=True)
    assert [(r["id"], r["status"]) for r in forced] == [("conci-sim", "done")]
    assert [(j["id"], j["status"]) for j in voxhap.batch.jobs(ours)] == [("conci-sim", "done"), ("lost-seg", "failed")]

    merged = voxhap.batch.merge(ours)
    assert merged["counts"] == {"done": 1, "failed": 1, "not run": 0} and not merged["all_done"]
    table = merged["csv"].read_text().splitlines()
    subprocess.run([voxhap_bin, "batch", "merge", str(theirs)], capture_output=True, check=False)
    cli_table = (tmp_path / "cli/out/cohort.csv").read_text().splitlines()
    assert len(table) == 3 and table[0] == cli_table[0]  # the same columns, one row per job
    with pytest.raises(ValueError, match="is past the last job"):
        voxhap.batch.run(ours, program=voxhap_bin, index=2)
