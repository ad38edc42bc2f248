// cullide/unwritten.h: the arrays that start unwritten (records, oracle buffers, hierarchy rows).
#include "cullide/unwritten.h"

#include "cullide/mesh.h"

#include <gtest/gtest.h>

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

}  // namespace
