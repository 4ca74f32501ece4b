# SPDX-License-Identifier: Apache-2.0
"""Devices by name from Python, run by the servo loop in simulated time and by
one servo tick at a time (docs/reference.md "Python"): the scripted device
follows its closed form, a recorded session replays the poses it recorded, the
simulated hand stops or not at the loss of resistance, and a Python loop of
ServoStep ticks renders the same forces as ServoLoop."""
import csv
import json
import os
import socket
import subprocess
import sys

import numpy as np
import pytest

import voxhap

# Tips are sums of a few products of doubles of order 100 mm.
POSITION_MM = 1e-9
# session.csv is written at 10 significant digits: 1e-7 mm on tips of order 100 mm.
CSV_MM = 1e-6


@pytest.fixture(scope="module")
def scene():
    return voxhap.Scene("senac-average")


def test_every_kind_of_this_build_is_listed_and_bad_names_are_refused(scene):
    kinds = voxhap.device_kinds()
    assert kinds[:3] == ["hand", "sim", "replay:FILE"]
    with pytest.raises(ValueError, match="device 'bogus' is not hand, sim.* replay:FILE"):
        voxhap.make_device("bogus", scene.model())
    with pytest.raises(ValueError, match="takes no argument"):
        voxhap.make_device("hand:2", scene.model())


def test_scripted_device_in_the_servo_loop_follows_its_closed_form(scene):
    """sim: depth(t) = -approach + v t along the path, until the depth; the force is zero in air."""
    model = scene.model()
    device = voxhap.make_device("sim", model, speed=20.0, depth=30.0)
    assert device.name == "sim-script"
    loop = voxhap.ServoLoop(model, device, rate_hz=1000.0)
    loop.run_ticks(2000)
    r = loop.records()
    t = r["time_s"]
    assert len(t) > 1500 and t[1] - t[0] == pytest.approx(1e-3, rel=1e-12)
    depth = np.minimum(-scene.approach_mm + 20.0 * t, 30.0)
    expected = np.asarray(model.path_origin) + depth[:, None] * np.asarray(model.path_direction)
    assert np.abs(r["tip"] - expected).max() < POSITION_MM
    in_air = depth < -0.5
    assert in_air.any() and np.abs(r["force"][in_air]).max() == 0.0
    assert np.linalg.norm(r["force"], axis=1).max() > 1.0, "the skin must push back"
    assert "skin_contact" in {e["type"] for e in loop.events()}


def test_replay_plays_the_recorded_poses(scene, tmp_path):
    """A session recorded from the scripted device, written as session.csv, replays its tips."""
    model = scene.model()
    loop = voxhap.ServoLoop(model, voxhap.make_device("sim", model, speed=20.0, depth=20.0))
    loop.run_ticks(300)
    rec = loop.records()
    path = tmp_path / "session.csv"
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["t_s", "tip_x_mm", "tip_y_mm", "tip_z_mm", "dir_x", "dir_y", "dir_z"])
        for t, tip in zip(rec["time_s"], rec["tip"]):
            w.writerow([f"{t:.10g}"] + [f"{x:.10g}" for x in tip] + [f"{x:.10g}" for x in model.path_direction])
    replay = voxhap.make_device(f"replay:{path}", scene.model())
    assert replay.name == "replay"
    for i in (0, 150, 299):
        got = replay.read(rec["time_s"][i] - rec["time_s"][0])
        assert got["valid"]
        assert np.abs(np.asarray(got["tip"]) - rec["tip"][i]).max() < CSV_MM
    with pytest.raises(OSError):
        voxhap.make_device(f"replay:{tmp_path / 'none.csv'}", scene.model())


@pytest.mark.parametrize("careful", [True, False])
def test_the_hand_stops_at_the_loss_of_resistance_only_when_careful(scene, careful):
    """senac-average: the careful hand stops in the epidural space, the reckless one punctures the dura."""
    model = scene.model()
    hand = voxhap.make_device("hand", model, speed=1.0 if careful else 10.0, careful=careful)
    assert hand.name == "sim-hand"
    loop = voxhap.ServoLoop(model, hand)
    loop.run_ticks(60000 if careful else 15000)
    types = {e["type"] for e in loop.events()}
    assert "loss_of_resistance" in types
    assert ("dura_puncture" in types) == (not careful)


def test_a_python_loop_of_servo_steps_renders_what_the_servo_loop_renders(scene):
    """The same hand, ticked by ServoLoop.run_ticks and by ServoStep.step in Python at the same times: bit for bit."""
    model_a, model_b = scene.model(), scene.model()
    loop = voxhap.ServoLoop(model_a, voxhap.make_device("hand", model_a, speed=5.0))
    loop.run_ticks(3000)
    expected = loop.records()["force"]
    hand = voxhap.make_device("hand", model_b, speed=5.0)
    step = voxhap.ServoStep(model_b)
    # The loop's clock: one period added per tick (ServoLoop.run_ticks does the same sum).
    forces, t = [], 0.0
    for _ in range(3000):
        forces.append(step.step(hand, t))
        t += 1.0 / 1000.0
    forces = np.array(forces)
    assert np.linalg.norm(expected, axis=1).max() > 1.0, "the comparison must cover a force"
    np.testing.assert_array_equal(forces, expected)
    assert step.output["depth_mm"] > 0.0


def test_igtl_is_made_by_name_when_this_build_has_it(scene):
    if "igtl[:PORT]" not in voxhap.device_kinds():
        pytest.skip("built without OpenIGTLink (VOXHAP_WITH_IGTL=OFF): the kind is not in this build")
    with socket.socket() as s:  # a free port
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    device = voxhap.make_device(f"igtl:{port}", scene.model())
    assert device.name == f"igtl:{port}"
    assert not device.read(0.0)["valid"], "no client has sent a pose"
    with pytest.raises(ValueError, match="the port must be a number"):
        voxhap.make_device("igtl:80x", scene.model())


def test_the_device_example_runs_both_loops_alike(source_dir):
    """examples/python/device_by_name.py: voxhap's loop and a Python loop of ticks give the same events and peak."""
    script = os.path.join(source_dir, "examples", "python", "device_by_name.py")
    outputs = []
    for loop in ("servo", "step"):
        p = subprocess.run([sys.executable, script, "--device", "hand", "--loop", loop, "--seconds", "6",
                            "--speed", "10"], capture_output=True, text=True, check=False)
        assert p.returncode == 0, p.stderr
        outputs.append([json.loads(line) for line in p.stdout.splitlines()])
    assert outputs[0] == outputs[1]
    assert "loss_of_resistance" in {line.get("event") for line in outputs[0]}
    assert outputs[0][-1]["device"] == "sim-hand" and outputs[0][-1]["peak_force_N"] > 1.0
