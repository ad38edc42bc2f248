// Recording a workload into a trace (the reference's answers and the intervals around them) and
// replaying a trace on a backend (cullide/raster/trace.h).
#include "cullide/raster/trace.h"

#include "trace_format.h"

#include "cullide/error.h"

namespace cullide::raster {

using namespace trace_format;

IntervalOptions TraceRules::intervalOptions() const {
    IntervalOptions o;
    o.subpixelBits = subpixelBits;
    o.fillRule = fillRule;
    o.otherSubpixelBits = otherSubpixelBits;
    o.depthLsb = depthLsb;
    o.depthFloatUlps = depthFloatUlps;
    return o;
}

namespace {
IntervalOptions withThreads(IntervalOptions o, int threads) {
    o.threads = threads;
    return o;
}
}  // namespace

TraceRecorder::TraceRecorder(CpuBackend& reference, TraceWriter& writer, const TraceRules& rules, int threads)
    : reference_(reference), writer_(writer), intervals_(withThreads(rules.intervalOptions(), threads)) {}

void TraceRecorder::setGeometry(std::span<const Vec3f> positions, std::span<const Triangle> triangles) {
    endFrame();  // the previous frame's lists
    reference_.borrowGeometry(positions, triangles);
    writer_.beginFrame(frame_, positions, triangles);
}

void TraceRecorder::setView(const OrthoView& view) {
    reference_.setView(view);
    view_ = view;
}

std::vector<uint64_t> TraceRecorder::execute(const CommandList& list) {
    if (list.conservativeCount() > 0) refuseConservative();
    std::vector<uint64_t> results = reference_.execute(list);
    pending_.push_back({view_, list, results});
    return results;
}

void TraceRecorder::endFrame() {
    reference_.releaseScratch();  // and forgets the borrowed geometry
    if (pending_.empty()) return;
    // The geometry comes back from the writer's scratch file (the caller's copy is gone by now),
    // handed over, not copied.
    {
        std::vector<Vec3f> positions;
        std::vector<Triangle> triangles;
        writer_.frameGeometry(positions, triangles);
        intervals_.setGeometry(std::move(positions), std::move(triangles));
    }
    // The evaluator sees the same setView/execute sequence as the reference did.
    for (const PendingList& p : pending_) {
        intervals_.setView(p.view);
        const std::vector<QueryInterval> iv = intervals_.execute(p.commands);
        std::vector<TraceQuery> queries(p.results.size());
        for (size_t q = 0; q < p.results.size(); ++q) {
            queries[q] = {p.results[q], iv[q]};
            if (!iv[q].contains(p.results[q])) ++referenceOutside_;
        }
        queries_ += p.results.size();
        writer_.addList(p.view, p.commands, queries);
    }
    intervals_.releaseScratch();
    intervals_.setGeometry(std::vector<Vec3f>{}, std::vector<Triangle>{});
    std::vector<PendingList>().swap(pending_);
}

uint64_t TraceRecorder::finish() {
    endFrame();
    return writer_.finish();
}

std::vector<std::vector<uint64_t>> replayTrace(const TraceReader& trace, DepthBackend& backend,
                                               const std::function<void(size_t, size_t)>& onList) {
    std::vector<std::vector<uint64_t>> out;
    out.reserve(trace.listCount());
    std::vector<Vec3f> positions;
    std::vector<Triangle> triangles;
    size_t list = 0;
    for (size_t f = 0; f < trace.frameCount(); ++f) {
        trace.readGeometry(f, positions, triangles);
        backend.setGeometry(positions, triangles);
        // The backend keeps its own copy: release ours (a frame of 10^6 triangles holds ~18 MB).
        std::vector<Vec3f>().swap(positions);
        std::vector<Triangle>().swap(triangles);
        for (size_t l = 0; l < trace.listCount(f); ++l, ++list) {
            const TraceList tl = trace.readList(list);
            backend.setView(tl.view);
            out.push_back(backend.execute(tl.commands));
            CULLIDE_CHECK(out.back().size() == tl.queries.size(), "a backend returned the wrong number of results");
            if (onList) onList(list + 1, trace.listCount());
        }
    }
    return out;
}

}  // namespace cullide::raster
