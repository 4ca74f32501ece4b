# SPDX-License-Identifier: Apache-2.0
"""voxhap.fuse from Python: a phantom's CT and its MR in a frame shifted by a
known translation come back as one volume whose record holds that translation;
the MR given first is refused in the command line's one line."""
import numpy as np
import pytest

import voxhap

# The translation the MR's frame is moved by [mm]: a few voxels on every axis.
SHIFT = np.array([9.0, -6.0, 12.0])
# The registration's own error on the phantoms is about 0.3 mm (docs/reference.md
# "CT and MR fusion"); half a 1.5 mm voxel bounds it with room for the coarser MR.
SHIFT_TOL_MM = 0.75


@pytest.fixture(scope="module")
def pair(tmp_path_factory):
    d = tmp_path_factory.mktemp("fusion")
    torso = voxhap.phantom("lumbar", spacing=1.5)
    ct = voxhap.Volume(torso.shape, torso.index_to_world)
    ct.set_grid("hu", torso.grid("hu"))
    ct.modality = "CT"
    moved = np.array(torso.index_to_world)
    moved[:3, 3] += SHIFT
    mr = voxhap.Volume(torso.shape, moved)
    mr.set_grid("t1", torso.grid("t1"))
    mr.modality = "MR"
    voxhap.save(ct, d / "ct.nrrd")
    voxhap.save(mr, d / "mr.nrrd")
    return d


def test_fuse_recovers_the_known_shift_and_writes_both_files(pair):
    out = pair / "fused.vdb"
    r = voxhap.fuse(pair / "ct.nrrd", pair / "mr.nrrd", out=out)
    m = np.array(r["record"]["mr_from_ct"])
    # The MR sees the CT point x at x + SHIFT: a pure translation by SHIFT.
    # No turn: SHIFT_TOL_MM / 100 = 0.0075 per matrix element, about 0.43°,
    # which moves a point 100 mm from the centre (the phantom's half-width) by 0.75 mm.
    assert np.allclose(m[:3, :3], np.eye(3), atol=SHIFT_TOL_MM / 100.0)
    assert np.linalg.norm(m[:3, 3] - SHIFT) <= SHIFT_TOL_MM, m[:3, 3]
    v = r["volume"]
    assert "hu" in v and "t1" in v and "label" in v
    assert out.exists() and out.with_suffix(".tfm").exists()
    again = voxhap.load(out)
    assert np.allclose(np.array(again.metadata["fusion"]["mr_from_ct"]), m)
    assert 0.0 < r["damping_from_t1_fraction"] <= 1.0


def test_the_mr_given_first_is_refused_and_nothing_is_written(pair):
    out = pair / "swapped.vdb"
    with pytest.raises(ValueError, match="give the CT first"):
        voxhap.fuse(pair / "mr.nrrd", pair / "ct.nrrd", out=out)
    assert not out.exists() and not out.with_suffix(".tfm").exists()
