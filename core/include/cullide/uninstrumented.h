// Calls into libraries whose threads ThreadSanitizer cannot follow (Embree).
//
// Embree runs its builds and its rtcCollide on TBB tasks whose joins are compiled into
// libembree3 itself (TBB's inline header code, uninstrumented): TSan sees TBB's workers touch the
// task contexts Embree keeps on the caller's stack, but not the join that ends those touches, and
// reports the caller's next use of that stack as a race (seen at random in the peers' tests, a
// worker's read of an Embree task's context against the oracle's next frame on the caller's
// stack). Under TSan such a call runs in a one-thread arena, where there are
// no workers and no join to see; the results do not depend on the thread count. Without TSan the
// call runs as it is, on every thread of the caller's arena.
#pragma once

#if defined(__SANITIZE_THREAD__)
#include <tbb/task_arena.h>
#endif

namespace cullide {

template <typename F>
auto callUninstrumented(const F& f) -> decltype(f()) {
#if defined(__SANITIZE_THREAD__)
    tbb::task_arena one(1);
    return one.execute(f);
#else
    return f();
#endif
}

}  // namespace cullide
