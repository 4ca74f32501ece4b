# SPDX-License-Identifier: Apache-2.0
"""Forces from Python against closed forms: the damping integral along a shaft
through a layered slab (physics.md §7 R1), one force-model step at a time
through the lumbar-puncture table (§4, §7 R2), and a scripted insertion the same
as `voxhap simulate` writes it."""
import csv
import json
import pathlib
import subprocess

import numpy as np
import pytest

import voxhap

# physics.md §7 R1: the exact voxel traversal is exact for a piecewise-constant
# field whose boundaries lie on voxel faces, to 1e-9 relative.
R1_REL_TOL = 1e-9
# physics.md §7 R2: the [LP] table through the force model to 1e-6 N.
R2_ABS_TOL_N = 1e-6
# The CSV of `voxhap simulate` prints 9 significant digits (setprecision(9)).
CSV_REL_TOL = 5e-9
CSV_ABS_TOL = 1e-12

LAYERS = [("skin", 2.0), ("fat", 8.0), ("muscle", 20.0)]


@pytest.fixture(scope="module")
def slab_field():
    slab = voxhap.phantom("slab", layers=LAYERS, spacing=0.5)
    return slab, voxhap.MaterialField(slab, damping=True)


def layer_betas(slab, beta):
    """beta [N s/mm^2] of each layer, read from the field's array at the layer's middle."""
    table = slab.phantom_layers()
    entry, direction = np.asarray(table["entry"]), np.asarray(table["direction"])
    inverse = np.linalg.inv(slab.index_to_world)
    out = []
    for layer in table["layers"]:
        mid = entry + direction * 0.5 * (layer["start_mm"] + layer["end_mm"])
        ijk = np.rint(inverse @ np.append(mid + [0.25, 0, 0.25], 1.0))[:3].astype(int)
        out.append((layer["start_mm"], layer["end_mm"] - layer["start_mm"], float(beta[tuple(ijk)])))
    return out


@pytest.mark.parametrize("theta_deg", [0.0, 30.0, 45.0])  # the shaft stays inside the 20 mm half-width block
def test_damping_integral_is_the_layered_closed_form(slab_field, theta_deg):
    """F(s) = v0 * sum_j beta_j * clip(s cos(theta) - z_j, 0, t_j) / cos(theta) (physics.md §7 R1)."""
    slab, field = slab_field
    betas = layer_betas(slab, field.damping)
    assert len({b for _, _, b in betas}) == 3, "the three layers must differ for the test to mean anything"
    theta = np.deg2rad(theta_deg)
    direction = np.array([np.sin(theta), -np.cos(theta), 0.0])
    integrator = voxhap.ShaftIntegrator(field, strategy="exact-voxel")
    for s in (0.7, 2.0, 9.3, 17.5, 25.0):
        depth = s * np.cos(theta)
        r = integrator.integrate([0.0, 0.0, 0.0], direction * s)
        expected = sum(b * np.clip(depth - z, 0.0, t) / np.cos(theta) for z, t, b in betas)
        assert r["length_mm"] == pytest.approx(s, rel=R1_REL_TOL)
        assert r["damping_integral"] == pytest.approx(expected, rel=R1_REL_TOL)
        for (name, _), (z, t, _) in zip(LAYERS, betas):
            chord = np.clip(depth - z, 0.0, t) / np.cos(theta)
            assert r["label_length_mm"].get(name, 0.0) == pytest.approx(chord, rel=R1_REL_TOL, abs=1e-12)


# physics.md §4, [LP] Table I: end of layer [mm], k [N/m], b [N s/m^2], C [N].
LP_TABLE = [("out of skin", 5, 0, 0.0, 0.0), ("skin", 7, 330, 2.1, 0.3), ("fat", 14, 0, 1.0, 0.3),
            ("ligament", 30, 550, 3.0, 0.5), ("dura", 35, 980, 3.3, 0.6), ("puncture aim", 48, 0, 1.6, 0.2),
            ("bone", 55, 2370, 0.0, 0.0)]
# physics.md §4 reference values at v = 0.02 m/s: depth [mm] -> |f| [N], printed to 4 decimals (3 above 10 N).
BONE_TEXTURE_N = 0.3  # the lumbar-puncture scene's [LP] bone texture c (physics.md §4)
LP_REFERENCE = {6: 0.6300, 6.99: 0.9568, 10: 0.3001, 20: 3.8006, 29.99: 9.2957, 32: 2.5613, 34.99: 5.4917,
                40: 0.2017, 50: 4.7419, 54.99: 16.568}


def lp_closed_form(depth, v):
    """[LP] Eq. 1-3 at table depth [mm], speed v [mm/s]: k x of the layer at the tip,
    its C, and sum_i b_i l_i v over the shaft (physics.md §4, "Interpretation")."""
    start, force = 0.0, 0.0
    for _, end, k, b, c in LP_TABLE:
        length = np.clip(depth - start, 0.0, end - start)
        force += b * 1e-6 * length * v  # N s/m^2 -> N s/mm^2
        if start <= depth < end:
            force += k * 1e-3 * (depth - start) + c  # N/m -> N/mm
        start = end
    return force


def test_force_model_steps_through_the_lumbar_puncture_table():
    scene = voxhap.Scene("lumbar-puncture")
    # The scene's depth 0 is the skin: the table's 5 mm "out of skin" lie before it.
    assert scene.layers[0]["name"] == "out of skin" and scene.layers[0]["start_mm"] == -5.0
    model = scene.model()
    direction = (scene.target - scene.entry) / np.linalg.norm(scene.target - scene.entry)
    speed, rate = 20.0, 2000.0  # 0.01 mm a tick: every reference depth is a tick
    matched = 0
    for i in range(int(round(55.0 / (speed / rate))) + 1):
        depth = -5.0 + i * speed / rate
        out = model.step(scene.entry + direction * depth, direction, direction * speed, i / rate, 1.0 / rate)
        table_depth = round(depth + 5.0, 6)
        if table_depth in LP_REFERENCE:
            # The table's values leave out [LP]'s bone texture, -c sgn(v) while the tip is in bone, which
            # the scene turns on (data/scenes/lumbar-puncture.json "bone_texture": c_N 0.3): it adds c there.
            texture = BONE_TEXTURE_N if table_depth >= 48 else 0.0
            printed = LP_REFERENCE[table_depth] + texture
            assert out["axial_N"] == pytest.approx(printed, abs=5e-4 if printed >= 10 else 5e-5), table_depth
            expected = lp_closed_form(depth + 5.0, speed) + texture
            assert out["axial_N"] == pytest.approx(expected, abs=R2_ABS_TOL_N), table_depth
            matched += 1
    assert matched == len(LP_REFERENCE)


def test_simulate_is_what_the_command_line_writes(voxhap_bin, tmp_path):
    ours = voxhap.simulate("senac-average")
    subprocess.run([voxhap_bin, "simulate", "--scene", "senac-average", "--out", str(tmp_path), "--no-plot"],
                   check=True, capture_output=True)
    with open(tmp_path / "insertion.csv" if (tmp_path / "insertion.csv").exists() else
              next(tmp_path.glob("*.csv")), newline="") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == len(ours["depth_mm"]) > 1000
    for column, key in (("t_s", "time_s"), ("depth_mm", "depth_mm"), ("force_N", "force_N"),
                        ("axial_model_N", "axial_N"), ("plunger_N", "plunger_N")):
        theirs = np.array([float(r[column]) for r in rows])
        np.testing.assert_allclose(ours[key], theirs, rtol=CSV_REL_TOL, atol=CSV_ABS_TOL, err_msg=column)
    events = [e for r in rows for e in r["events"].split(";") if e]
    assert [e["type"] for e in ours["events"]] == events
    # The summary's loss of resistance is at the epidural space of the average patient: derma 10 mm,
    # ligaments 3 + 15 + ... (scene file): the event's depth and the summary agree.
    lor = [e["depth_mm"] for e in ours["events"] if e["type"] == "loss_of_resistance"]
    assert lor and ours["summary"]["loss_of_resistance_mm"] == pytest.approx(lor[0], abs=1e-12)


def rendered_over_model_before_limits(run):
    """Each tick's rendered |F| over the model's axial force while no device limit can act: before bone
    contact and before the model's force first reaches the kyung device's continuous force (1.4 N,
    physics.md §6.3: below it the I²t budget is untouched), on ticks with at least 0.05 N of model force."""
    bone = min([e["depth_mm"] for e in run["events"] if e["type"] == "bone_contact"] or [np.inf])
    over = np.nonzero(np.abs(run["axial_N"]) >= 1.4)[0]
    tick = np.arange(run["axial_N"].size)
    before = (run["depth_mm"] < bone) & (tick < (over[0] if over.size else tick.size))
    before &= np.abs(run["axial_N"]) >= 0.05
    return run["force_N"][before] / np.abs(run["axial_N"][before]), run["axial_N"][before]


def test_simulate_reports_the_scenes_force_scale(tmp_path, source_dir):
    # kyung renders half its model force (data/scenes/kyung.json "force_scale": 0.5). While no device
    # limit acts, every tick renders exactly half the model's force along the straight path, and the
    # model's force there is real (skin, fat and muscle damping, over 1 N): a run that rendered nothing,
    # or all of it, fails. The control is the same scene at force_scale 1, whose ticks render the whole
    # model force and so fail the check for one half.
    kyung = voxhap.simulate("kyung")
    assert kyung["summary"]["force_scale"] == 0.5
    ratio, model = rendered_over_model_before_limits(kyung)
    assert ratio.size > 100 and np.max(np.abs(model)) > 1.0
    np.testing.assert_allclose(ratio, 0.5, rtol=1e-9)
    scene = json.loads(pathlib.Path(source_dir, "data", "scenes", "kyung.json").read_text())
    scene["name"], scene["force_scale"] = "kyung-whole", 1.0
    (tmp_path / "kyung-whole.json").write_text(json.dumps(scene))
    whole = voxhap.simulate(str(tmp_path / "kyung-whole.json"))
    assert whole["summary"]["force_scale"] == 1.0
    ratio, model = rendered_over_model_before_limits(whole)
    assert ratio.size > 100
    np.testing.assert_allclose(ratio, 1.0, rtol=1e-9)
    assert not np.allclose(ratio, 0.5, rtol=1e-9)
