// libFuzzer harness for positions files (core/src/positions_file.cpp): each input is written as a
// positions file, opened (header and size checked) and every frame read. The contract under test:
// frames or InputError, nothing else, and never a read past the file. Build and run as the other
// harnesses (docs/fuzzing.md); seeds: small files written by `cullide make-scene twist --frames 2`
// (its .pos) and their headers cut or changed by hand.
#include "fuzz_util.h"

#include "cullide/positions_file.h"

#include <cstdint>
#include <string_view>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const std::string_view bytes(reinterpret_cast<const char*>(data), size);
    try {
        // The header alone, as the reader sees it, for any claimed file size.
        (void)cullide::parsePositionsHeader(bytes, size, "input");
    } catch (const cullide::InputError&) {}
    try {
        const cullide::PositionsFile file(cullide::fuzz::writeScratch("positions_fuzz", ".pos", bytes));
        std::vector<cullide::Vec3f> frame;
        for (uint64_t f = 0; f < file.header().frameCount; ++f) {
            file.readFrame(f, frame);
            if (frame.size() != file.header().vertexCount) __builtin_trap();
        }
    } catch (const cullide::InputError&) {}
    return 0;
}
