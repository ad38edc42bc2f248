// libFuzzer harness for the trace reader (raster/verify/src/trace_*.cpp): each input is written as a
// trace file and read the way `cullide trace replay` reads it (the header, every frame's
// geometry, every command list), then judged against a results file of the right shape. The
// contract under test: a result or InputError, nothing else. Build and run: see docs/fuzzing.md.
// Seeds: traces written by `cullide trace record` (docs/fuzzing.md says how).
#include "cullide/error.h"
#include "cullide/raster/trace.h"

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>
#include <unistd.h>

namespace {

const std::filesystem::path& tracePath() {
    static const std::filesystem::path p =
        std::filesystem::temp_directory_path() / ("cullide_trace_fuzz_" + std::to_string(::getpid()) + ".trace");
    return p;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    std::FILE* f = std::fopen(tracePath().c_str(), "wb");
    if (!f) __builtin_trap();
    std::fwrite(data, 1, size, f);
    std::fclose(f);
    try {
        const cullide::raster::TraceReader trace(tracePath());
        std::vector<cullide::Vec3f> positions;
        std::vector<cullide::Triangle> triangles;
        cullide::raster::TraceResults results;
        for (size_t fr = 0; fr < trace.frameCount(); ++fr) trace.readGeometry(fr, positions, triangles);
        for (size_t l = 0; l < trace.listCount(); ++l) {
            const cullide::raster::TraceList list = trace.readList(l);
            std::vector<uint64_t>& r = results.results.emplace_back();
            for (const cullide::raster::TraceQuery& q : list.queries) r.push_back(q.reference);
        }
        (void)cullide::raster::compareTrace(trace, results, "results");
    } catch (const cullide::InputError&) {}
    return 0;
}
