// Traces: a depth-only workload, the rules of the reference and the reference's answer to every
// query, in one backend-neutral file (docs/trace-format.md), so that any GPU backend, ours or
// someone else's, can be judged against the CPU reference without linking cullide.
//
//   record:  TraceRecorder, a DepthBackend that runs each command list on the reference and on the
//            interval evaluator (validate.h) and streams geometry, views, commands and answers to
//            a TraceWriter;
//   replay:  TraceReader (the header parsed, blobs read on demand, so memory stays near one
//            frame's geometry) + replayTrace() on any DepthBackend;
//   compare: compareTrace() of a results file against the trace's intervals.
// Everything read from a file is checked; a malformed trace or results file is an
// InputError(path, problem), never a crash.
#pragma once

#include "cullide/depth_backend.h"
#include "cullide/raster/cpu_backend.h"
#include "cullide/raster/rules.h"
#include "cullide/raster/validate.h"

#include <nlohmann/json.hpp>

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace cullide::raster {

// The format version this build writes and the newest it reads.
inline constexpr int kTraceFormatVersion = 1;

// What defines the reference's answers: its rasterization rules and the intervals' margins (the
// header's "rules").
struct TraceRules {
    int subpixelBits = kDefaultSubpixelBits;
    FillRule fillRule = FillRule::BottomLeft;
    int otherSubpixelBits = kDefaultSubpixelBits;  // what the intervals allow the replaying side
    double depthLsb = 2.0;
    double depthFloatUlps = 4.0;

    IntervalOptions intervalOptions() const;
};

// One query of a trace: the reference's exact count and its interval.
struct TraceQuery {
    uint64_t reference = 0;
    QueryInterval interval;
};

// One command list of a trace, as read back.
struct TraceList {
    size_t frameIndex = 0;  // position of its frame in the trace
    uint32_t frame = 0;  // the scene's frame number
    size_t index = 0;  // position over the whole trace (the results file's list number)
    OrthoView view;
    CommandList commands;
    std::vector<QueryKind> kinds;  // per query, from the begin_query commands
    std::vector<TraceQuery> queries;
};

// Writes a trace, streaming the blobs to a scratch file beside the destination so that memory
// does not grow with the trace; finish() assembles the file and renames it into place (a reader
// never sees half a trace). Without finish(), even when the process is killed, nothing is left
// behind: both files are unnamed while written (O_TMPFILE; where the file system lacks it, named
// temporaries removed on every failure the process sees). Same calls, same bytes.
class TraceWriter {
public:
    // `workload` and `provenance` go into the header as they are (provenance without a date).
    TraceWriter(std::filesystem::path path, const TraceRules& rules, nlohmann::ordered_json workload,
                nlohmann::ordered_json provenance);
    ~TraceWriter();
    TraceWriter(const TraceWriter&) = delete;
    TraceWriter& operator=(const TraceWriter&) = delete;

    // A new frame and its geometry. Triangles equal to the previous frame's are stored once.
    void beginFrame(uint32_t frame, std::span<const Vec3f> positions, std::span<const Triangle> triangles);
    // One executed list of the current frame, with one entry per query.
    void addList(const OrthoView& view, const CommandList& commands, std::span<const TraceQuery> queries);
    // Writes the file. Returns its size in bytes.
    uint64_t finish();

    // The current frame's geometry, read back from the scratch file.
    void frameGeometry(std::vector<Vec3f>& positions, std::vector<Triangle>& triangles);

private:
    nlohmann::ordered_json blob(const void* data, size_t bytes, const char* dtype, size_t rows, size_t cols);
    void scratchRead(uint64_t offset, void* out, size_t bytes);
    bool scratchEquals(uint64_t offset, const void* data, size_t bytes);

    std::filesystem::path path_;
    class PendingFile;  // a file unnamed until it is committed (trace_writer.cpp)
    std::unique_ptr<PendingFile> scratchFile_;  // owns scratch_
    std::FILE* scratch_ = nullptr;
    uint64_t binaryBytes_ = 0;
    TraceRules rules_;
    nlohmann::ordered_json workload_, provenance_;
    nlohmann::ordered_json frames_ = nlohmann::ordered_json::array();
    nlohmann::ordered_json lastTrianglesRef_;
    uint64_t lists_ = 0, commands_ = 0, queries_ = 0, trianglesDrawn_ = 0;
    bool finished_ = false;
};

// Reads a trace: the header at construction (fully checked: structure, blob bounds, shapes, and
// the summary's counts against the data, for which every list's commands are read once), blobs
// on request (their contents checked as they are read). A trace without frames is refused.
class TraceReader {
public:
    explicit TraceReader(std::filesystem::path path);

    const std::string& path() const { return pathText_; }
    const nlohmann::ordered_json& header() const { return header_; }
    const TraceRules& rules() const { return rules_; }
    uint64_t fileBytes() const { return fileBytes_; }

    size_t frameCount() const { return frames_.size(); }
    uint32_t frameNumber(size_t f) const { return frames_[f].frame; }
    size_t listCount() const { return lists_.size(); }  // over the whole trace
    size_t listCount(size_t f) const { return frames_[f].lists; }
    size_t queryCount(size_t list) const { return lists_[list].queries; }
    const DepthFormat& depthFormat(size_t list) const { return lists_[list].view.depth; }

    // Frame f's geometry (indices checked against the vertex count, positions finite).
    void readGeometry(size_t f, std::vector<Vec3f>& positions, std::vector<Triangle>& triangles) const;
    // List `list` (over the whole trace) with its commands and queries, checked.
    TraceList readList(size_t list) const;

private:
    struct BlobRef {
        uint64_t offset = 0, rows = 0;
    };
    struct FrameInfo {
        uint32_t frame = 0;
        BlobRef positions, triangles;
        size_t firstList = 0, lists = 0;
    };
    struct ListInfo {
        size_t frameIndex = 0;
        OrthoView view;
        BlobRef commands, queryRows;
        size_t queries = 0;
    };
    BlobRef parseBlob(const nlohmann::ordered_json& j, const std::string& where, const char* dtype, size_t cols) const;
    // Refuses a header whose "summary" counts differ from the frames, lists, commands, queries
    // and drawn triangles the trace holds (std::invalid_argument naming the count).
    void checkSummary() const;
    uint64_t trianglesDrawn() const;
    std::string drawPastTheEnd(size_t list, size_t command, uint64_t first, uint64_t count) const;
    void readBlob(const BlobRef& ref, size_t itemBytes, size_t cols, void* out) const;
    [[noreturn]] void fail(const std::string& problem) const;

    std::filesystem::path path_;
    std::string pathText_;
    nlohmann::ordered_json header_;
    TraceRules rules_;
    uint64_t fileBytes_ = 0, binaryStart_ = 0, binaryBytes_ = 0;
    std::vector<FrameInfo> frames_;
    std::vector<ListInfo> lists_;
};

// A DepthBackend that records what it is asked into a TraceWriter: each list runs on the
// reference (whose results it returns, so the workload is the reference's) and on an interval
// evaluator with the writer's rules. setFrame() names the scene frame of the next setGeometry().
// Conservative commands are refused (no GPU counterpart to validate).
class TraceRecorder : public DepthBackend {
public:
    // `threads`: the interval evaluator's workers (IntervalOptions::threads; 0: oneTBB's default).
    // The reference borrows each frame's geometry (CpuBackend::borrowGeometry) and its scratch is
    // released at endFrame: the caller's arrays must live until then, as runCullide's do.
    TraceRecorder(CpuBackend& reference, TraceWriter& writer, const TraceRules& rules, int threads = 0);
    std::string describe() const override { return "trace recorder: " + reference_.describe(); }
    void setGeometry(std::span<const Vec3f> positions, std::span<const Triangle> triangles) override;
    void setView(const OrthoView& view) override;
    // Runs `list` on the reference and keeps it, with its view and answers, until endFrame().
    std::vector<uint64_t> execute(const CommandList& list) override;
    int maxViewportSide() const override { return reference_.maxViewportSide(); }
    DepthImage readDepth() override { return reference_.readDepth(); }
    void readDepthInto(DepthImage& out) override { reference_.readDepthInto(out); }

    void setFrame(uint32_t frame) { frame_ = frame; }
    // Ends the frame: the intervals of the frame's lists, in order, then the lists to the writer;
    // the interval evaluator's scratch is freed. The intervals wait for it so that the caller's
    // pipeline (hierarchy, records of the reference) and the evaluator are not in memory at once:
    // call it after the frame's run (setGeometry and finish() call it too).
    void endFrame();
    // endFrame(), then TraceWriter::finish(): the trace's size in bytes.
    uint64_t finish();
    // Queries whose reference count lies outside its own interval (a bug in one of the two), and
    // all queries, of the frames ended so far.
    uint64_t referenceOutside() const { return referenceOutside_; }
    uint64_t queries() const { return queries_; }

private:
    struct PendingList {
        OrthoView view;
        CommandList commands;
        std::vector<uint64_t> results;
    };
    CpuBackend& reference_;
    TraceWriter& writer_;
    QueryIntervals intervals_;
    OrthoView view_;
    std::vector<PendingList> pending_;
    uint32_t frame_ = 0;
    uint64_t referenceOutside_ = 0, queries_ = 0;
};

// Executes every list of the trace on `backend`, in order (geometry per frame, view per list);
// returns one result list per command list. `onList` (optional) is called after each list.
std::vector<std::vector<uint64_t>> replayTrace(const TraceReader& trace, DepthBackend& backend,
                                               const std::function<void(size_t done, size_t total)>& onList = {});

// A results file: what a backend answered to a trace.
struct TraceResults {
    std::string backend;
    std::vector<std::vector<uint64_t>> results;
};
// Reads and checks the JSON shape ({"backend": string, "results": [[non-negative integer...]...]}).
TraceResults readTraceResults(const std::filesystem::path& path);
// Writes {"backend", "trace", "provenance", "results"} (one inner list per line).
void writeTraceResults(const std::filesystem::path& path, const TraceResults& results, const std::string& tracePath,
                       const nlohmann::ordered_json& provenance);

// Every query of a trace against a results file.
struct TraceComparison {
    std::vector<QueryComparison> queries;  // frame = scene frame, list = list over the trace
    std::vector<DepthFormat> formats;  // per list
    // Counts per group ("frame 3", "D24"): queries, exact, in interval.
    struct Rates {
        uint64_t queries = 0, exact = 0, inside = 0;
    };
    std::map<uint32_t, Rates> perFrame;
    std::map<std::string, Rates> perFormat;
    Rates all;
    bool passed() const { return all.inside == all.queries; }
};
// Throws InputError(results path, ...) when the results do not have the trace's shape: the
// number of lists, and the number of queries of each list (naming the first that differs).
TraceComparison compareTrace(const TraceReader& trace, const TraceResults& results, const std::string& resultsPath);

// The worst queries: outside the interval first (by distance), then by |other - reference|; only
// queries that are not exact or not inside. At most `count`.
std::vector<size_t> worstQueries(const std::vector<QueryComparison>& queries, size_t count);

// The draws of query q in a list: [first, first + count) ranges of triangles.
std::vector<std::pair<uint32_t, uint32_t>> queryDraws(const CommandList& list, uint32_t query);

// Runs the interval evaluator over the trace and captures the coverage classes of the given
// queries (at most one per list; list -> query), calling `captured` for each.
void captureTraceQueries(const TraceReader& trace, const std::map<size_t, uint32_t>& wanted,
                         const std::function<void(const TraceList&, uint32_t query, const CoverageCapture&)>& captured);

}  // namespace cullide::raster
