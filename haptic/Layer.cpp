// SPDX-License-Identifier: Apache-2.0
/// @file Layer.cpp
/// @brief Layer roles by tissue name (physics.md §2.3 layer names, §4 [LP] rows).

#include "haptic/Layer.h"

namespace voxhap::haptic {

LayerRole roleFromName(const std::string& n, bool rigid, bool critical)
{
    if (critical) return LayerRole::Critical;
    if (rigid || n == "bone" || n.find("_bone") != std::string::npos) return LayerRole::Bone;
    const auto has = [&](const char* s) { return n.find(s) != std::string::npos; };
    if (n == "air" || has("out of skin") || n == "gap") return LayerRole::Air;
    if (n == "skin" || n == "derma") return LayerRole::Skin;
    if (has("ligament") || has("flavum")) return LayerRole::Ligament;
    if (has("epidural")) return LayerRole::Epidural; // also Conci's merged "epidural_dura" row
    if (has("dura")) return LayerRole::Dura;
    if (n == "csf" || has("puncture aim")) return LayerRole::Csf;
    return LayerRole::Tissue;
}

const char* roleName(LayerRole r)
{
    switch (r) {
    case LayerRole::Tissue:
        return "tissue";
    case LayerRole::Air:
        return "air";
    case LayerRole::Skin:
        return "skin";
    case LayerRole::Ligament:
        return "ligament";
    case LayerRole::Epidural:
        return "epidural";
    case LayerRole::Dura:
        return "dura";
    case LayerRole::Csf:
        return "csf";
    case LayerRole::Bone:
        return "bone";
    case LayerRole::Critical:
        return "critical";
    }
    return "?";
}

} // namespace voxhap::haptic
