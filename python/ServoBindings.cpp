// SPDX-License-Identifier: Apache-2.0
/// @file ServoBindings.cpp
/// @brief Python: devices by name (haptic/devices/DeviceSpec.h), the servo
/// loop in simulated time or real time, and one servo tick (ServoStep) for a
/// loop written in Python.

#include "python/HapticBindings.h"

#include "haptic/devices/DeviceSpec.h"
#include "haptic/servo/ServoLoop.h"
#include "haptic/servo/ServoStep.h"

#include <pybind11/eigen.h>
#include <pybind11/stl.h>

#include <cmath>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace voxhap::python {

namespace {

/// A device and the force model it was made for (its path and limits), kept alive together.
struct PyDevice {
    std::shared_ptr<PyForceModel> model;
    std::unique_ptr<haptic::Device> device;
};

/// A servo loop over a model and a device; it keeps both alive.
struct PyServoLoop {
    std::shared_ptr<PyForceModel> model;
    std::shared_ptr<PyDevice> device;
    std::unique_ptr<haptic::ServoLoop> loop;
    std::vector<haptic::ServoRecord> records; ///< drained from the loop's queue
    std::vector<haptic::Event> events;

    void drain()
    {
        haptic::ServoRecord r;
        while (loop->popRecord(r)) records.push_back(r);
        haptic::Event e;
        while (loop->popEvent(e)) events.push_back(e);
    }
};

/// One tick of a loop written in Python: the step and watchdog, and the device it reads and writes.
struct PyServoStep {
    std::shared_ptr<PyForceModel> model;
    std::unique_ptr<haptic::ServoStep> step;
};

py::dict readingDict(const haptic::DeviceReading& r)
{
    py::dict d;
    d["tip"] = r.tip;
    d["direction"] = r.direction;
    d["velocity"] = r.velocity;
    d["valid"] = r.valid;
    d["lost"] = r.lost;
    d["pose_age_s"] = r.poseAgeS;
    d["plunger_fraction"] = r.plungerFraction;
    return d;
}

/// The records as numpy columns, as `simulate` returns its samples.
py::dict recordColumns(const std::vector<haptic::ServoRecord>& rs)
{
    const auto n = py::ssize_t(rs.size());
    py::array_t<double> t(n), depth(n), axial(n), plunger(n);
    py::array_t<double> tip({n, py::ssize_t(3)}), force({n, py::ssize_t(3)});
    py::array_t<int> layer(n);
    for (py::ssize_t i = 0; i < n; ++i) {
        const haptic::ServoRecord& r = rs[std::size_t(i)];
        t.mutable_at(i) = r.timeS;
        depth.mutable_at(i) = r.depthMm;
        axial.mutable_at(i) = r.axialN;
        plunger.mutable_at(i) = r.plungerN;
        layer.mutable_at(i) = r.layer;
        for (py::ssize_t c = 0; c < 3; ++c) {
            tip.mutable_at(i, c) = r.tip[c];
            force.mutable_at(i, c) = r.force[c];
        }
    }
    py::dict d;
    d["time_s"] = t;
    d["tip"] = tip;
    d["force"] = force;
    d["depth_mm"] = depth;
    d["axial_N"] = axial;
    d["plunger_N"] = plunger;
    d["layer"] = layer;
    return d;
}

} // namespace

void bindServo(py::module_& m)
{
    m.def("device_kinds", &haptic::deviceKindUsages,
        "The device names this build knows: 'hand', 'sim', 'replay:FILE', and 'igtl[:PORT]' when built with "
        "OpenIGTLink");

    py::class_<PyDevice, std::shared_ptr<PyDevice>>(
        m, "Device", "A haptic device as the servo loop sees it (haptic/servo/Device.h): read a pose, write a force")
        .def_property_readonly("name", [](const PyDevice& d) { return d.device->name(); })
        .def_property_readonly("finished", [](const PyDevice& d) { return d.device->finished(); })
        .def(
            "read", [](PyDevice& d, double timeS) { return readingDict(d.device->read(timeS)); }, py::arg("time_s"),
            "The pose at time_s [s]: {tip [mm], direction, velocity [mm/s], valid, lost, pose_age_s, "
            "plunger_fraction}")
        .def(
            "write",
            [](PyDevice& d, const Vec3d& force, double plungerN, double timeS) {
                d.device->write(force, plungerN, timeS);
            },
            py::arg("force"), py::arg("plunger_N") = 0.0, py::arg("time_s") = 0.0,
            "Send a force [N] (and the syringe plunger's force [N]) to the device");

    m.def(
        "make_device",
        [](const std::string& name, std::shared_ptr<PyForceModel> model, std::optional<double> speed,
            std::optional<double> depth, bool careful) {
            const haptic::Scene& scene = model->scene->instance->scene();
            haptic::DeviceContext c = haptic::deviceContext(
                *model->model, speed.value_or(scene.speedMmPerS), scene.approachMm, depth ? depth : scene.depthMm);
            c.careful = careful;
            auto out = std::make_shared<PyDevice>();
            out->model = std::move(model);
            out->device = haptic::makeDevice(haptic::parseDeviceSpec(name), c);
            return out;
        },
        py::arg("name"), py::arg("model"), py::kw_only(), py::arg("speed") = std::nullopt,
        py::arg("depth") = std::nullopt, py::arg("careful") = true,
        "The device `name` ('hand', 'sim', 'replay:session.csv', 'igtl:18944', ... as `voxhap serve --device`; "
        "device_kinds() lists them) for the force model's path and limits, inserting at the scene's speed "
        "[mm/s] (or speed=) to its depth [mm] (or depth=); careful=False makes the simulated hand keep going "
        "after the loss of resistance");

    py::class_<PyServoLoop, std::shared_ptr<PyServoLoop>>(m, "ServoLoop",
        "The servo loop (haptic/servo/ServoLoop.h) over a force model and a device: run_ticks() in simulated "
        "time on this thread, or start()/release_and_stop() on its own real-time thread")
        .def(py::init([](std::shared_ptr<PyForceModel> model, std::shared_ptr<PyDevice> device, double rateHz) {
            auto p = std::make_shared<PyServoLoop>();
            haptic::ServoOptions o;
            o.rateHz = rateHz;
            p->loop = std::make_unique<haptic::ServoLoop>(*model->model, *device->device, o);
            p->model = std::move(model);
            p->device = std::move(device);
            return p;
        }),
            py::arg("model"), py::arg("device"), py::arg("rate_hz") = 1000.0)
        .def(
            "run_ticks",
            [](PyServoLoop& p, long ticks) {
                // In chunks the queues hold (65536 records), draining between them.
                for (long done = 0; done < ticks;) {
                    const long n = std::min(ticks - done, 1L << 15);
                    {
                        py::gil_scoped_release release;
                        p.loop->runTicks(n);
                    }
                    p.drain();
                    done += n;
                    if (p.device->device->finished()) break;
                }
            },
            py::arg("ticks"), "Run ticks now in simulated time (1/rate_hz each), until the device finishes")
        .def(
            "start",
            [](PyServoLoop& p) {
                py::gil_scoped_release release;
                p.loop->start();
            },
            "Run in real time on the loop's own thread")
        .def(
            "release_and_stop",
            [](PyServoLoop& p) {
                {
                    py::gil_scoped_release release;
                    p.loop->releaseAndStop();
                }
                p.drain();
            },
            "Ramp the force to zero, send it, stop (what Ctrl-C does)")
        .def_property_readonly("running", [](const PyServoLoop& p) { return p.loop->running(); })
        .def_property_readonly("ticks", [](const PyServoLoop& p) { return p.loop->ticks(); })
        .def(
            "records",
            [](PyServoLoop& p) {
                p.drain();
                return recordColumns(p.records);
            },
            "Every tick so far as numpy columns: time_s, tip (n x 3), force (n x 3, rendered) [N], depth_mm, "
            "axial_N, plunger_N, layer")
        .def(
            "events",
            [](PyServoLoop& p) {
                p.drain();
                py::list out;
                for (const auto& e : p.events) out.append(eventDict(e, p.model->model->layers()));
                return out;
            },
            "The insertion events so far");

    py::class_<PyServoStep, std::shared_ptr<PyServoStep>>(
        m, "ServoStep", "One servo tick without a thread (haptic/servo/ServoStep.h): for a loop written in Python")
        .def(py::init([](std::shared_ptr<PyForceModel> model, double rateHz) {
            auto p = std::make_shared<PyServoStep>();
            haptic::ServoStepOptions o;
            o.rateHz = rateHz;
            p->step = std::make_unique<haptic::ServoStep>(*model->model, o);
            p->model = std::move(model);
            return p;
        }),
            py::arg("model"), py::arg("rate_hz") = 1000.0)
        .def(
            "step",
            [](PyServoStep& p, PyDevice& device, double timeS) {
                const haptic::DeviceReading r = device.device->read(timeS);
                const Vec3d f = p.step->step(r, timeS);
                const haptic::NeedleOutput& out = p.step->output();
                for (const haptic::Event& e : out.events) device.device->event(e);
                device.device->write(f, out.plungerN, timeS);
                return f;
            },
            py::arg("device"), py::arg("time_s"),
            "One tick at time_s [s]: read the device, step the model and the watchdog, write the force; returns "
            "the force [N]")
        .def_property_readonly(
            "output", [](const PyServoStep& p) { return outputDict(p.step->output(), p.model->model->layers()); },
            "The model's output of the last tick with a valid reading")
        .def_property_readonly("gain", [](const PyServoStep& p) { return p.step->gain(); });
}

} // namespace voxhap::python
