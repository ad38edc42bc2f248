// libFuzzer harness for results files (`cullide trace compare`, raster/verify/src/trace_compare.cpp
// through the JSON reader): each input is written as a results file, read, and compared with a
// small trace recorded once when the harness starts (two crossing boxes, one frame), its worst
// queries ranked. The contract under test: a comparison or InputError, nothing else. Build and
// run: see docs/fuzzing.md. Seeds: results files written by `cullide trace replay --out`
// (docs/fuzzing.md says how).
#include "cullide/cullide.h"
#include "cullide/error.h"
#include "cullide/raster/cpu_backend.h"
#include "cullide/raster/trace.h"

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <unistd.h>

namespace {

namespace fs = std::filesystem;

fs::path scratch(const char* name) {
    return fs::temp_directory_path() / ("cullide_results_fuzz_" + std::to_string(::getpid()) + name);
}

cullide::Mesh box(float at) {
    cullide::Mesh m;
    for (int i = 0; i < 8; ++i) m.positions.push_back({at + float(i & 1), float((i >> 1) & 1), float(i >> 2)});
    m.triangles = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                   {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
    return m;
}

const cullide::raster::TraceReader& trace() {
    static const std::unique_ptr<cullide::raster::TraceReader> reader = [] {
        const fs::path path = scratch(".trace");
        cullide::raster::TraceRules rules;
        auto cpu = cullide::raster::makeCpuBackend();
        cullide::raster::TraceWriter writer(path, rules, {{"scene", "two boxes"}}, {{"harness", "results_fuzz"}});
        cullide::raster::TraceRecorder recorder(*cpu, writer, rules);
        cullide::Scene scene;
        scene.objects.push_back({"a", box(0), cullide::Transform::Identity()});
        scene.objects.push_back({"b", box(0.5f), cullide::Transform::Identity()});
        cullide::CullideOptions options;
        options.width = options.height = 32;
        options.hierarchy.leafSize = 2;
        recorder.setFrame(0);
        cullide::runCullide(scene, recorder, options);
        recorder.finish();
        return std::make_unique<cullide::raster::TraceReader>(path);
    }();
    return *reader;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const cullide::raster::TraceReader& t = trace();
    const fs::path path = scratch(".json");
    std::FILE* f = std::fopen(path.c_str(), "wb");
    if (!f) __builtin_trap();
    std::fwrite(data, 1, size, f);
    std::fclose(f);
    try {
        const cullide::raster::TraceResults results = cullide::raster::readTraceResults(path);
        const cullide::raster::TraceComparison c = cullide::raster::compareTrace(t, results, path.string());
        (void)cullide::raster::worstQueries(c.queries, 10);
    } catch (const cullide::InputError&) {}
    return 0;
}
