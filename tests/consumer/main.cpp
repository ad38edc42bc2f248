// The consumer: loads a mesh, runs Cullide on the CPU reference and checks the PCS against the
// exact oracle: the modified method (the defaults) gives a non-empty PCS of valid triangles, and
// the reliable method keeps every triangle of every intersecting pair (cullide.h: it never prunes
// one; the modified method may lose shallow crossings to depth rounding, the seed paper's Section 5).
// Usage: consumer MESH EXPECTED_VERSION. Exit 0 on success, 1 on a failed check, 2 on bad input.
#include <cullide/cullide.h>
#include <cullide/error.h>
#include <cullide/mesh_io.h>
#include <cullide/oracle/oracle.h>
#include <cullide/pipeline/pruner.h>
#include <cullide/provenance.h>
#include <cullide/raster/cpu_backend.h>

#include <algorithm>
#include <cstdio>
#include <string>

int main(int argc, char** argv) {
    if (argc != 3) {
        std::fprintf(stderr, "usage: consumer MESH EXPECTED_VERSION\n");
        return 2;
    }
    try {
        if (std::string(cullide::version()) != argv[2]) {
            std::fprintf(stderr, "consumer: cullide::version() is %s, the package says %s\n", cullide::version(),
                         argv[2]);
            return 1;
        }
        cullide::Scene scene;
        scene.objects.push_back({"mesh", cullide::loadMesh(argv[1]), cullide::Transform::Identity()});
        auto backend = cullide::raster::makeCpuBackend();
        cullide::Pruner pruner(cullide::PruneSettings{}, *backend);  // modified: 500x500, D24, six axes
        const cullide::CullideResult modified = pruner.prune(scene).cull;
        cullide::PruneSettings reliableSettings;
        reliableSettings.cullide.method = cullide::CullMethod::Reliable;
        reliableSettings.exactStage = true;  // the exact pairs among the PCS, too
        const cullide::FramePrune reliable = cullide::Pruner(reliableSettings, *backend).prune(scene);
        const cullide::oracle::Truth truth = cullide::oracle::findIntersections(scene);
        const auto& pcs = reliable.cull.pcs;
        size_t kept = 0;
        for (const auto& p : truth.pairs)
            kept +=
                std::binary_search(pcs.begin(), pcs.end(), p.a()) && std::binary_search(pcs.begin(), pcs.end(), p.b());
        std::printf(
            "consumer: %s: modified PCS %zu, reliable PCS %zu of %zu triangles; %zu intersecting pairs, %zu kept\n",
            argv[1], modified.pcs.size(), pcs.size(), scene.triangleCount(), truth.pairs.size(), kept);
        const bool inRange = std::all_of(modified.pcs.begin(), modified.pcs.end(), [&](const cullide::PcsTriangle& t) {
            return t.object == 0 && t.triangle < scene.triangleCount();
        });
        // The reliable PCS holds both triangles of every pair: the exact stage on it finds them all.
        const bool exactAgrees = reliable.exact && reliable.exact->pairs == truth.pairs;
        return !modified.pcs.empty() && inRange && !truth.pairs.empty() && kept == truth.pairs.size() && exactAgrees
            ? 0
            : 1;
    } catch (const cullide::InputError& e) {
        std::fprintf(stderr, "consumer: %s\n", e.what());
        return 2;
    }
}
