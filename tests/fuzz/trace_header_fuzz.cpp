// libFuzzer harness for trace headers (raster/verify/src/trace_reader.cpp through the JSON reader):
// each input is a header's JSON text, then optionally a NUL byte and the binary section; the
// harness puts the preamble (magic and the header's length) in front, so that every mutation
// reaches the JSON and the checks of its fields instead of failing at the length. The trace is
// then read as trace_fuzz.cpp reads it. The contract under test: a result or InputError, nothing
// else. Build and run: see docs/fuzzing.md. Seeds: headers of traces written by `cullide trace
// record`, each followed by a NUL and its binary section (docs/fuzzing.md says how).
#include "cullide/error.h"
#include "cullide/raster/trace.h"

#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <string>
#include <unistd.h>

namespace {

const std::filesystem::path& tracePath() {
    static const std::filesystem::path p =
        std::filesystem::temp_directory_path() / ("cullide_trace_header_fuzz_" + std::to_string(::getpid()) + ".trace");
    return p;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const char* text = reinterpret_cast<const char*>(data);
    const char* nul = static_cast<const char*>(std::memchr(text, 0, size));
    const size_t headerBytes = nul ? size_t(nul - text) : size;
    std::string bytes = "CULTRACE";
    for (int i = 0; i < 8; ++i) bytes.push_back(char(uint64_t(headerBytes) >> (8 * i)));
    bytes.append(text, headerBytes);
    if (nul) bytes.append(nul + 1, size - headerBytes - 1);
    std::FILE* f = std::fopen(tracePath().c_str(), "wb");
    if (!f) __builtin_trap();
    std::fwrite(bytes.data(), 1, bytes.size(), f);
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
