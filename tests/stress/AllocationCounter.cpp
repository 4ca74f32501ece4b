// SPDX-License-Identifier: Apache-2.0
/// @file AllocationCounter.cpp
/// @brief Counting definitions of every operator new and delete and of the C
/// allocator, forwarding to the next definition found with dlsym(RTLD_NEXT)
/// (see AllocationCounter.h for why not linker wrapping).
#include "stress/AllocationCounter.h"

#include <atomic>
#include <cerrno>
#include <cstddef>
#include <cstdlib>
#include <cstring>
#include <dlfcn.h>
#include <malloc.h>
#include <new>
#include <unistd.h>

namespace {

using voxhap::test::AllocKind;

std::atomic<long> gCounts[std::size_t(AllocKind::Count)];
std::atomic<long> gFrees{0};

void count(AllocKind k) noexcept { gCounts[std::size_t(k)].fetch_add(1, std::memory_order_relaxed); }

/// The next definitions in the lookup order (glibc's, or a preloaded allocator's).
/// The rest of the C allocator is built on these five, so that everything comes
/// from, and goes back to, one allocator.
struct Next {
    void* (*malloc)(std::size_t) = nullptr;
    void* (*calloc)(std::size_t, std::size_t) = nullptr;
    void* (*realloc)(void*, std::size_t) = nullptr;
    void (*free)(void*) = nullptr;
    int (*posixMemalign)(void**, std::size_t, std::size_t) = nullptr;
    std::size_t (*usableSize)(void*) = nullptr;
};
Next gNext;
std::atomic<int> gState{0}; // 0 not resolved, 1 resolving, 2 resolved

/// Allocations made while dlsym resolves the next definitions (dlsym may call
/// malloc or calloc) come from here. Never reused, so always zero on first use;
/// the size sits in the word before each block; free ignores these blocks.
constexpr std::size_t kArenaBytes = std::size_t(1) << 16;
alignas(4096) unsigned char gArena[kArenaBytes];
std::atomic<std::size_t> gArenaUsed{0};

bool inArena(const void* p) noexcept
{
    const auto* c = static_cast<const unsigned char*>(p);
    return c >= gArena && c < gArena + kArenaBytes;
}

void* arenaAlloc(std::size_t n, std::size_t align) noexcept
{
    if (align < 16) align = 16;
    std::size_t used = gArenaUsed.load(std::memory_order_relaxed);
    for (;;) {
        const std::size_t start = (used + sizeof(std::size_t) + align - 1) & ~(align - 1);
        if (start > kArenaBytes || n > kArenaBytes - start) {
            errno = ENOMEM;
            return nullptr;
        }
        if (gArenaUsed.compare_exchange_weak(used, start + n, std::memory_order_relaxed)) {
            __builtin_memcpy(gArena + start - sizeof(std::size_t), &n, sizeof n);
            return gArena + start;
        }
    }
}

std::size_t arenaSize(const void* p) noexcept
{
    std::size_t n;
    __builtin_memcpy(&n, static_cast<const unsigned char*>(p) - sizeof n, sizeof n);
    return n;
}

template <typename F> void lookUp(F& f, const char* name) noexcept { f = reinterpret_cast<F>(dlsym(RTLD_NEXT, name)); }

/// @return true once the next definitions are known; false while they are being
/// looked up (by this thread's dlsym, or briefly by another thread).
bool ready() noexcept
{
    int s = gState.load(std::memory_order_acquire);
    if (s == 2) return true;
    if (s == 0 && gState.compare_exchange_strong(s, 1, std::memory_order_acq_rel)) {
        lookUp(gNext.malloc, "malloc");
        lookUp(gNext.calloc, "calloc");
        lookUp(gNext.realloc, "realloc");
        lookUp(gNext.free, "free");
        lookUp(gNext.posixMemalign, "posix_memalign");
        lookUp(gNext.usableSize, "malloc_usable_size");
        if (!gNext.malloc || !gNext.calloc || !gNext.realloc || !gNext.free || !gNext.posixMemalign) {
            static const char msg[] = "AllocationCounter: dlsym(RTLD_NEXT) found no C allocator to forward to\n";
            (void)!::write(2, msg, sizeof msg - 1);
            std::abort();
        }
        gState.store(2, std::memory_order_release);
        return true;
    }
    return false;
}

bool powerOfTwo(std::size_t a) noexcept { return a != 0 && (a & (a - 1)) == 0; }

void* rawMalloc(std::size_t n) noexcept { return ready() ? gNext.malloc(n) : arenaAlloc(n, 16); }

/// @p align a power of two.
void* rawAligned(std::size_t n, std::size_t align) noexcept
{
    if (!ready()) return arenaAlloc(n, align);
    void* p = nullptr;
    const int err = gNext.posixMemalign(&p, align < sizeof(void*) ? sizeof(void*) : align, n);
    if (err != 0) {
        errno = err;
        return nullptr;
    }
    return p;
}

void rawFree(void* p) noexcept
{
    if (!p) return;
    gFrees.fetch_add(1, std::memory_order_relaxed);
    if (inArena(p) || !ready()) return; // nothing but arena blocks exists before the lookup
    gNext.free(p);
}

void* rawRealloc(void* p, std::size_t n) noexcept
{
    if (p && inArena(p)) { // moves out of the arena
        void* q = rawMalloc(n);
        if (q) std::memcpy(q, p, arenaSize(p) < n ? arenaSize(p) : n);
        return q;
    }
    return ready() ? gNext.realloc(p, n) : arenaAlloc(n, 16);
}

std::size_t pageSize() noexcept { return std::size_t(::sysconf(_SC_PAGESIZE)); }

void* newOrThrow(std::size_t n, std::size_t align)
{
    if (n == 0) n = 1;
    for (;;) {
        if (void* p = align ? rawAligned(n, align) : rawMalloc(n)) return p;
        std::new_handler h = std::get_new_handler();
        if (!h) throw std::bad_alloc();
        h();
    }
}

void* newOrNull(std::size_t n, std::size_t align) noexcept
{
    try {
        return newOrThrow(n, align);
    } catch (...) {
        return nullptr;
    }
}

} // namespace

long voxhap::test::allocations()
{
    long n = 0;
    for (const auto& c : gCounts) n += c.load(std::memory_order_relaxed);
    return n;
}

long voxhap::test::allocations(AllocKind kind) { return gCounts[std::size_t(kind)].load(std::memory_order_relaxed); }

long voxhap::test::deallocations() { return gFrees.load(std::memory_order_relaxed); }

// The C allocator.
extern "C" {

void* malloc(std::size_t n) noexcept
{
    count(AllocKind::Malloc);
    return rawMalloc(n);
}

void* calloc(std::size_t m, std::size_t n) noexcept
{
    count(AllocKind::Calloc);
    if (ready()) return gNext.calloc(m, n);
    std::size_t bytes = 0;
    if (__builtin_mul_overflow(m, n, &bytes)) {
        errno = ENOMEM;
        return nullptr;
    }
    return arenaAlloc(bytes, 16); // never used before: zero
}

void* realloc(void* p, std::size_t n) noexcept
{
    count(AllocKind::Realloc);
    return rawRealloc(p, n);
}

void* reallocarray(void* p, std::size_t m, std::size_t n) noexcept
{
    count(AllocKind::Realloc);
    std::size_t bytes = 0;
    if (__builtin_mul_overflow(m, n, &bytes)) {
        errno = ENOMEM;
        return nullptr;
    }
    return rawRealloc(p, bytes);
}

void free(void* p) noexcept { rawFree(p); }

int posix_memalign(void** out, std::size_t align, std::size_t n) noexcept
{
    count(AllocKind::AlignedC);
    if (!powerOfTwo(align) || align % sizeof(void*) != 0) return EINVAL;
    const int saved = errno;
    void* p = rawAligned(n, align);
    if (!p) {
        const int err = errno;
        errno = saved;
        return err ? err : ENOMEM;
    }
    *out = p;
    return 0;
}

void* aligned_alloc(std::size_t align, std::size_t n) noexcept
{
    count(AllocKind::AlignedC);
    if (!powerOfTwo(align)) {
        errno = EINVAL;
        return nullptr;
    }
    return rawAligned(n, align);
}

void* memalign(std::size_t align, std::size_t n) noexcept
{
    count(AllocKind::AlignedC);
    std::size_t a = 1;
    while (a < align) a <<= 1; // glibc rounds an alignment up to a power of two
    return rawAligned(n, a);
}

void* valloc(std::size_t n) noexcept
{
    count(AllocKind::AlignedC);
    return rawAligned(n, pageSize());
}

void* pvalloc(std::size_t n) noexcept
{
    count(AllocKind::AlignedC);
    const std::size_t page = pageSize();
    return rawAligned(n == 0 ? page : (n + page - 1) / page * page, page);
}

std::size_t malloc_usable_size(void* p) noexcept
{
    if (!p) return 0;
    if (inArena(p)) return arenaSize(p);
    return ready() && gNext.usableSize ? gNext.usableSize(p) : 0;
}

} // extern "C"

// Every replaceable operator new and delete.
void* operator new(std::size_t n)
{
    count(AllocKind::New);
    return newOrThrow(n, 0);
}
void* operator new[](std::size_t n)
{
    count(AllocKind::New);
    return newOrThrow(n, 0);
}
void* operator new(std::size_t n, const std::nothrow_t&) noexcept
{
    count(AllocKind::New);
    return newOrNull(n, 0);
}
void* operator new[](std::size_t n, const std::nothrow_t&) noexcept
{
    count(AllocKind::New);
    return newOrNull(n, 0);
}
void* operator new(std::size_t n, std::align_val_t a)
{
    count(AllocKind::AlignedNew);
    return newOrThrow(n, std::size_t(a));
}
void* operator new[](std::size_t n, std::align_val_t a)
{
    count(AllocKind::AlignedNew);
    return newOrThrow(n, std::size_t(a));
}
void* operator new(std::size_t n, std::align_val_t a, const std::nothrow_t&) noexcept
{
    count(AllocKind::AlignedNew);
    return newOrNull(n, std::size_t(a));
}
void* operator new[](std::size_t n, std::align_val_t a, const std::nothrow_t&) noexcept
{
    count(AllocKind::AlignedNew);
    return newOrNull(n, std::size_t(a));
}

// GCC cannot see that these replace the global pairs, and warns at inlined call sites.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
void operator delete(void* p) noexcept { rawFree(p); }
void operator delete[](void* p) noexcept { rawFree(p); }
void operator delete(void* p, std::size_t) noexcept { rawFree(p); }
void operator delete[](void* p, std::size_t) noexcept { rawFree(p); }
void operator delete(void* p, const std::nothrow_t&) noexcept { rawFree(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { rawFree(p); }
void operator delete(void* p, std::align_val_t) noexcept { rawFree(p); }
void operator delete[](void* p, std::align_val_t) noexcept { rawFree(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { rawFree(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { rawFree(p); }
void operator delete(void* p, std::align_val_t, const std::nothrow_t&) noexcept { rawFree(p); }
void operator delete[](void* p, std::align_val_t, const std::nothrow_t&) noexcept { rawFree(p); }
#pragma GCC diagnostic pop
