// SPDX-License-Identifier: Apache-2.0
/// @file SpscQueue.h
/// @brief A bounded single-producer single-consumer queue without locks: the
/// servo thread hands events and records out through it (architecture.md
/// "Threads"). Push and pop never allocate; a full queue drops and counts.
#pragma once

#include <array>
#include <atomic>
#include <cstddef>

namespace voxhap::haptic {

template <typename T, std::size_t Capacity> class SpscQueue {
    static_assert(Capacity >= 2 && (Capacity & (Capacity - 1)) == 0, "capacity must be a power of two");

public:
    /// @brief Producer side. @return false (and counts a drop) when full.
    bool push(const T& v) noexcept
    {
        const std::size_t head = mHead.load(std::memory_order_relaxed);
        if (head - mTail.load(std::memory_order_acquire) == Capacity) {
            mDropped.fetch_add(1, std::memory_order_relaxed);
            return false;
        }
        mItems[head & (Capacity - 1)] = v;
        mHead.store(head + 1, std::memory_order_release);
        return true;
    }
    /// @brief Consumer side. @return false when empty.
    bool pop(T& v) noexcept
    {
        const std::size_t tail = mTail.load(std::memory_order_relaxed);
        if (tail == mHead.load(std::memory_order_acquire)) return false;
        v = mItems[tail & (Capacity - 1)];
        mTail.store(tail + 1, std::memory_order_release);
        return true;
    }
    long dropped() const noexcept { return mDropped.load(std::memory_order_relaxed); }

private:
    std::array<T, Capacity> mItems{};
    alignas(64) std::atomic<std::size_t> mHead{0};
    alignas(64) std::atomic<std::size_t> mTail{0};
    std::atomic<long> mDropped{0};
};

} // namespace voxhap::haptic
