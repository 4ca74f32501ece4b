// SPDX-License-Identifier: Apache-2.0
/// @file HapticBindings.h
/// @brief What HapticBindings.cpp and ServoBindings.cpp share: a scene made
/// ready to run, a force model that keeps its scene alive, and the dicts of an
/// event and of one step's output.
#pragma once

#include "python/Bindings.h"

#include "haptic/force/NeedleForceModel.h"
#include "haptic/scene/Scene.h"

#include <memory>
#include <vector>

namespace voxhap::python {

/// A scene made ready to run (volume, materials, layers); models are made from it.
struct PyScene {
    std::shared_ptr<const volume::Volume> volume; // the caller's, or null: the scene's own
    std::unique_ptr<haptic::SceneInstance> instance;
};

/// One force model; it reads the scene's material field, so it keeps the scene alive.
struct PyForceModel {
    std::shared_ptr<const PyScene> scene;
    std::unique_ptr<haptic::NeedleForceModel> model;
    haptic::NeedleOutput out;
};

py::dict eventDict(const haptic::Event& e, const std::vector<haptic::Layer>& layers);
py::dict outputDict(const haptic::NeedleOutput& o, const std::vector<haptic::Layer>& layers);

/// @brief Devices by name, the servo loop and one servo tick (ServoBindings.cpp).
void bindServo(py::module_& m);

} // namespace voxhap::python
