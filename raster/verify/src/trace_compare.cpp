// Results files of other backends, their comparison with a trace's answers, the worst queries,
// and the coverage of chosen queries re-evaluated for pictures (cullide/raster/trace.h).
#include "cullide/raster/trace.h"

#include "trace_format.h"

#include "cullide/error.h"
#include "cullide/file_io.h"
#include "cullide/json_read.h"

#include <algorithm>

namespace cullide::raster {

using namespace trace_format;

TraceResults readTraceResults(const std::filesystem::path& path) {
    const std::string where = path.string();
    // 256 MiB: at least 12 million query results (20 digits each at most).
    constexpr JsonLimits kResultsJson{.kind = "a results file", .maxBytes = uint64_t(256) << 20};
    const Json j = parseOrderedJson(readFile(path, kResultsJson.maxBytes, kResultsJson.kind), where, kResultsJson);
    if (!j.is_object()) throw InputError(where, "not a results file (a JSON object with \"backend\" and \"results\")");
    TraceResults r;
    const auto backend = j.find("backend");
    if (backend == j.end() || !backend->is_string()) throw InputError(where, "no \"backend\" string");
    r.backend = backend->get<std::string>();
    const auto results = j.find("results");
    if (results == j.end() || !results->is_array()) throw InputError(where, "no \"results\" array");
    r.results.reserve(results->size());
    for (size_t l = 0; l < results->size(); ++l) {
        const Json& list = (*results)[l];
        if (!list.is_array()) throw InputError(where, "results[" + std::to_string(l) + "] is not an array");
        std::vector<uint64_t>& out = r.results.emplace_back();
        out.reserve(list.size());
        for (size_t q = 0; q < list.size(); ++q) {
            if (!list[q].is_number_unsigned())
                throw InputError(where,
                                 "list " + std::to_string(l) + " query " + std::to_string(q) + ": " + list[q].dump() +
                                     " is not a non-negative integer");
            out.push_back(list[q].get<uint64_t>());
        }
    }
    return r;
}

void writeTraceResults(const std::filesystem::path& path, const TraceResults& results, const std::string& tracePath,
                       const Json& provenance) {
    // One line per list, so that a diff of two results files points at the list.
    std::string text = "{\"backend\": " + Json(results.backend).dump() + ",\n \"trace\": " + Json(tracePath).dump() +
        ",\n \"provenance\": " + provenance.dump() + ",\n \"results\": [";
    for (size_t l = 0; l < results.results.size(); ++l) {
        text += l ? ",\n  [" : "\n  [";
        for (size_t q = 0; q < results.results[l].size(); ++q) {
            if (q) text.push_back(',');
            text += std::to_string(results.results[l][q]);
        }
        text += "]";
    }
    text += "]}\n";
    writeFileAtomically(path, text);
}

TraceComparison compareTrace(const TraceReader& trace, const TraceResults& results, const std::string& resultsPath) {
    if (results.results.size() != trace.listCount())
        throw InputError(resultsPath,
                         "has " + std::to_string(results.results.size()) + " result lists, but " + trace.path() +
                             " has " + std::to_string(trace.listCount()) + " command lists");
    for (size_t l = 0; l < trace.listCount(); ++l)
        if (results.results[l].size() != trace.queryCount(l))
            throw InputError(resultsPath,
                             "list " + std::to_string(l) + " has " + std::to_string(results.results[l].size()) +
                                 " results, but the trace's list " + std::to_string(l) + " has " +
                                 std::to_string(trace.queryCount(l)) + " queries");
    TraceComparison c;
    c.formats.reserve(trace.listCount());
    for (size_t l = 0; l < trace.listCount(); ++l) {
        const TraceList tl = trace.readList(l);
        c.formats.push_back(tl.view.depth);
        TraceComparison::Rates& frame = c.perFrame[tl.frame];
        TraceComparison::Rates& format = c.perFormat[tl.view.depth.name()];
        for (uint32_t q = 0; q < tl.queries.size(); ++q) {
            QueryComparison qc;
            qc.frame = tl.frame;
            qc.list = uint32_t(l);
            qc.query = q;
            qc.kind = tl.kinds[q];
            qc.reference = tl.queries[q].reference;
            qc.interval = tl.queries[q].interval;
            qc.other = results.results[l][q];
            for (TraceComparison::Rates* r : {&frame, &format, &c.all}) {
                ++r->queries;
                r->exact += qc.exact() ? 1 : 0;
                r->inside += qc.inInterval() ? 1 : 0;
            }
            c.queries.push_back(qc);
        }
    }
    return c;
}

std::vector<size_t> worstQueries(const std::vector<QueryComparison>& queries, size_t count) {
    std::vector<size_t> order;
    for (size_t i = 0; i < queries.size(); ++i)
        if (!queries[i].exact() || !queries[i].inInterval()) order.push_back(i);
    auto diff = [](const QueryComparison& c) {
        return c.other > c.reference ? c.other - c.reference : c.reference - c.other;
    };
    std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) {
        if (queries[a].outside() != queries[b].outside()) return queries[a].outside() > queries[b].outside();
        return diff(queries[a]) > diff(queries[b]);
    });
    order.resize(std::min(order.size(), count));
    return order;
}

std::vector<std::pair<uint32_t, uint32_t>> queryDraws(const CommandList& list, uint32_t query) {
    std::vector<std::pair<uint32_t, uint32_t>> draws;
    int64_t open = -1, next = 0;
    for (const Command& c : list.commands()) {
        if (c.op == Command::Op::BeginQuery) open = next++;
        else if (c.op == Command::Op::EndQuery) open = -1;
        else if (c.op == Command::Op::Draw && open == int64_t(query)) draws.push_back({c.first, c.count});
    }
    return draws;
}

void captureTraceQueries(const TraceReader& trace, const std::map<size_t, uint32_t>& wanted,
                         const std::function<void(const TraceList&, uint32_t, const CoverageCapture&)>& captured) {
    if (wanted.empty()) return;
    const size_t last = wanted.rbegin()->first;
    QueryIntervals intervals(trace.rules().intervalOptions());
    std::vector<Vec3f> positions;
    std::vector<Triangle> triangles;
    size_t list = 0;
    for (size_t f = 0; f < trace.frameCount() && list <= last; ++f) {
        trace.readGeometry(f, positions, triangles);
        intervals.setGeometry(positions, triangles);
        for (size_t l = 0; l < trace.listCount(f) && list <= last; ++l, ++list) {
            const TraceList tl = trace.readList(list);
            intervals.setView(tl.view);
            const auto it = wanted.find(list);
            if (it == wanted.end()) {
                intervals.execute(tl.commands);
                continue;
            }
            CoverageCapture capture;
            capture.query = it->second;
            intervals.execute(tl.commands, nullptr, nullptr, &capture);
            captured(tl, it->second, capture);
        }
    }
}

}  // namespace cullide::raster
