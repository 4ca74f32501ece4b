# SPDX-License-Identifier: Apache-2.0
"""Volumes from Python: a phantom's layer values against the tissue table and
its own layer table, numpy arrays saved and reloaded unchanged, the same
phantom as `voxhap phantom` writes it, and one-line errors naming the file."""
import os
import pathlib
import numpy as np
import pytest

import voxhap

# Layer boundaries are located by bisection to 1e-9 mm (phantoms/Rasterize.h);
# the sums of thicknesses carry double round-off (2.000000000000001).
LAYER_TOL_MM = 1e-9
# An affine rebuilt from spacing and unit direction columns: a few ulps of 1 mm.
AFFINE_TOL = 1e-12

LAYERS = [("skin", 2.0), ("fat", 8.0), ("muscle", 20.0)]


@pytest.fixture(scope="module")
def slab():
    return voxhap.phantom("slab", layers=LAYERS, spacing=0.5)


@pytest.fixture(scope="module")
def tissues():
    return {t["name"]: t for t in voxhap.tissues()}


def array_index(volume, world):
    """The nearest array index of a world point, through the inverse 4x4 affine."""
    ijk = np.linalg.solve(volume.index_to_world, np.append(world, 1.0))[:3]
    return tuple(int(round(c)) for c in ijk)


def test_slab_layer_table_is_the_one_asked_for(slab):
    table = slab.phantom_layers()
    assert [l["tissue"] for l in table["layers"]] == [name for name, _ in LAYERS]
    start = 0.0
    for layer, (_, thickness) in zip(table["layers"], LAYERS):
        assert layer["start_mm"] == pytest.approx(start, abs=LAYER_TOL_MM)
        assert layer["end_mm"] == pytest.approx(start + thickness, abs=LAYER_TOL_MM)
        start += thickness
    np.testing.assert_array_equal(table["direction"], [0, -1, 0])


def test_slab_voxels_hold_each_layers_table_values(slab, tissues):
    """Mid-layer voxels on the reference path hold the tissue's id, typical HU and
    T1 at 1.5 T; a layer t mm thick is t / spacing voxels along the path, since its
    boundaries lie on voxel faces (physics.md §7 R1)."""
    label, hu, t1 = slab.grid("label"), slab.grid("hu"), slab.grid("t1")
    assert label.dtype == np.int32 and hu.dtype == np.float32 and hu.shape == slab.shape
    table = slab.phantom_layers()
    entry, direction = np.asarray(table["entry"]), np.asarray(table["direction"])
    spacing = slab.spacing[1]
    a, _, c = array_index(slab, entry + direction * 1.0)
    column = label[a, :, c]
    for layer in table["layers"]:
        t = tissues[layer["tissue"]]
        mid = array_index(slab, entry + direction * 0.5 * (layer["start_mm"] + layer["end_mm"]))
        assert label[mid] == t["id"]
        assert hu[mid] == np.float32(t["hu_typical"])
        assert t1[mid] == np.float32(t["t1_1p5t_ms"])
        voxels = int(np.count_nonzero(column == t["id"]))
        assert voxels == round((layer["end_mm"] - layer["start_mm"]) / spacing)
    # Air above the skin: label 0, the HU of air, inactive.
    above = array_index(slab, entry - direction * 2.0)
    assert label[above] == 0 and hu[above] == -1000.0


def test_same_phantom_as_the_command_line(slab, voxhap_bin, tmp_path):
    import subprocess
    out = tmp_path / "slab.vdb"
    subprocess.run([voxhap_bin, "phantom", "slab", "--layers", "skin:2,fat:8,muscle:20", "--out", str(out)],
                   check=True, capture_output=True)
    cli = voxhap.load(out)
    assert cli.shape == slab.shape
    np.testing.assert_allclose(cli.index_to_world, slab.index_to_world, rtol=0, atol=AFFINE_TOL)
    for name in ("hu", "t1", "label"):
        np.testing.assert_array_equal(cli.grid(name), slab.grid(name))


def test_numpy_volume_saved_and_reloaded_unchanged(tmp_path):
    """An anisotropic, rotated volume made from numpy arrays survives .vdb exactly
    (every grid) and .nrrd (hu as float32); the transform to 1e-12."""
    rng = np.random.default_rng(22)
    shape = (12, 9, 7)
    hu = rng.uniform(-500.0, 1500.0, shape).astype(np.float32)  # above the readers' air threshold
    label = rng.integers(0, 4, shape).astype(np.int32)
    angle = np.deg2rad(30.0)
    rotation = np.array([[np.cos(angle), -np.sin(angle), 0], [np.sin(angle), np.cos(angle), 0], [0, 0, 1]])
    affine = np.eye(4)
    affine[:3, :3] = rotation @ np.diag([0.7, 0.9, 2.5])
    affine[:3, 3] = [-40.0, 12.5, 100.0]
    v = voxhap.Volume(shape, affine)
    v.set_grid("hu", hu)
    v.set_grid("label", label)
    v.modality = "CT"
    np.testing.assert_allclose(v.index_to_world, affine, rtol=0, atol=AFFINE_TOL)

    voxhap.save(v, tmp_path / "v.vdb")
    back = voxhap.load(tmp_path / "v.vdb")
    assert back.shape == shape and sorted(back.channels) == ["hu", "label"]
    np.testing.assert_allclose(back.index_to_world, affine, rtol=0, atol=AFFINE_TOL)
    np.testing.assert_array_equal(back.grid("hu"), hu)
    np.testing.assert_array_equal(back.grid("label"), label)

    voxhap.save(v, tmp_path / "v.nrrd")
    nrrd = voxhap.load(tmp_path / "v.nrrd", modality="ct")
    np.testing.assert_allclose(nrrd.index_to_world, affine, rtol=0, atol=AFFINE_TOL)
    np.testing.assert_array_equal(nrrd.grid("hu"), hu)


def test_command_line_reads_the_python_volume(cli, tmp_path):
    shape = (10, 8, 6)
    affine = np.diag([0.8, 0.8, 3.0, 1.0])
    v = voxhap.Volume(shape, affine)
    v.set_grid("hu", np.full(shape, 40.0, np.float32))
    v.modality = "CT"
    voxhap.save(v, tmp_path / "v.nrrd")
    info = cli("info", tmp_path / "v.nrrd")
    assert info["dimensions"] == list(shape)
    assert info["spacing_mm"] == pytest.approx([0.8, 0.8, 3.0], abs=AFFINE_TOL)


def test_bad_input_is_one_clear_error(tmp_path):
    missing = tmp_path / "nowhere.nrrd"
    with pytest.raises(OSError, match="nowhere.nrrd"):
        voxhap.load(missing)
    v = voxhap.Volume((4, 4, 4))
    with pytest.raises(ValueError, match=r"shape \(4, 4, 4\)"):
        v.set_grid("hu", np.zeros((4, 4, 5), np.float32))
    with pytest.raises(ValueError, match="unknown|kind"):
        voxhap.phantom("teapot")


SHARED = pathlib.Path(__file__).resolve().parents[2].parent / "shared" / "data"


def shared_folder(*parts):
    folder = SHARED.joinpath(*parts)
    if not folder.is_dir():
        if os.environ.get("VOXHAP_REQUIRE_SHARED_DATA") or os.environ.get("VOXHAP_REQUIRE_ALL"):
            pytest.fail(f"no shared data at {folder}")
        pytest.skip(f"no shared data at {folder} (skipped locally; CI requires it)")
    return folder


def test_a_4d_dicom_series_loads_one_volume_at_a_time():
    # The Siemens diffusion series: 13 volumes of 25 slices (b=0, then 12 at b=1000; its README).
    # Without volume= the loader refuses and says so; volume=1 and volume=2 load those volumes,
    # on one grid, and the b=0 image is brighter than a diffusion-weighted one.
    dwi = shared_folder("mr-dwi-prisma", "dwi-mosaic")
    with pytest.raises(OSError, match="13 volumes"):
        voxhap.load(dwi)
    b0, b1000 = voxhap.load(dwi, volume=1), voxhap.load(dwi, volume=2)
    assert b0.shape == b1000.shape and 25 in b0.shape
    assert np.nanmean(b0.grid("intensity")) > np.nanmean(b1000.grid("intensity"))
    with pytest.raises(OSError):
        voxhap.load(dwi, volume=14)
    # The field map's echoes alternate irregularly (its README): one echo alone has uneven slice
    # spacing, which is refused, never stacked silently.
    with pytest.raises(OSError, match="non-uniform slice spacing"):
        voxhap.load(shared_folder("mr-head-trio", "gre-field-map"), volume=1)
