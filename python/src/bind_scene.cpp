// The Python module: scenes and mesh loading (Scene, load_mesh, load_scene).
#include "types.h"

#include "cullide/mesh_io.h"
#include "cullide/scene_io.h"

#include <utility>
#include <vector>

namespace cullide::python {

void bindScene(py::module_& m) {
    m.def(
        "load_mesh",
        [](const std::string& path) {
            Mesh mesh;
            {
                py::gil_scoped_release release;
                mesh = loadMesh(path);
            }
            return py::make_tuple(verticesArray(mesh), facesArray(mesh));
        },
        py::arg("path"),
        "Loads a mesh (.off, .obj, .ply, .stl) as (V float32 (n,3), F uint32 (m,3)); ValueError on a bad file.");

    py::class_<PyScene>(m, "Scene", "A scene: named objects (mesh and 4x4 transform), optionally animated frames.")
        .def(py::init<>(), "An empty scene (prune, oracle and world_mesh need at least one object: add them).")
        .def(
            "add",
            [](PyScene& s, const std::string& name, const py::object& v, const py::object& f,
               const py::object& transform) {
                // The names a scene file may have (frames and results name objects by them).
                checkObjectName(name, s.names.contains(name), "argument name", "");
                Object o;
                o.name = name;
                o.mesh = meshFromPython(v, f, "object '" + name + "'");
                o.transform = transformFromPython(transform, "object '" + name + "': transform");
                checkWorldPositions(o.mesh.positions, o.transform, name, "Scene.add", "");
                s.names.insert(name);
                s.animation.scene.objects.push_back(std::move(o));
                // An animated scene: the new object keeps its mesh and transform in every frame.
                for (Frame& fr : s.animation.frames)
                    if (!fr.poses.empty()) fr.poses.emplace_back();
                return s.animation.scene.objects.size() - 1;
            },
            py::arg("name"), py::arg("vertices"), py::arg("faces") = py::none(), py::arg("transform") = py::none(),
            "Adds an object: vertices (n,3) real and faces (m,3) integer arrays, or one object with .vertices "
            "and .faces (a trimesh mesh) as `vertices`; transform: a 4x4 affine matrix (default identity). "
            "Vertices are stored as float32. Returns the object's index. ValueError on bad arrays, an empty "
            "name or one the scene has, or world coordinates (transform times vertices, in float32) that are "
            "not finite or beyond 2^60.")
        .def_property_readonly(
            "object_count", [](const PyScene& s) { return s.animation.scene.objects.size(); }, "Number of objects.")
        .def_property_readonly(
            "frame_count", [](const PyScene& s) { return s.animation.frameCount(); },
            "Number of frames (1 for a still scene).")
        .def_property_readonly(
            "triangle_count", [](const PyScene& s) { return s.animation.scene.triangleCount(); },
            "Triangles over all objects.")
        .def_property_readonly(
            "names",
            [](const PyScene& s) {
                std::vector<std::string> n;
                for (const Object& o : s.animation.scene.objects) n.push_back(o.name);
                return n;
            },
            "The objects' names, in order.")
        .def(
            "world_mesh",
            [](const PyScene& s, long object, long frame) {
                const Scene scene = s.at(frame);
                if (object < 0 || size_t(object) >= scene.objects.size())
                    fail("object: " + std::to_string(object) + " is not an object of the scene (0.." +
                         std::to_string(long(scene.objects.size()) - 1) + ")");
                const Mesh w = scene.worldMesh(size_t(object));
                return py::make_tuple(verticesArray(w), facesArray(w));
            },
            py::arg("object"), py::arg("frame") = 0,
            "Object `object` at `frame` with its transform applied: (V float32 (n,3), F uint32 (m,3)).")
        .def("__len__", [](const PyScene& s) { return s.animation.scene.objects.size(); });

    m.def(
        "load_scene",
        [](const std::string& path) {
            PyScene s;
            s.source = path;
            py::gil_scoped_release release;
            s.animation = loadScene(path);
            for (const Object& o : s.animation.scene.objects) s.names.insert(o.name);
            return s;
        },
        py::arg("path"),
        "Loads a scene file (.json, docs/scene-format) or a mesh (one object) as a Scene; ValueError on a bad file.");

}

}  // namespace cullide::python
