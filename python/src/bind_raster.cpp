// The Python module: the depth-backend interface (CommandList) and the CPU reference backend.
#include "types.h"

#include "cullide/depth_backend.h"
#include "cullide/raster/cpu_backend.h"

#include <optional>
#include <vector>

namespace cullide::python {

void bindCommandList(py::module_& m) {
    py::class_<CommandList>(m, "CommandList",
                            "A depth-only command list, as cullide::CommandList: what one reducePCS pass asks a "
                            "backend to do. Queries are numbered in the order of begin_query().")
        .def(py::init<>())
        .def("clear", &CommandList::clear, py::arg("depth") = 1.0, "Clears the depth buffer to `depth` in [0,1].")
        .def(
            "depth_func", [](CommandList& l, const std::string& f) { l.depthFunc(parseDepthFunc(f)); }, py::arg("func"),
            "Sets the depth function: never, less, equal, lequal, greater, notequal, gequal, always.")
        .def("depth_mask", &CommandList::depthMask, py::arg("write"), "Whether draws write depth.")
        .def(
            "begin_query", [](CommandList& l, const std::string& k) { return l.beginQuery(parseQueryKind(k)); },
            py::arg("kind") = "samples", "Opens a query ('samples' or 'any'); returns its index.")
        .def("end_query", &CommandList::endQuery, "Closes the open query.")
        .def(
            "draw",
            [](CommandList& l, long long first, long long count) {
                l.draw(rangeValue(first, "draw: first"), rangeValue(count, "draw: count"));
            },
            py::arg("first"), py::arg("count"), "Draws triangles [first, first+count) of the geometry.")
        .def("clear_intervals", &CommandList::clearIntervals, "Conservative mode: empties the interval buffer.")
        .def(
            "draw_conservative",
            [](CommandList& l, long long first, long long count, bool test, bool write) {
                l.drawConservative(rangeValue(first, "draw_conservative: first"),
                                   rangeValue(count, "draw_conservative: count"), test, write);
            },
            py::arg("first"), py::arg("count"), py::arg("test"), py::arg("write"),
            "Conservative mode: rasterizes [first, first+count) conservatively.")
        .def_property_readonly("query_count", &CommandList::queryCount, "Queries begun so far.")
        .def("reset", &CommandList::reset, "Empties the list.")
        .def("__len__", [](const CommandList& l) { return l.commands().size(); });

}

void bindCpuBackend(py::module_& m) {
    py::class_<PyCpuBackend>(m, "CpuBackend", "The CPU reference backend (a deterministic software depth buffer).")
        .def(py::init([](int subpixelBits, int threads, int tileSize, bool scalarReference, bool simd, bool direct,
                         long long viewCacheBytes, const std::string& fillRule) {
                 raster::CpuBackendOptions o;
                 o.subpixelBits = subpixelBits;
                 o.threads = checkedThreads(threads);
                 o.tileSize = tileSize;
                 o.scalarReference = scalarReference;
                 o.simd = simd;
                 o.direct = direct;
                 if (viewCacheBytes < 0)
                     fail("argument view_cache_bytes: " + std::to_string(viewCacheBytes) + " is negative");
                 o.viewCacheBytes = size_t(viewCacheBytes);
                 const std::optional<raster::FillRule> rule = raster::parseFillRule(fillRule);
                 if (!rule) fail("argument fill_rule: '" + fillRule + "' is not " + raster::kFillRuleNames);
                 o.fillRule = *rule;
                 PyCpuBackend b;
                 b.backend = raster::makeCpuBackend(o);
                 return b;
             }),
             py::arg("subpixel_bits") = raster::kDefaultSubpixelBits, py::arg("threads") = 0,
             py::arg("tile_size") = raster::kDefaultTileSize, py::arg("scalar_reference") = false,
             py::arg("simd") = true, py::arg("direct") = true,
             py::arg("view_cache_bytes") = (long long)raster::CpuBackendOptions{}.viewCacheBytes,
             py::arg("fill_rule") = "bottom-left")
        .def(
            "describe", [](const PyCpuBackend& b) { return b.backend->describe(); }, "A short description.")
        .def_property_readonly(
            "last_stats",
            [](const PyCpuBackend& b) {
                const raster::RasterStats& s = b.backend->lastStats();
                py::dict d;
                d["draws"] = s.draws, d["triangles"] = s.triangles, d["rejected"] = s.rejected;
                d["clipped"] = s.clipped, d["zero_area"] = s.zeroArea, d["fragments"] = s.fragments;
                d["passed"] = s.passed;
                return d;
            },
            "Counters of the last execute() (RasterStats; per drawn triangle instance), the same on every path.")
        .def_property_readonly(
            "last_ran_direct", [](const PyCpuBackend& b) { return b.backend->lastRanDirect(); },
            "Whether the last execute() took the direct path (option direct).")
        .def_property_readonly(
            "last_replayed_view", [](const PyCpuBackend& b) { return b.backend->lastReplayedView(); },
            "Whether the last execute() replayed fragments kept under its view (option view_cache_bytes).")
        .def(
            "set_geometry",
            [](PyCpuBackend& b, const py::object& v, const py::object& f) {
                const Mesh mesh = meshFromPython(v, f, "geometry");
                b.backend->setGeometry(mesh.positions, mesh.triangles);
            },
            py::arg("vertices"), py::arg("faces") = py::none(),
            "Sets the triangles to draw: (n,3) vertices and (m,3) faces (validated), or one object with them.")
        .def(
            "set_view",
            [](PyCpuBackend& b, const py::object& direction, const py::object& box, int width, int height,
               const std::string& depth) {
                OrthoView v = OrthoView::looking(vec3(direction, "direction"));
                std::vector<double> bx;
                try {
                    bx = box.cast<std::vector<double>>();
                } catch (const py::cast_error&) {
                    fail("box: not a sequence of 6 numbers");
                }
                if (bx.size() != 6) fail("box: has " + std::to_string(bx.size()) + " numbers, not 6");
                v.xmin = bx[0], v.xmax = bx[1], v.ymin = bx[2], v.ymax = bx[3], v.znear = bx[4], v.zfar = bx[5];
                v.width = width, v.height = height;
                v.depth = DepthFormat::parse(depth);
                b.backend->setView(v);
                b.viewSet = true;
                py::dict frame;
                frame["right"] = py::make_tuple(v.right.x(), v.right.y(), v.right.z());
                frame["up"] = py::make_tuple(v.up.x(), v.up.y(), v.up.z());
                frame["dir"] = py::make_tuple(v.dir.x(), v.dir.y(), v.dir.z());
                return frame;
            },
            py::arg("direction"), py::arg("box"), py::arg("width") = 500, py::arg("height") = 500,
            py::arg("depth") = "d24",
            "Sets an orthographic view looking along `direction` (frame as OrthoView::looking); box = (xmin, xmax, "
            "ymin, ymax, znear, zfar) in that frame's view coordinates. Returns the frame (right, up, dir).")
        .def(
            "execute",
            [](PyCpuBackend& b, const CommandList& l) {
                if (!b.viewSet) fail("execute: call set_view first");
                std::vector<uint64_t> r;
                {
                    py::gil_scoped_release release;
                    r = b.backend->execute(l);
                }
                py::array_t<uint64_t> a(py::ssize_t(r.size()));
                if (!r.empty()) std::memcpy(a.mutable_data(), r.data(), r.size() * sizeof(uint64_t));
                return a;
            },
            py::arg("commands"), "Executes a CommandList; returns one uint64 result per query.")
        .def(
            "read_depth",
            [](PyCpuBackend& b) {
                if (!b.viewSet) fail("read_depth: call set_view first");
                const DepthImage img = b.backend->readDepth();
                return makeArray(img.values, size_t(img.height), size_t(img.width));
            },
            "The stored depth buffer as (h,w) uint32: unorm codes (or float bit patterns for d32f); row 0 is the "
            "bottom row (GL window coordinates).");
}

}  // namespace cullide::python
