// SPDX-License-Identifier: Apache-2.0
/// @file Events.h
/// @brief Insertion events (architecture.md "The force pipeline", step 2) and a
/// fixed-capacity buffer the force model fills without allocating.
#pragma once

#include <array>
#include <cstdint>

namespace voxhap::haptic {

enum class EventType : std::uint8_t {
    SkinContact,      ///< the tip meets the skin
    SkinEntry,        ///< the skin is punctured (the first pop); the trajectory locks
    Pop,              ///< a layer is punctured (skin included)
    LossOfResistance, ///< the tip enters the epidural space (§2.3)
    DuraPuncture,     ///< the dura is punctured
    BoneContact,      ///< the tip meets bone (§1.3)
    BoneRelease,      ///< pulled back off the bone
    CriticalBreach,   ///< the shaft touches a critical structure: force zero (§1.1)
    CriticalClear,    ///< no longer touching it
    Withdrawn,        ///< the tip left the body: the state resets
    Fault,            ///< a non-finite input or force: zero force, latched (§6.4)
    ForceLimited,     ///< the device's peak or I²t limit starts cutting the force (§6.3)
};

const char* eventName(EventType t);

struct Event {
    EventType type = EventType::Pop;
    double timeS = 0;   ///< [s]
    double depthMm = 0; ///< tip depth along the path [mm]
    int layer = -1;     ///< index into the model's layers, -1 if none
};

/// @brief Events of one tick or more: fixed capacity, never allocates; extra
/// events are counted, not stored.
class EventBuffer {
public:
    static constexpr int kCapacity = 64;
    void push(const Event& e) noexcept
    {
        if (mCount < kCapacity)
            mEvents[std::size_t(mCount++)] = e;
        else
            ++mDropped;
    }
    void clear() noexcept { mCount = 0; }
    int size() const noexcept { return mCount; }
    long dropped() const noexcept { return mDropped; }
    const Event& operator[](int i) const noexcept { return mEvents[std::size_t(i)]; }
    const Event* begin() const noexcept { return mEvents.data(); }
    const Event* end() const noexcept { return mEvents.data() + mCount; }

private:
    std::array<Event, kCapacity> mEvents{};
    int mCount = 0;
    long mDropped = 0;
};

} // namespace voxhap::haptic
