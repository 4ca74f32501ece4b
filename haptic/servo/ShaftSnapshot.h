// SPDX-License-Identifier: Apache-2.0
/// @file ShaftSnapshot.h
/// @brief The bent needle's shaft, handed from the servo thread to a display
/// thread (the live needle of `voxhap serve --viewer`).
///
/// A sequence lock: the servo thread is the only writer and never waits; a
/// reader copies the points and retries when a write overlapped its copy. The
/// points are relaxed atomics (no data race on the memory model's terms), so
/// the writer's cost is one store per coordinate: 150 nodes are about 450
/// stores, well under a microsecond. Nothing allocates on the writer's side.
#pragma once

#include "core/Math.h"

#include <array>
#include <atomic>
#include <cstdint>
#include <span>
#include <vector>

namespace voxhap::haptic {

class ShaftSnapshot {
public:
    /// Above BentNeedle's node cap (150 nodes): a longer polyline keeps its ends
    /// and an even subsample between them.
    static constexpr int kMaxPoints = 256;

    /// @brief Publish @p points (hub to tip); none: the needle is straight. Writer only.
    void publish(std::span<const Vec3d> points) noexcept
    {
        const std::size_t n = points.size();
        const int kept = int(n < std::size_t(kMaxPoints) ? n : std::size_t(kMaxPoints));
        const std::uint64_t s = mSeq.load(std::memory_order_relaxed);
        mSeq.store(s + 1, std::memory_order_relaxed); // odd: a write is under way
        std::atomic_thread_fence(std::memory_order_release);
        for (int i = 0; i < kept; ++i) {
            // Point i of the kept ones: the ends exactly, the rest evenly between.
            const std::size_t src = kept < 2 ? std::size_t(i) : std::size_t(i) * (n - 1) / std::size_t(kept - 1);
            for (int c = 0; c < 3; ++c) mXyz[std::size_t(3 * i + c)].store(points[src][c], std::memory_order_relaxed);
        }
        mCount.store(kept, std::memory_order_relaxed);
        mSeq.store(s + 2, std::memory_order_release); // even: complete
    }

    /// @brief Copy the latest published shaft into @p out (empty: straight, or
    /// nothing published). Reader side: allocates, retries a torn copy.
    /// @return the number of publications so far (0: none), to tell a new shaft from an old one
    std::uint64_t read(std::vector<Vec3d>& out) const
    {
        for (;;) {
            const std::uint64_t before = mSeq.load(std::memory_order_acquire);
            if (before & 1u) continue; // the writer is mid-copy: it finishes within a microsecond
            const int n = mCount.load(std::memory_order_relaxed);
            out.resize(std::size_t(n));
            for (int i = 0; i < n; ++i) {
                for (int c = 0; c < 3; ++c)
                    out[std::size_t(i)][c] = mXyz[std::size_t(3 * i + c)].load(std::memory_order_relaxed);
            }
            std::atomic_thread_fence(std::memory_order_acquire);
            if (mSeq.load(std::memory_order_relaxed) == before) return before / 2;
        }
    }

private:
    std::atomic<std::uint64_t> mSeq{0};
    std::atomic<int> mCount{0};
    std::array<std::atomic<double>, 3 * kMaxPoints> mXyz{};
};

} // namespace voxhap::haptic
