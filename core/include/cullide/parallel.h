// Parallel loops on oneTBB that ThreadSanitizer can follow.
//
// Every parallel phase of cullide goes through these helpers, which tell TSan what TBB guarantees:
// the caller's history happens-before every task of the phase, and every task happens-before the
// caller's continuation. Tasks of one phase are NOT ordered with each other, so a race between
// two tasks is still reported. They were written for Debian's uninstrumented libtbb.so, whose
// joins TSan cannot see; the tsan preset now links a libtbb built with -fsanitize=thread
// (tools/sanitizers/build-tbb-tsan.sh), which sees those joins itself: the loop annotations are
// now redundant (kept until a TSan run without them is clean). tsanRelease/tsanAcquire are still
// needed for Embree's callbacks: Embree's own TBB loops are compiled into uninstrumented code.
// Without TSan they are plain tbb::parallel_for / task_arena::execute.
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <cstddef>

#if defined(__SANITIZE_THREAD__)
extern "C" void __tsan_acquire(void* addr);
extern "C" void __tsan_release(void* addr);
#endif

namespace cullide {

// For code that hands work to threads it does not see (e.g. Embree's rtcCollide callbacks):
// call tsanRelease(&token) at the end of each callback and tsanAcquire(&token) after the call
// that ran them returns. No-ops without ThreadSanitizer.
inline void tsanRelease([[maybe_unused]] void* token) {
#if defined(__SANITIZE_THREAD__)
    __tsan_release(token);
#endif
}
inline void tsanAcquire([[maybe_unused]] void* token) {
#if defined(__SANITIZE_THREAD__)
    __tsan_acquire(token);
#endif
}

// tbb::parallel_for over [begin, end) in blocked ranges of at least `grain`; body(range).
template <typename Body>
void parallelFor(size_t begin, size_t end, size_t grain, const Body& body) {
    static char before, after;  // sync tokens: only their addresses matter
    tsanRelease(&before);
    tbb::parallel_for(tbb::blocked_range<size_t>(begin, end, grain), [&](const tbb::blocked_range<size_t>& r) {
        tsanAcquire(&before);
        body(r);
        tsanRelease(&after);
    });
    tsanAcquire(&after);
}

// tbb::parallel_for over each index in [begin, end); body(i).
template <typename Body>
void parallelForEach(size_t begin, size_t end, const Body& body) {
    parallelFor(begin, end, 1, [&](const tbb::blocked_range<size_t>& r) {
        for (size_t i = r.begin(); i != r.end(); ++i) body(i);
    });
}

// arena.execute(f), with the hand-over annotated; returns what f returns.
template <typename F>
auto executeIn(tbb::task_arena& arena, const F& f) -> decltype(f()) {
    static char before, after;
    struct Acquire {
        ~Acquire() { tsanAcquire(&after); }
    };
    struct Release {
        ~Release() { tsanRelease(&after); }
    };
    tsanRelease(&before);
    Acquire acquire;  // runs after execute() has returned
    return arena.execute([&]() -> decltype(f()) {
        tsanAcquire(&before);
        Release release;  // runs after f() has returned
        return f();
    });
}

}  // namespace cullide
