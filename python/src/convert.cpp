// Python values to cullide's types and back (convert.h).
#include "convert.h"

#include "cullide/mesh.h"

#include <cmath>

namespace cullide::python {

void fail(const std::string& what) {
    throw py::value_error(what);
}

py::array_t<float> verticesArray(const Mesh& m) {
    std::vector<float> v;
    v.reserve(m.positions.size() * 3);
    for (const Vec3f& p : m.positions) v.insert(v.end(), {p.x(), p.y(), p.z()});
    return makeArray(v, m.positions.size(), 3);
}

py::array_t<uint32_t> facesArray(const Mesh& m) {
    std::vector<uint32_t> f;
    f.reserve(m.triangles.size() * 3);
    for (const Triangle& t : m.triangles) f.insert(f.end(), t.begin(), t.end());
    return makeArray(f, m.triangles.size(), 3);
}

// The array as a C-contiguous array of T, after checking its dtype kind ('f' float, 'i'/'u' integer)
// and shape (rows unknown: -1). `name` names the argument in errors.
py::array checkedArray(const py::handle& obj, const std::string& name, int cols, bool integer) {
    py::array a;
    try {
        a = py::array::ensure(obj);
    } catch (...) {}
    if (!a) fail(name + ": not an array (got " + std::string(py::str(py::type::handle_of(obj).attr("__name__"))) + ")");
    const char kind = a.dtype().kind();
    if (integer && kind != 'i' && kind != 'u')
        fail(name + ": dtype " + std::string(py::str(a.dtype())) + " is not an integer type");
    if (!integer && kind != 'f' && kind != 'i' && kind != 'u')
        fail(name + ": dtype " + std::string(py::str(a.dtype())) + " is not a real number type");
    if (a.ndim() != 2 || a.shape(1) != cols) {
        std::string shape = "(";
        for (py::ssize_t d = 0; d < a.ndim(); ++d) shape += (d ? ", " : "") + std::to_string(a.shape(d));
        shape += a.ndim() == 1 ? ",)" : ")";
        fail(name + ": shape " + shape + " is not (n, " + std::to_string(cols) + ")");
    }
    return a;
}

// (V, F) -> Mesh, validated: V (n,3) real, finite; F (m,3) integers in [0, n).
Mesh meshFromArrays(const py::handle& vertices, const py::handle& faces, const std::string& name) {
    const py::array v = checkedArray(vertices, name + ": vertices", 3, false);
    const py::array f = checkedArray(faces, name + ": faces", 3, true);
    const auto vd = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(v);
    Mesh m;
    m.positions.resize(size_t(v.shape(0)));
    const double* pv = vd.data();
    for (size_t i = 0; i < m.positions.size(); ++i) {
        for (int k = 0; k < 3; ++k) {
            const double x = pv[3 * i + k];
            if (!std::isfinite(x) || !std::isfinite(float(x)))
                fail(name + ": vertices: row " + std::to_string(i) +
                     " has a NaN, infinite or out-of-float-range value");
        }
        m.positions[i] = Vec3f(float(pv[3 * i]), float(pv[3 * i + 1]), float(pv[3 * i + 2]));
    }
    // Indices read as signed 64-bit (uint64 above INT64_MAX wraps negative and is refused too).
    const auto fd = py::array_t<int64_t, py::array::c_style | py::array::forcecast>::ensure(f);
    m.triangles.resize(size_t(f.shape(0)));
    const int64_t* pf = fd.data();
    const int64_t n = int64_t(m.positions.size());
    for (size_t t = 0; t < m.triangles.size(); ++t)
        for (int k = 0; k < 3; ++k) {
            const int64_t idx = pf[3 * t + k];
            if (idx < 0 || idx >= n)
                fail(name + ": faces: row " + std::to_string(t) + " has index " + std::to_string(idx) + " outside 0.." +
                     std::to_string(n - 1) + " (" + std::to_string(n) + " vertices)");
            m.triangles[t][size_t(k)] = uint32_t(idx);
        }
    validateMesh(m, name);
    return m;
}

// (V, F) from either two arrays or one object with .vertices and .faces (trimesh, Open3D-like).
Mesh meshFromPython(const py::object& v, const py::object& f, const std::string& name) {
    if (f.is_none()) {
        if (py::hasattr(v, "vertices") && py::hasattr(v, "faces"))
            return meshFromArrays(v.attr("vertices"), v.attr("faces"), name);
        fail(name + ": give vertices and faces, or one object with .vertices and .faces");
    }
    return meshFromArrays(v, f, name);
}

Transform transformFromPython(const py::object& obj, const std::string& name) {
    Transform t = Transform::Identity();
    if (obj.is_none()) return t;
    const py::array a = checkedArray(obj, name, 4, false);
    if (a.shape(0) != 4) fail(name + ": shape (" + std::to_string(a.shape(0)) + ", 4) is not (4, 4)");
    const auto d = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(a);
    const double* p = d.data();
    for (int i = 0; i < 16; ++i)
        if (!std::isfinite(p[i])) fail(name + ": has a NaN or infinite value");
    if (p[12] != 0 || p[13] != 0 || p[14] != 0 || p[15] != 1)
        fail(name + ": the last row must be [0, 0, 0, 1] (an affine transform)");
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 4; ++c) t.matrix()(r, c) = float(p[4 * r + c]);
    return t;
}

Vec3d vec3(const py::handle& obj, const std::string& name) {
    std::vector<double> v;
    try {
        v = obj.cast<std::vector<double>>();
    } catch (const py::cast_error&) {
        fail(name + ": not a sequence of 3 numbers");
    }
    if (v.size() != 3) fail(name + ": has " + std::to_string(v.size()) + " numbers, not 3");
    for (double x : v)
        if (!std::isfinite(x)) fail(name + ": has a NaN or infinite value");
    return {v[0], v[1], v[2]};
}

std::string integerText(const py::handle& obj, const std::string& name) {
    if (py::isinstance<py::str>(obj)) return obj.cast<std::string>();
    if (py::isinstance<py::bool_>(obj) || !PyIndex_Check(obj.ptr()))
        fail(name + ": " + std::string(py::str(py::type::handle_of(obj).attr("__name__"))) + " is not an integer");
    return py::str(py::reinterpret_steal<py::object>(PyNumber_Index(obj.ptr())));
}

// A draw range bound from Python: 0..2^32-1 (CommandList then checks that first + count fits).
uint32_t rangeValue(long long v, const std::string& name) {
    if (v < 0 || v > 0xffffffffLL) fail(name + ": " + std::to_string(v) + " is not 0..4294967295");
    return uint32_t(v);
}

}  // namespace cullide::python
