// SPDX-License-Identifier: Apache-2.0
/// @file CallbackAllocations.h
/// @brief The example's own check that the servo callback never calls the heap
/// allocator: while a CountAllocations object lives on a thread, every call of
/// that thread to malloc, calloc, realloc, the aligned allocators and free is
/// counted. Not needed to embed voxhap; it shows the claim instead of stating it.
///
/// How: this program defines the C allocator's entry points itself and forwards
/// to glibc's (__libc_malloc and friends). A definition in the executable comes
/// first in the dynamic linker's lookup, so the calls of every shared library
/// reach it too, and operator new (libstdc++'s, built on malloc) with them.
/// glibc only; memory taken with mmap directly, or by an allocator that does so,
/// is not seen.
#pragma once

namespace alloccheck {

/// @brief Counts this thread's allocator calls from construction to destruction.
/// No allocation of its own; nesting is not supported.
class CountAllocations {
public:
    CountAllocations() noexcept;
    ~CountAllocations();
    CountAllocations(const CountAllocations&) = delete;
    CountAllocations& operator=(const CountAllocations&) = delete;
};

/// @brief Allocations (malloc, calloc, realloc, aligned) and frees counted so far,
/// on every thread, inside CountAllocations scopes.
long allocations() noexcept;
long frees() noexcept;

} // namespace alloccheck
