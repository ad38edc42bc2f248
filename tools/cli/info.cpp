// `cullide info SCENE|MESH...`: what a scene or mesh holds, and what matters for image-space
// culling in it (degenerate triangles, components, duplicated vertices); with --all-frames, how
// that changes over an animation's frames.
#include "commands.h"

#include "cullide/error.h"
#include "cullide/mesh_stats.h"
#include "cullide/provenance.h"
#include "cullide/scene_io.h"

#include <nlohmann/json.hpp>

#include <cstdio>
#include <string>
#include <vector>

namespace cullide::cli {
namespace {

struct InfoOptions {
    std::vector<std::string> paths;
    bool json = false;
    long frame = 0;
    bool allFrames = false;
};

nlohmann::ordered_json boundsJson(const Bounds& b) {
    if (b.empty()) return nullptr;
    return {{"min", {b.lo.x(), b.lo.y(), b.lo.z()}}, {"max", {b.hi.x(), b.hi.y(), b.hi.z()}}};
}

nlohmann::ordered_json statsJson(const MeshStats& s) {
    return {{"vertices", s.vertices},
            {"triangles", s.triangles},
            {"bounds", boundsJson(s.bounds)},
            {"degenerate_triangles", s.degenerateTriangles},
            {"components", s.components},
            {"duplicate_vertices", s.duplicateVertices},
            {"duplicate_triangles", s.duplicateTriangles},
            {"unreferenced_vertices", s.unreferencedVertices}};
}

void printStats(const char* indent, const MeshStats& s) {
    std::printf("%svertices %zu, triangles %zu\n", indent, s.vertices, s.triangles);
    if (!s.bounds.empty())
        std::printf("%sbounds [%g, %g, %g] .. [%g, %g, %g]\n", indent, s.bounds.lo.x(), s.bounds.lo.y(),
                    s.bounds.lo.z(), s.bounds.hi.x(), s.bounds.hi.y(), s.bounds.hi.z());
    std::printf(
        "%sdegenerate triangles %zu, connected components %zu, duplicate vertices %zu, "
        "duplicate triangles %zu, unreferenced vertices %zu\n",
        indent, s.degenerateTriangles, s.components, s.duplicateVertices, s.duplicateTriangles, s.unreferencedVertices);
}

// Every object's statistics at one frame, and their sum (bounds: of all of them).
struct SceneStats {
    std::vector<MeshStats> objects;
    MeshStats total;
};

SceneStats sceneStats(const Scene& scene) {
    SceneStats st;
    for (size_t i = 0; i < scene.objects.size(); ++i) {
        const MeshStats s = computeStats(scene.worldMesh(i));
        MeshStats& t = st.total;
        t.vertices += s.vertices;
        t.triangles += s.triangles;
        t.degenerateTriangles += s.degenerateTriangles;
        t.components += s.components;
        t.duplicateVertices += s.duplicateVertices;
        t.duplicateTriangles += s.duplicateTriangles;
        t.unreferencedVertices += s.unreferencedVertices;
        t.bounds.add(s.bounds);
        st.objects.push_back(s);
    }
    return st;
}

// One line per frame of the whole scene (text), or an array of one object per frame (JSON): what
// deformation and motion change (bounds, degenerate and duplicate vertices), with the rest. One
// frame is in memory at a time.
nlohmann::ordered_json describeEveryFrame(const Animation& animation, bool json) {
    nlohmann::ordered_json frames = nlohmann::ordered_json::array();
    if (!json) std::printf("  every frame:\n");
    for (size_t f = 0; f < animation.frameCount(); ++f) {
        const MeshStats t = sceneStats(animation.sceneAt(f)).total;
        if (json) {
            nlohmann::ordered_json j = {{"frame", f}};
            j.update(statsJson(t));
            frames.push_back(std::move(j));
            continue;
        }
        std::printf("    frame %zu: triangles %zu", f, t.triangles);
        if (!t.bounds.empty())
            std::printf(", bounds [%g, %g, %g] .. [%g, %g, %g]", t.bounds.lo.x(), t.bounds.lo.y(), t.bounds.lo.z(),
                        t.bounds.hi.x(), t.bounds.hi.y(), t.bounds.hi.z());
        std::printf(", degenerate triangles %zu, duplicate vertices %zu\n", t.degenerateTriangles, t.duplicateVertices);
    }
    return frames;
}

int runInfo(const InfoOptions& o) {
    nlohmann::ordered_json all = nlohmann::ordered_json::array();
    for (const std::string& path : o.paths) {
        const Animation animation = loadScene(path);
        const Scene scene = animation.sceneAt(selectFrames(animation, o.frame, path).first);
        const SceneStats st = sceneStats(scene);

        nlohmann::ordered_json objects = nlohmann::ordered_json::array();
        if (!o.json)
            std::printf("%s: %zu object(s), %zu frame(s)\n", path.c_str(), scene.objects.size(),
                        animation.frameCount());
        for (size_t i = 0; i < scene.objects.size(); ++i) {
            if (o.json) {
                nlohmann::ordered_json j = {{"name", scene.objects[i].name}};
                j.update(statsJson(st.objects[i]));
                objects.push_back(j);
            } else {
                std::printf("  object '%s'\n", scene.objects[i].name.c_str());
                printStats("    ", st.objects[i]);
            }
        }
        if (o.json) {
            nlohmann::ordered_json j = {
                {"path", path}, {"frames", animation.frameCount()}, {"frame", o.frame}, {"objects", objects}};
            j["total"] = statsJson(st.total);
            if (o.allFrames) j["every_frame"] = describeEveryFrame(animation, true);
            // The output stays an array of one object per file; each carries the provenance.
            j["provenance"] = toJson(provenance(0));
            all.push_back(j);
            continue;
        }
        if (scene.objects.size() > 1) {
            std::printf("  total\n");
            printStats("    ", st.total);
        }
        if (o.allFrames) describeEveryFrame(animation, false);
    }
    if (o.json) std::printf("%s\n", all.dump(2).c_str());
    return 0;
}

}  // namespace

void addInfoCommand(CLI::App& app, Action& action) {
    auto o = std::make_shared<InfoOptions>();
    CLI::App* sub = app.add_subcommand("info",
                                       "Describe scenes or meshes: objects, vertices, triangles, bounds, "
                                       "degenerate triangles, components, duplicate vertices");
    sub->add_option("paths", o->paths, "Scene files (.json) or meshes (.obj .off .ply .stl)")->required();
    sub->add_flag("--json", o->json, "Print JSON for machines instead of text");
    addNumber(sub, "--frame", o->frame, "Animation frame to describe (default 0)", 0L, std::numeric_limits<long>::max());
    sub->add_flag("--all-frames", o->allFrames,
                  "Also summarise every frame: triangles, bounds, degenerate triangles, duplicate vertices");
    sub->callback([o, &action] { action = [o] { return runInfo(*o); }; });
}

}  // namespace cullide::cli
