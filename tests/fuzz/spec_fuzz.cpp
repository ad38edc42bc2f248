// libFuzzer harness for study specs (tools/study/src/spec.cpp through the JSON reader): each input
// is written as spec.json, loaded, and its sweep expanded (its scenes replaced by a generated one
// when they name files, so that no input reads files elsewhere on the machine; generated scenes
// are only counted, not made). The contract under test: a spec and its runs, or InputError,
// nothing else. Build and run: see docs/fuzzing.md. Seeds: the specs in docs/studies.md.
#include "fuzz_util.h"

#include "cullide/error.h"
#include "cullide/study/study.h"

#include <cstdint>
#include <string>
#include <string_view>

namespace {

bool generated(const std::string& scene) {
    for (const char* g : {"bunny:", "cows:", "twist:", "cylinders:"})
        if (scene.rfind(g, 0) == 0) return true;
    return false;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const auto& path = cullide::fuzz::writeScratch("spec_fuzz", ".json",
                                                   std::string_view(reinterpret_cast<const char*>(data), size));
    try {
        cullide::study::Spec spec = cullide::study::loadSpec(path.string());
        for (std::string& scene : spec.scenes)
            if (!generated(scene)) scene = "bunny:500";
        (void)cullide::study::expand(spec);
    } catch (const cullide::InputError&) {}
    return 0;
}
