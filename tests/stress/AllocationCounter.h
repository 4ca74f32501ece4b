// SPDX-License-Identifier: Apache-2.0
/// @file AllocationCounter.h
/// @brief Every heap allocation of the stress program is counted, so that a test
/// can assert that a servo-path call allocates nothing (architecture.md "Threads").
///
/// Counted: every form of operator new (plain, array, nothrow, aligned, and the
/// sized and aligned deletes on the way back), and the C allocator: malloc,
/// calloc, realloc, reallocarray, posix_memalign, aligned_alloc, memalign,
/// valloc and pvalloc (Eigen's aligned allocator and libc's own strdup, fopen
/// and friends go through these).
///
/// How: the program defines those functions itself and forwards to the next
/// definition in the dynamic linker's search order, found with
/// dlsym(RTLD_NEXT, ...) (glibc's, or a preloaded allocator's). A definition in
/// the executable comes first in the global lookup scope, so every shared
/// library's call binds to it too: libstdc++, TBB, OpenVDB and libc itself
/// (glibc documents that its internal calls to malloc go to a replacement).
/// Linker wrapping (-Wl,--wrap=malloc) was not chosen: it rewrites only the
/// references in the objects linked statically into this program, so a malloc
/// made inside any shared library (the very kind that was invisible before)
/// would still pass uncounted. dlsym may itself allocate while it resolves the
/// real functions; those few allocations are served from a static arena.
///
/// Not seen: memory obtained with mmap or sbrk directly (an allocator that
/// bypasses malloc, such as tbbmalloc), and stack growth.
#pragma once

namespace voxhap::test {

/// @brief The allocating entry points, by kind.
enum class AllocKind {
    New,        ///< operator new / new[], plain and nothrow
    AlignedNew, ///< operator new / new[] with std::align_val_t
    Malloc,
    Calloc,
    Realloc,  ///< realloc and reallocarray, whatever they end up doing
    AlignedC, ///< posix_memalign, aligned_alloc, memalign, valloc, pvalloc
    Count
};

/// @brief Allocations of every kind so far in this program, on any thread.
long allocations();
/// @brief Allocations of one kind so far.
long allocations(AllocKind kind);
/// @brief Calls to free and operator delete with a non-null pointer so far (they
/// take the allocator's locks as well).
long deallocations();

} // namespace voxhap::test
