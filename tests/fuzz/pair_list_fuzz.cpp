// libFuzzer harness for pair lists (tools/pipeline/src/pair_list.cpp, JSON through the JSON
// reader, CSV line by line): each input is parsed as a pair list, its pairs checked against a small
// scene, and those the scene has audited against the scene's truth, as `cullide audit` does. The
// contract under test: a list and its audit, or InputError, nothing else. Build and run: see
// docs/fuzzing.md. Seeds: tests/fuzz/seeds/pair_list/.
#include "cullide/error.h"
#include "cullide/oracle/audit.h"
#include "cullide/oracle/oracle.h"
#include "cullide/pipeline/pair_list.h"

#include <cstdint>
#include <string>
#include <string_view>

namespace {

// Two crossing triangles in one object, a third in another and a degenerate one: every cause
// path of the audit is reachable from indices below 3.
cullide::Scene fuzzScene() {
    cullide::Scene s;
    cullide::Mesh a{{{0, 0, 0}, {2, 0, 0}, {0, 2, 0}, {0.5f, 0.5f, -1}, {0.5f, 0.5f, 1}, {1, 1, 1}, {3, 3, 3}},
                    {{0, 1, 2}, {3, 4, 5}, {0, 1, 6}, {6, 6, 6}}};
    cullide::Mesh b{{{0, 0, 0.5f}, {1, 0, 0.5f}, {0, 1, 0.5f}}, {{0, 1, 2}}};
    s.objects.push_back({"a", a, cullide::Transform::Identity()});
    s.objects.push_back({"b", b, cullide::Transform::Identity()});
    return s;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    static const cullide::Scene scene = fuzzScene();
    static const cullide::oracle::Truth truth = cullide::oracle::findIntersections(scene);
    try {
        const cullide::pipeline::PairList list =
            cullide::pipeline::parsePairList(std::string_view(reinterpret_cast<const char*>(data), size), "fuzz");
        for (const cullide::pipeline::PairListFrame& f : list.frames) {
            cullide::pipeline::checkPairsInScene(list, f, scene);
            (void)cullide::oracle::audit(scene, truth, f.pairs);
        }
    } catch (const cullide::InputError&) {}
    return 0;
}
