// SPDX-License-Identifier: Apache-2.0
/// @file CallbackAllocations.cpp
/// @brief Counting definitions of the C allocator, forwarding to glibc's
/// (CallbackAllocations.h says why and what is not seen).
#include "CallbackAllocations.h"

#include <atomic>
#include <cerrno>
#include <cstddef>
#include <cstdlib>
#include <malloc.h>

// glibc's own allocator under its public alternative names (GLIBC_2.2.5).
extern "C" {
void* __libc_malloc(std::size_t);
void* __libc_calloc(std::size_t, std::size_t);
void* __libc_realloc(void*, std::size_t);
void* __libc_memalign(std::size_t, std::size_t);
void* __libc_valloc(std::size_t);
void* __libc_pvalloc(std::size_t);
void __libc_free(void*);
}

namespace {

std::atomic<long> gAllocations{0}, gFrees{0};
// Constant-initialised thread-local data of the executable: a fixed offset from the
// thread pointer, read without a call and without allocating.
thread_local bool tCounting = false;

void counted() noexcept
{
    if (tCounting) gAllocations.fetch_add(1, std::memory_order_relaxed);
}

bool powerOfTwo(std::size_t n) noexcept { return n != 0 && (n & (n - 1)) == 0; }

} // namespace

namespace alloccheck {

CountAllocations::CountAllocations() noexcept { tCounting = true; }
CountAllocations::~CountAllocations() { tCounting = false; }
long allocations() noexcept { return gAllocations.load(); }
long frees() noexcept { return gFrees.load(); }

} // namespace alloccheck

extern "C" {

void* malloc(std::size_t n) noexcept
{
    counted();
    return __libc_malloc(n);
}

void* calloc(std::size_t count, std::size_t n) noexcept
{
    counted();
    return __libc_calloc(count, n);
}

void* realloc(void* p, std::size_t n) noexcept
{
    counted();
    return __libc_realloc(p, n);
}

void* reallocarray(void* p, std::size_t count, std::size_t n) noexcept
{
    counted();
    std::size_t bytes = 0;
    if (__builtin_mul_overflow(count, n, &bytes)) {
        errno = ENOMEM;
        return nullptr;
    }
    return __libc_realloc(p, bytes);
}

void* memalign(std::size_t alignment, std::size_t n) noexcept
{
    counted();
    return __libc_memalign(alignment, n);
}

void* aligned_alloc(std::size_t alignment, std::size_t n) noexcept
{
    counted();
    return __libc_memalign(alignment, n);
}

int posix_memalign(void** out, std::size_t alignment, std::size_t n) noexcept
{
    counted();
    if (!powerOfTwo(alignment) || alignment % sizeof(void*) != 0) return EINVAL;
    void* p = __libc_memalign(alignment, n);
    if (!p) return ENOMEM;
    *out = p;
    return 0;
}

void* valloc(std::size_t n) noexcept
{
    counted();
    return __libc_valloc(n);
}

void* pvalloc(std::size_t n) noexcept
{
    counted();
    return __libc_pvalloc(n);
}

void free(void* p) noexcept
{
    if (p && tCounting) gFrees.fetch_add(1, std::memory_order_relaxed);
    __libc_free(p);
}

} // extern "C"
