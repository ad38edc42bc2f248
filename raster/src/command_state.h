// The GL state a command list walks through, shared by the fast path, the scalar reference path
// and the interval evaluator (raster/verify/src/query_intervals.cpp). Private to raster/.
#pragma once

#include "cullide/depth_backend.h"

#include <cstdint>
#include <vector>

namespace cullide::raster::detail {

// GL state that persists across command lists.
struct PipelineState {
    DepthFunc func = DepthFunc::Less;
    bool mask = true;
};

// Walks the state commands of one list: the depth function and mask (the caller's, kept across
// lists) and the open query, numbered in BeginQuery order.
class StateWalker {
public:
    StateWalker(DepthFunc& func, bool& mask, size_t queries) : func_(func), mask_(mask), kinds_(queries) {}
    explicit StateWalker(PipelineState& state, size_t queries) : StateWalker(state.func, state.mask, queries) {}

    // Applies SetDepthFunc, SetDepthMask, BeginQuery and EndQuery; false for any other command.
    bool apply(const Command& c) {
        switch (c.op) {
            case Command::Op::SetDepthFunc: func_ = c.func; return true;
            case Command::Op::SetDepthMask: mask_ = c.mask; return true;
            case Command::Op::BeginQuery:
                query_ = next_++;
                kinds_[size_t(query_)] = c.queryKind;
                return true;
            case Command::Op::EndQuery: query_ = -1; return true;
            default: return false;
        }
    }

    DepthFunc func() const { return func_; }
    bool mask() const { return mask_; }
    int64_t query() const { return query_; }  // the open query, -1 when none
    // Whether query q only reports whether any sample passed (then its result is 0 or 1).
    bool anySamples(size_t q) const { return kinds_[q] == QueryKind::AnySamplesPassed; }
    // Sample counts to query results: 0 or 1 for AnySamplesPassed.
    void finish(std::vector<uint64_t>& results) const {
        for (size_t q = 0; q < results.size(); ++q)
            if (anySamples(q)) results[q] = results[q] > 0 ? 1 : 0;
    }

private:
    DepthFunc& func_;
    bool& mask_;
    std::vector<QueryKind> kinds_;
    int64_t query_ = -1;
    uint32_t next_ = 0;
};

}  // namespace cullide::raster::detail
