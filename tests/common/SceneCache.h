// SPDX-License-Identifier: Apache-2.0
/// @file SceneCache.h
/// @brief Built-in scenes instanced once per test program: a scene on the
/// torso phantom takes seconds to build, and many tests read the same one.
#pragma once

#include "BuiltinTable.h"
#include "haptic/scene/Scene.h"

#include <map>
#include <memory>
#include <string>

namespace voxhap::test {

/// @brief The built-in scene @p name on its own phantom, built at the first call.
inline const haptic::SceneInstance& sceneInstance(const std::string& name)
{
    static std::map<std::string, std::unique_ptr<haptic::SceneInstance>> cache;
    auto& slot = cache[name];
    if (!slot) slot = std::make_unique<haptic::SceneInstance>(haptic::loadScene(name), nullptr, table());
    return *slot;
}

} // namespace voxhap::test
