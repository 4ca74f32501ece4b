# SPDX-License-Identifier: Apache-2.0
"""Segmentation and planning from Python give what `voxhap segment` and
`voxhap plan` give on the same volume, and a planned path's geometry adds up."""
import subprocess

import numpy as np
import pytest

import voxhap

# Path geometry: segment lengths are differences of depths along one straight line [mm];
# double round-off over ~100 mm and a few dozen segments.
GEOMETRY_TOL_MM = 1e-9
# Markups are written with every digit and read back through one sign flip at most
# (RAS/LPS): exact, up to the text's last digit of a coordinate of order 100 mm.
MARKUPS_TOL_MM = 1e-12


@pytest.fixture(scope="module")
def torso(tmp_path_factory):
    """The spine-biopsy torso at 1 mm (planning tests need no finer), saved for the program."""
    v = voxhap.phantom("torso", spacing=1.0)
    path = tmp_path_factory.mktemp("torso") / "torso.vdb"
    voxhap.save(v, path)
    return v, path


def test_segment_matches_the_command_line(torso, cli, tmp_path):
    v, path = torso
    ours = v.copy()
    report = voxhap.segment(ours)
    theirs = cli("segment", path, "--out", tmp_path / "seg.vdb")
    assert report["method"] == theirs["method"] == "ct"
    assert [(l["id"], l["name"], l["voxels"]) for l in report["labels"]] == \
        [(l["id"], l["name"], l["voxels"]) for l in theirs["labels"]]
    assert report["distance_fields"] == theirs["distance_fields"] and report["distance_fields"]
    seg = voxhap.load(tmp_path / "seg.vdb")
    np.testing.assert_array_equal(ours.grid("label"), seg.grid("label"))
    for name in report["distance_fields"]:
        np.testing.assert_array_equal(ours.grid(name), seg.grid(name))
    # The copy was segmented; the phantom it came from keeps its own labels and no distance field.
    assert not v.derived_names


def test_plan_search_matches_the_command_line(torso, cli, tmp_path):
    v, path = torso
    target = v.landmark("lesion")
    assert target is not None
    ours = voxhap.plan(v, target, top=5, name=str(path))
    theirs = cli("plan", path, "--target", ",".join(map(str, target)), "--top", "5", "--no-views",
                 "--out", tmp_path / "plan")
    assert ours["schema"] == theirs["schema"] == "voxhap-plan-report/1"
    assert len(ours["paths"]) == len(theirs["paths"]) > 0
    for a, b in zip(ours["paths"], theirs["paths"]):
        # The same code on the same grids: the same numbers, bit for bit through JSON.
        assert a["entry"] == b["entry"] and a["risk"] == b["risk"]
        assert a["length_mm"] == b["length_mm"] and a["segments"] == b["segments"] and a["force"] == b["force"]
    for key in ("directions", "analysed", "feasible"):
        assert ours["search"][key] == theirs["search"][key]
    # The files it wrote read back through the one plan-file reader: the report's
    # paths in rank order, bit for bit through JSON; the markups' Lines in LPS.
    from_report = voxhap.load_plan(tmp_path / "plan" / "report.json")
    assert [p["name"] for p in from_report] == [f"path {i + 1}" for i in range(len(theirs["paths"]))]
    for read, written in zip(from_report, theirs["paths"]):
        assert list(read["entry"]) == written["entry"] and list(read["target"]) == written["target"]
    from_markups = voxhap.load_plan(tmp_path / "plan" / "paths.mrk.json")
    assert len(from_markups) == len(theirs["paths"])
    np.testing.assert_allclose(from_markups[0]["entry"], theirs["paths"][0]["entry"], rtol=0, atol=MARKUPS_TOL_MM)


def test_planned_path_geometry_adds_up(torso):
    v, _ = torso
    target = np.asarray(v.landmark("lesion"))
    report = voxhap.plan(v, target, top=3)
    assert report["paths"], "the torso's lesion has a feasible posterior path"
    for p in report["paths"]:
        entry = np.asarray(p["entry"])
        np.testing.assert_allclose(p["target"], target, rtol=0, atol=GEOMETRY_TOL_MM)
        assert p["length_mm"] == pytest.approx(np.linalg.norm(target - entry), abs=GEOMETRY_TOL_MM)
        segments = p["segments"]
        assert segments[0]["start_mm"] == pytest.approx(0.0, abs=GEOMETRY_TOL_MM)
        assert segments[-1]["end_mm"] == pytest.approx(p["length_mm"], abs=GEOMETRY_TOL_MM)
        for before, after in zip(segments, segments[1:]):
            assert after["start_mm"] == pytest.approx(before["end_mm"], abs=GEOMETRY_TOL_MM)
    # Analysing the best entry again gives the same path: search and analyse agree.
    best = report["paths"][0]
    again = voxhap.plan(v, target, entry=best["entry"])["paths"][0]
    assert again["length_mm"] == pytest.approx(best["length_mm"], abs=GEOMETRY_TOL_MM)
    assert again["risk"]["total"] == pytest.approx(best["risk"]["total"], rel=1e-9)


def test_plan_refuses_a_target_outside_the_volume(torso):
    v, _ = torso
    with pytest.raises(ValueError, match="outside the volume"):
        voxhap.plan(v, [0.0, 0.0, 5000.0])
