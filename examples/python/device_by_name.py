#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Drive a scene with a haptic device chosen by name, from Python.

The device is any kind this build knows (voxhap.device_kinds(): the simulated
hand, a scripted insertion, a recorded session, an OpenIGTLink server, a
driver's kind), made for the scene's force model. It runs either in voxhap's
servo loop, here in simulated time (`--loop servo`), or in a loop written in
Python that calls one servo tick at a time (`--loop step`), as a device SDK's
callback would.

    PYTHONPATH=build/python /usr/bin/python3 examples/python/device_by_name.py --device hand
    PYTHONPATH=build/python /usr/bin/python3 examples/python/device_by_name.py --device sim --loop step \
        --scene lumbar-puncture --seconds 4

Prints one JSON line per event, then one with the peak force and the last depth.
"""
import argparse
import json
import sys

import numpy as np

import voxhap


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--scene", default="senac-average", help="a built-in scene name or a scene file")
    p.add_argument("--device", default="hand", help="one of: " + ", ".join(voxhap.device_kinds()))
    p.add_argument("--loop", choices=["servo", "step"], default="servo")
    p.add_argument("--seconds", type=float, default=10.0, help="simulated time [s]")
    p.add_argument("--speed", type=float, help="insertion speed [mm/s] (default: the scene's)")
    a = p.parse_args()

    scene = voxhap.Scene(a.scene)
    model = scene.model()
    device = voxhap.make_device(a.device, model, speed=a.speed)
    rate = scene.rate_hz
    ticks = int(round(a.seconds * rate))
    if a.loop == "servo":
        loop = voxhap.ServoLoop(model, device, rate_hz=rate)
        loop.run_ticks(ticks)
        events, records = loop.events(), loop.records()
        peak = float(np.linalg.norm(records["force"], axis=1).max(initial=0.0))
        depth = float(records["depth_mm"][-1]) if len(records["depth_mm"]) else 0.0
    else:
        step = voxhap.ServoStep(model, rate_hz=rate)
        events, peak, depth, t = [], 0.0, 0.0, 0.0
        for _ in range(ticks):
            if device.finished:
                break
            force = step.step(device, t)
            t += 1.0 / rate  # the clock advances by one period per tick, as voxhap's loop's does
            events += step.output["events"]
            peak = max(peak, float(np.linalg.norm(force)))
            depth = step.output["depth_mm"]
    for e in events:
        print(json.dumps({"event": e["type"], "depth_mm": round(e["depth_mm"], 3), "layer": e["layer"]}))
    print(json.dumps({"device": device.name, "peak_force_N": peak, "depth_mm": depth}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
