// cullide/unwritten.h: the arrays that start unwritten (records, oracle buffers, hierarchy rows).
#include "cullide/unwritten.h"

#include "cullide/mesh.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>

namespace {

using cullide::UnwrittenVector;

// Trap: the allocator asks for over-aligned storage itself: each array must keep its type's
// alignment (the oracle's 64-byte primitive records), and one of 2 MiB or more (huge pages
// advised) must start on a 2 MiB boundary and be writable to its end; freeing must use the same
// alignment (ASan reports a mismatch) or unmap exactly what was mapped.
// Both kinds: from malloc, and with pages of their own (mapped, then the unaligned head and tail
// of the mapping unmapped again; the mapping ends on a whole 2 MiB page: sizes just above and at
// 2 MiB, and 2.5 MiB).
template <bool kOwnPages>
void expectAligned() {
    struct alignas(64) Record {
        float x[16];
    };
    for (size_t n : {size_t(0), size_t(1), size_t(1000), size_t(5000), size_t(32768), size_t(32769), size_t(40000)}) {
        UnwrittenVector<Record, kOwnPages> b(n);
        EXPECT_EQ(b.size(), n);
        EXPECT_EQ(reinterpret_cast<uintptr_t>(b.data()) % 64, 0u);
        if (n * sizeof(Record) >= (size_t(2) << 20)) {
            EXPECT_EQ(reinterpret_cast<uintptr_t>(b.data()) % (2 << 20), 0u);
        }
        for (size_t i = 0; i < n; ++i) b[i].x[15] = float(i);
        if (n > 0) {
            EXPECT_EQ(b[n - 1].x[15], float(n - 1));
        }
    }
    UnwrittenVector<uint64_t, kOwnPages> moved(500000);
    moved = {};
    EXPECT_EQ(moved.size(), 0u);
}

TEST(Unwritten, KeepsAlignment) {
    expectAligned<false>();
    expectAligned<true>();
}

// Trap: only growing without a value is left unwritten. A value given (resize(n, v), push_back,
// an aggregate's members in braces) must be written as with std::vector, and so must a type with
// a constructor of its own (Eigen's vectors: constructed from coordinates).
TEST(Unwritten, WritesWhatIsGiven) {
    struct Pair {
        uint32_t a, b;
    };
    UnwrittenVector<uint32_t> v(3);
    v.resize(6, 7u);
    EXPECT_EQ(v[3], 7u);
    EXPECT_EQ(v[5], 7u);
    v.push_back(9);
    EXPECT_EQ(v.back(), 9u);
    UnwrittenVector<Pair> p;
    p.emplace_back(1u, 2u);
    EXPECT_EQ(p[0].a, 1u);
    EXPECT_EQ(p[0].b, 2u);
    UnwrittenVector<cullide::Vec3f> q;
    q.emplace_back(1.f, 2.f, 3.f);
    q.push_back(cullide::Vec3f(4, 5, 6));
    EXPECT_EQ(q[0], cullide::Vec3f(1, 2, 3));
    EXPECT_EQ(q[1], cullide::Vec3f(4, 5, 6));
}

// Trap: PageArena decides by size where an array comes from and where it goes back: below
// 64 KiB malloc, from 2 MiB pages of its own (2 MiB aligned, writable to the end, unmapped when
// freed), between handed out in order from 2 MiB chunks. Arrays from one chunk must not overlap
// (the next position advanced past each, aligned for the next one's type), one that does not fit
// the chunk's tail takes a new chunk, and freeing the latest array (and only the latest) takes its
// space back for the next.
TEST(PageArena, HandsOutMemoryBySize) {
    cullide::PageArena arena;
    constexpr size_t kKiB = 1024;
    void* small = arena.allocate(1000, 8);  // malloc
    EXPECT_EQ(arena.chunks(), 0u);
    auto* a = static_cast<std::byte*>(arena.allocate(700 * kKiB, 64));
    auto* b = static_cast<std::byte*>(arena.allocate(100 * kKiB + 3, 4));
    auto* c = static_cast<std::byte*>(arena.allocate(200 * kKiB, 64));  // after b's odd size: aligned
    EXPECT_EQ(arena.chunks(), 1u);
    EXPECT_EQ(reinterpret_cast<uintptr_t>(a) % (2 << 20), 0u);  // a chunk's start
    EXPECT_EQ(b, a + 700 * kKiB);
    EXPECT_EQ(reinterpret_cast<uintptr_t>(c) % 64, 0u);
    EXPECT_GE(c, b + 100 * kKiB + 3);
    EXPECT_LT(c, b + 100 * kKiB + 3 + 64);
    // The latest freed: its space again; an earlier one freed: nothing taken back.
    arena.deallocate(c, 200 * kKiB, 64);
    auto* c2 = static_cast<std::byte*>(arena.allocate(200 * kKiB, 64));
    EXPECT_EQ(c2, c);
    arena.deallocate(a, 700 * kKiB, 64);
    auto* d = static_cast<std::byte*>(arena.allocate(900 * kKiB, 64));
    EXPECT_GE(d, c2 + 200 * kKiB);
    EXPECT_EQ(arena.chunks(), 1u);
    // 1 MiB does not fit the first chunk's tail (2 MiB - 1.9 MiB): a second chunk.
    auto* e = static_cast<std::byte*>(arena.allocate(1024 * kKiB, 64));
    EXPECT_EQ(arena.chunks(), 2u);
    EXPECT_EQ(reinterpret_cast<uintptr_t>(e) % (2 << 20), 0u);
    // Its own pages: not from a chunk, 2 MiB aligned, writable to its end.
    const size_t big = (5 << 20) + 123;
    auto* f = static_cast<std::byte*>(arena.allocate(big, 64));
    EXPECT_EQ(arena.chunks(), 2u);
    EXPECT_EQ(reinterpret_cast<uintptr_t>(f) % (2 << 20), 0u);
    f[0] = std::byte{1}, f[big - 1] = std::byte{2};
    // Every array is writable over its whole size without touching the others.
    std::fill(b, b + 100 * kKiB + 3, std::byte{3});
    std::fill(c2, c2 + 200 * kKiB, std::byte{4});
    std::fill(d, d + 900 * kKiB, std::byte{5});
    std::fill(e, e + 1024 * kKiB, std::byte{6});
    EXPECT_EQ(b[100 * kKiB + 2], std::byte{3});
    EXPECT_EQ(c2[0], std::byte{4});
    EXPECT_EQ(d[0], std::byte{5});
    EXPECT_EQ(f[big - 1], std::byte{2});
    arena.deallocate(f, big, 64);
    arena.deallocate(small, 1000, 8);
}

// Trap: an ended arena's chunks go to the pool (at most kPooled of them, the rest unmapped) and
// the next arena starts on them; releasePool() empties it. A chunk given twice (pooled and
// still in use) would hand two arenas the same memory.
TEST(PageArena, PoolsEndedChunksForTheNextArena) {
    using cullide::PageArena;
    PageArena::releasePool();
    {
        PageArena arena;
        for (size_t k = 0; k < PageArena::kPooled + 2; ++k)
            arena.allocate(size_t(3) << 19, 64);  // 1.5 MiB: a chunk each
        EXPECT_EQ(arena.chunks(), PageArena::kPooled + 2);
        EXPECT_EQ(PageArena::pooled(), 0u);
    }
    EXPECT_EQ(PageArena::pooled(), PageArena::kPooled);
    {
        PageArena a, b;
        auto* pa = static_cast<std::byte*>(a.allocate(size_t(1) << 20, 64));
        auto* pb = static_cast<std::byte*>(b.allocate(size_t(1) << 20, 64));
        EXPECT_EQ(PageArena::pooled(), PageArena::kPooled - 2);
        EXPECT_NE(pa, pb);  // each its own chunk
        std::fill(pa, pa + (size_t(1) << 20), std::byte{1});
        std::fill(pb, pb + (size_t(1) << 20), std::byte{2});
        EXPECT_EQ(pa[(size_t(1) << 20) - 1], std::byte{1});
    }
    EXPECT_EQ(PageArena::pooled(), PageArena::kPooled);
    PageArena::releasePool();
    EXPECT_EQ(PageArena::pooled(), 0u);
}

// Trap: an ArenaVector's allocator travels with its storage. Growing one (from malloc's sizes
// through the chunks' to pages of its own, each old array freed after the new one is made),
// swapping or moving arrays between an arena and malloc
// (cullide's idiom to free one: swap with an empty one), must free each through the allocator
// that made it (ASan reports a mismatch; malloc aborts on an arena's pointer).
TEST(PageArena, VectorsFreeThroughTheirOwnAllocator) {
    using cullide::ArenaAllocator;
    using cullide::ArenaVector;
    cullide::PageArena arena;
    ArenaVector<uint64_t> grown{ArenaAllocator<uint64_t>(&arena)};
    for (uint64_t i = 0; i < 200000; ++i) grown.push_back(i);  // 8 KiB to 1.6 MiB, then own pages
    EXPECT_EQ(grown[199999], 199999u);
    ArenaVector<uint64_t> fromMalloc(100000);
    fromMalloc[99999] = 7;
    ArenaVector<uint64_t> inArena(20000, ArenaAllocator<uint64_t>(&arena));
    inArena[19999] = 9;
    inArena.swap(fromMalloc);  // storage and allocators swap
    EXPECT_EQ(inArena.get_allocator().arena, nullptr);
    EXPECT_EQ(fromMalloc.get_allocator().arena, &arena);
    EXPECT_EQ(inArena[99999], 7u);
    EXPECT_EQ(fromMalloc[19999], 9u);
    ArenaVector<uint64_t>().swap(fromMalloc);  // freed through the arena
    ArenaVector<uint64_t> moved = std::move(grown);
    grown = ArenaVector<uint64_t>(10, ArenaAllocator<uint64_t>(&arena));
    moved = std::move(inArena);  // moved's arena storage freed through the arena, then malloc's taken
    EXPECT_EQ(moved.get_allocator().arena, nullptr);
    EXPECT_EQ(moved[99999], 7u);
}

}  // namespace
