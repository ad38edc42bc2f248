// The comparing tee (cullide/raster/validate.h): one workload run on the reference, another
// backend and the interval evaluator at once, every query compared.
#include "cullide/raster/validate.h"

namespace cullide::raster {

TeeBackend::TeeBackend(DepthBackend& reference, DepthBackend& other, const IntervalOptions& options)
    : reference_(reference), other_(other), intervals_(options) {}

std::string TeeBackend::describe() const {
    return "tee: " + reference_.describe() + " | " + other_.describe();
}

void TeeBackend::setGeometry(std::span<const Vec3f> positions, std::span<const Triangle> triangles) {
    reference_.setGeometry(positions, triangles);
    other_.setGeometry(positions, triangles);
    intervals_.setGeometry(positions, triangles);
}

void TeeBackend::setView(const OrthoView& view) {
    reference_.setView(view);
    other_.setView(view);
    intervals_.setView(view);
    view_ = view;
}

std::vector<uint64_t> TeeBackend::execute(const CommandList& list) {
    std::vector<uint64_t> ref = reference_.execute(list);
    const std::vector<uint64_t> oth = other_.execute(list);
    std::vector<uint64_t> exact;
    bool exactValid = false;
    CoverageCapture capture;
    const int64_t want = onCapture ? onCapture(frame_, list_) : -1;
    capture.query = want >= 0 ? uint32_t(want) : 0;
    const std::vector<QueryInterval> iv = intervals_.execute(list, &exact, &exactValid, want >= 0 ? &capture : nullptr);
    std::vector<QueryKind> kinds;
    for (const Command& c : list.commands())
        if (c.op == Command::Op::BeginQuery) kinds.push_back(c.queryKind);
    for (uint32_t q = 0; q < ref.size(); ++q) {
        QueryComparison cmp;
        cmp.frame = frame_;
        cmp.list = list_;
        cmp.query = q;
        cmp.kind = kinds[q];
        cmp.reference = ref[q];
        cmp.other = oth[q];
        cmp.interval = iv[q];
        if (exactValid) {
            ++selfChecked_;
            if (exact[q] != ref[q]) ++selfCheckMismatches_;
        }
        comparisons_.push_back(cmp);
        if (want == int64_t(q) && captured) captured(cmp, capture, view_);
    }
    ++list_;
    return ref;
}

DepthImage TeeBackend::readDepth() {
    return reference_.readDepth();
}

void TeeBackend::readDepthInto(DepthImage& out) {
    reference_.readDepthInto(out);
}

}  // namespace cullide::raster
