// libFuzzer harness for the trace reader (raster/verify/src/trace_*.cpp): each input is written as a
// trace file and read the way `cullide trace replay` reads it (the header, every frame's
// geometry, every command list), then judged against a results file of the right shape. The
// contract under test: a result or InputError, nothing else. Build and run: see docs/fuzzing.md.
// Seeds: traces written by `cullide trace record` (docs/fuzzing.md says how).
#include "fuzz_util.h"

#include <cstdint>
#include <string_view>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const auto& path = cullide::fuzz::writeScratch("trace_fuzz", ".trace",
                                                   std::string_view(reinterpret_cast<const char*>(data), size));
    try {
        cullide::fuzz::readWholeTrace(path);
    } catch (const cullide::InputError&) {}
    return 0;
}
