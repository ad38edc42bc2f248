// What the file-reading fuzz harnesses share: a scratch file per process that each input is
// written to, and the whole read of a trace as `cullide trace replay` and `compare` do it.
#pragma once

#include "cullide/error.h"
#include "cullide/raster/trace.h"

#include <cstdio>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include <unistd.h>

namespace cullide::fuzz {

// The harness's scratch file, "cullide_<name>_<pid><extension>" in the temporary folder, holding
// `bytes` (traps when it cannot be written: the harness, not the input, is broken then).
inline const std::filesystem::path& writeScratch(const char* name, const char* extension, std::string_view bytes) {
    static const std::filesystem::path p = std::filesystem::temp_directory_path() /
        (std::string("cullide_") + name + "_" + std::to_string(::getpid()) + extension);
    std::FILE* f = std::fopen(p.c_str(), "wb");
    if (!f) __builtin_trap();
    std::fwrite(bytes.data(), 1, bytes.size(), f);
    std::fclose(f);
    return p;
}

// Reads the trace at `path` whole: the header, every frame's geometry, every command list, then
// judges it against results of the right shape (its own reference counts). InputError passes.
inline void readWholeTrace(const std::filesystem::path& path) {
    const raster::TraceReader trace(path);
    std::vector<Vec3f> positions;
    std::vector<Triangle> triangles;
    raster::TraceResults results;
    for (size_t fr = 0; fr < trace.frameCount(); ++fr) trace.readGeometry(fr, positions, triangles);
    for (size_t l = 0; l < trace.listCount(); ++l) {
        const raster::TraceList list = trace.readList(l);
        std::vector<uint64_t>& r = results.results.emplace_back();
        for (const raster::TraceQuery& q : list.queries) r.push_back(q.reference);
    }
    (void)raster::compareTrace(trace, results, "results");
}

}  // namespace cullide::fuzz
