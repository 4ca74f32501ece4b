// SPDX-License-Identifier: Apache-2.0
/// @file Events.cpp
#include "haptic/Events.h"

namespace voxhap::haptic {

const char* eventName(EventType t)
{
    switch (t) {
    case EventType::SkinContact:
        return "skin_contact";
    case EventType::SkinEntry:
        return "skin_entry";
    case EventType::Pop:
        return "pop";
    case EventType::LossOfResistance:
        return "loss_of_resistance";
    case EventType::DuraPuncture:
        return "dura_puncture";
    case EventType::BoneContact:
        return "bone_contact";
    case EventType::BoneRelease:
        return "bone_release";
    case EventType::CriticalBreach:
        return "critical_breach";
    case EventType::CriticalClear:
        return "critical_clear";
    case EventType::Withdrawn:
        return "withdrawn";
    case EventType::Fault:
        return "fault";
    case EventType::ForceLimited:
        return "force_limited";
    }
    return "?";
}

} // namespace voxhap::haptic
