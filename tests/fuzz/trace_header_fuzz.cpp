// libFuzzer harness for trace headers (raster/verify/src/trace_reader.cpp through the JSON reader):
// each input is a header's JSON text, then optionally a NUL byte and the binary section; the
// harness puts the preamble (magic and the header's length) in front, so that every mutation
// reaches the JSON and the checks of its fields instead of failing at the length. The trace is
// then read as trace_fuzz.cpp reads it. The contract under test: a result or InputError, nothing
// else. Build and run: see docs/fuzzing.md. Seeds: headers of traces written by `cullide trace
// record`, each followed by a NUL and its binary section (docs/fuzzing.md says how).
#include "fuzz_util.h"

#include <cstdint>
#include <cstring>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const char* text = reinterpret_cast<const char*>(data);
    const char* nul = static_cast<const char*>(std::memchr(text, 0, size));
    const size_t headerBytes = nul ? size_t(nul - text) : size;
    std::string bytes = "CULTRACE";
    for (int i = 0; i < 8; ++i) bytes.push_back(char(uint64_t(headerBytes) >> (8 * i)));
    bytes.append(text, headerBytes);
    if (nul) bytes.append(nul + 1, size - headerBytes - 1);
    try {
        cullide::fuzz::readWholeTrace(cullide::fuzz::writeScratch("trace_header_fuzz", ".trace", bytes));
    } catch (const cullide::InputError&) {}
    return 0;
}
