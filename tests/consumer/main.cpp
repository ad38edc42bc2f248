// The consumer: loads a mesh, runs Cullide (modified method, the defaults) on the CPU reference,
// and checks the PCS against the exact oracle: non-empty, in range, and holding every triangle of
// every crossing pair (the modified method's promise, cullide.h promisesToKeep).
// Usage: consumer MESH EXPECTED_VERSION. Exit 0 on success, 1 on a failed check, 2 on bad input.
#include <cullide/cullide.h>
#include <cullide/error.h>
#include <cullide/mesh_io.h>
#include <cullide/oracle/oracle.h>
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
        const cullide::CullideResult r = cullide::runCullide(scene, *backend, cullide::CullideOptions{});
        const cullide::oracle::Truth truth = cullide::oracle::findIntersections(scene);
        size_t crossing = 0, kept = 0;
        for (const auto& p : truth.pairs) {
            if (p.cls != cullide::oracle::PairClass::Crossing) continue;
            ++crossing;
            kept += std::binary_search(r.pcs.begin(), r.pcs.end(), p.a()) &&
                std::binary_search(r.pcs.begin(), r.pcs.end(), p.b());
        }
        std::printf("consumer: %s: PCS %zu of %zu triangles; %zu crossing pairs, %zu kept\n", argv[1], r.pcs.size(),
                    scene.triangleCount(), crossing, kept);
        const bool inRange = std::all_of(r.pcs.begin(), r.pcs.end(), [&](const cullide::PcsTriangle& t) {
            return t.object == 0 && t.triangle < scene.triangleCount();
        });
        return !r.pcs.empty() && inRange && crossing > 0 && kept == crossing ? 0 : 1;
    } catch (const cullide::InputError& e) {
        std::fprintf(stderr, "consumer: %s\n", e.what());
        return 2;
    }
}
