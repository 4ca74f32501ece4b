// SPDX-License-Identifier: Apache-2.0
/// @file TestAllocationCounter.cpp
/// @brief The allocation counter behind the "never allocates" tests sees each way
/// of allocating: every one of them below is counted exactly once, under its own
/// kind, including an allocation made inside a shared library (libc's strdup),
/// which linker wrapping would miss. A counter blind to any of them fails here.

#include "stress/AllocationCounter.h"

#include <Eigen/Core>
#include <gtest/gtest.h>

#include <array>
#include <cstdlib>
#include <cstring>
#include <malloc.h>
#include <new>
#include <string>

namespace voxhap::test {
namespace {

/// Hands @p p to the optimiser as used, so that a matching allocation and release
/// cannot be elided (both C++ and C allocation pairs may be removed when unused).
void keep(void* p) { asm volatile("" : : "g"(p) : "memory"); }

/// @p p, unknown to the optimiser (which turns realloc(nullptr, n) into malloc(n)).
void* opaque(void* p)
{
    asm volatile("" : "+r"(p));
    return p;
}

struct Snapshot {
    std::array<long, std::size_t(AllocKind::Count)> byKind{};
    long total = 0, frees = 0;
    static Snapshot now()
    {
        Snapshot s;
        for (std::size_t k = 0; k < s.byKind.size(); ++k) s.byKind[k] = allocations(AllocKind(k));
        s.total = allocations();
        s.frees = deallocations();
        return s;
    }
};

struct Case {
    const char* name;
    AllocKind kind;
    void (*allocate)(); ///< allocates once (of kind), releases once
};

// Each case allocates once and releases once. Releases happen after the allocation
// is counted; the test checks the kinds, the total and the releases.
const Case kCases[] = {
    {"malloc", AllocKind::Malloc,
        [] {
            void* p = std::malloc(40);
            keep(p);
            std::free(p);
        }},
    {"calloc", AllocKind::Calloc,
        [] {
            void* p = std::calloc(5, 8);
            keep(p);
            std::free(p);
        }},
    {"realloc of nullptr", AllocKind::Realloc,
        [] {
            void* p = std::realloc(opaque(nullptr), 64);
            keep(p);
            std::free(p);
        }},
    {"posix_memalign", AllocKind::AlignedC,
        [] {
            void* p = nullptr;
            if (posix_memalign(&p, 64, 100) != 0) std::abort();
            keep(p);
            std::free(p);
        }},
    {"aligned_alloc", AllocKind::AlignedC,
        [] {
            void* p = std::aligned_alloc(128, 256);
            keep(p);
            std::free(p);
        }},
    {"memalign", AllocKind::AlignedC,
        [] {
            void* p = memalign(32, 10);
            keep(p);
            std::free(p);
        }},
    {"new", AllocKind::New,
        [] {
            auto* p = new double(1.0);
            keep(p);
            delete p;
        }},
    {"new[]", AllocKind::New,
        [] {
            auto* p = new int[17];
            keep(p);
            delete[] p;
        }},
    {"nothrow new", AllocKind::New,
        [] {
            auto* p = new (std::nothrow) long(3);
            keep(p);
            delete p;
        }},
    {"aligned new", AllocKind::AlignedNew,
        [] {
            struct alignas(64) Line {
                double v[8];
            };
            auto* p = new Line();
            keep(p);
            delete p;
        }},
    {"aligned new[]", AllocKind::AlignedNew,
        [] {
            void* p = ::operator new[](96, std::align_val_t(256));
            keep(p);
            ::operator delete[](p, std::align_val_t(256));
        }},
    {"strdup inside libc", AllocKind::Malloc,
        [] {
            char* p = strdup("a string copied by libc");
            keep(p);
            std::free(p);
        }},
};

TEST(AllocationCounter, CountsEachKindOnceAndEachRelease)
{
    for (const Case& c : kCases) {
        const Snapshot before = Snapshot::now();
        c.allocate();
        const Snapshot after = Snapshot::now();
        EXPECT_EQ(after.total - before.total, 1) << c.name;
        EXPECT_EQ(after.frees - before.frees, 1) << c.name;
        for (std::size_t k = 0; k < before.byKind.size(); ++k) {
            EXPECT_EQ(after.byKind[k] - before.byKind[k], AllocKind(k) == c.kind ? 1 : 0) << c.name << ", kind " << k;
        }
    }
}

// A realloc that grows a block is counted as a reallocation (it may move the block),
// apart from the malloc that made it.
TEST(AllocationCounter, CountsAGrowingRealloc)
{
    const Snapshot before = Snapshot::now();
    void* p = std::malloc(16);
    keep(p);
    p = std::realloc(p, 1 << 20);
    keep(p);
    std::free(p);
    const Snapshot after = Snapshot::now();
    EXPECT_EQ(after.byKind[std::size_t(AllocKind::Malloc)] - before.byKind[std::size_t(AllocKind::Malloc)], 1);
    EXPECT_EQ(after.byKind[std::size_t(AllocKind::Realloc)] - before.byKind[std::size_t(AllocKind::Realloc)], 1);
    EXPECT_EQ(after.total - before.total, 2);
}

// Eigen's aligned allocator (the one fixed-size vectorisable members need) reaches
// the C allocator, whichever branch of it this build of Eigen takes.
TEST(AllocationCounter, CountsEigensAlignedAllocator)
{
    Eigen::aligned_allocator<Eigen::Vector4d> a;
    const long before = allocations();
    Eigen::Vector4d* p = a.allocate(3);
    keep(p);
    a.deallocate(p, 3);
    EXPECT_EQ(allocations() - before, 1);
}

// The counter adds nothing of its own: arithmetic and a string that fits its
// small-string buffer are not allocations.
TEST(AllocationCounter, CountsNothingWhenNothingIsAllocated)
{
    const Snapshot before = Snapshot::now();
    std::string s = "short";
    keep(s.data());
    double x = 1.0;
    for (int i = 0; i < 1000; ++i) x = x * 1.000001 + 1e-9;
    keep(&x);
    const Snapshot after = Snapshot::now();
    EXPECT_EQ(after.total - before.total, 0);
    EXPECT_EQ(after.frees - before.frees, 0);
}

} // namespace
} // namespace voxhap::test
