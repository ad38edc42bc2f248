// The depth-query backend interface: formats, views, command lists and the immediate context.
// See depth_backend.h for the conventions; the rasterization itself lives in raster/.
#include "cullide/depth_backend.h"

#include "cullide/error.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <bit>
#include <cctype>
#include <cmath>
#include <limits>
#include <string>
#include <utility>

namespace cullide {

const char* toString(DepthFunc f) {
    switch (f) {
        case DepthFunc::Never: return "NEVER";
        case DepthFunc::Less: return "LESS";
        case DepthFunc::Equal: return "EQUAL";
        case DepthFunc::LEqual: return "LEQUAL";
        case DepthFunc::Greater: return "GREATER";
        case DepthFunc::NotEqual: return "NOTEQUAL";
        case DepthFunc::GEqual: return "GEQUAL";
        case DepthFunc::Always: return "ALWAYS";
    }
    return "?";
}

// ---------------------------------------------------------------------------------------------
// DepthFormat

DepthFormat DepthFormat::unorm(int n) {
    if (n < 8 || n > 32) throw InputError("depth format", "unorm depth needs 8 to 32 bits, got " + std::to_string(n));
    return {Kind::Unorm, n};
}

// DepthFormat::parse is with the other option parsers (options.cpp).

std::string DepthFormat::name() const {
    if (kind == Kind::Float32) return "D32F";
    std::string s = std::to_string(bits);  // (not "D" + ...: GCC 12 warns falsely, -Wrestrict)
    s.insert(s.begin(), 'D');
    return s;
}

double DepthFormat::resolution() const {
    if (kind == Kind::Float32) return std::ldexp(1.0, -24);
    return 1.0 / (std::ldexp(1.0, bits) - 1.0);
}

// ---------------------------------------------------------------------------------------------
// OrthoView

namespace {

// right.p etc., evaluated left to right in double (written out so that no backend depends on how
// Eigen vectorizes a dot product).
inline double dot3(const Vec3d& a, double x, double y, double z) {
    return a.x() * x + a.y() * y + a.z() * z;
}

bool finite3(const Vec3d& v) {
    return std::isfinite(v.x()) && std::isfinite(v.y()) && std::isfinite(v.z());
}

}  // namespace

Vec3d OrthoView::toWindow(const Vec3f& p) const {
    const double px = p.x(), py = p.y(), pz = p.z();
    const double x = dot3(right, px, py, pz), y = dot3(up, px, py, pz), z = dot3(dir, px, py, pz);
    return {(x - xmin) / (xmax - xmin) * double(fullWidth()) - double(originX),
            (y - ymin) / (ymax - ymin) * double(fullHeight()) - double(originY), (z - znear) / (zfar - znear)};
}

OrthoView OrthoView::tile(int x, int y, int w, int h) const {
    OrthoView t = *this;
    t.gridWidth = fullWidth(), t.gridHeight = fullHeight();
    t.originX = originX + x, t.originY = originY + y;
    t.width = w, t.height = h;
    return t;
}

OrthoView OrthoView::looking(const Vec3d& direction) {
    if (!finite3(direction) || direction.norm() == 0.0)
        throw InputError("view", "the view direction must be a finite, non-zero vector");
    OrthoView v;
    v.dir = direction.normalized();
    int axis = 0;  // the world axis least aligned with dir (first one on ties)
    for (int k = 1; k < 3; ++k)
        if (std::abs(v.dir[k]) < std::abs(v.dir[axis])) axis = k;
    const Vec3d helper = Vec3d::Unit(axis);
    v.right = helper.cross(v.dir).normalized();
    v.up = v.dir.cross(v.right);
    return v;
}

void OrthoView::validate() const {
    if (!finite3(right) || !finite3(up) || !finite3(dir))
        throw InputError("view", "the view frame has a non-finite component");
    constexpr double tol = 1e-9;
    const bool unit =
        std::abs(right.norm() - 1) < tol && std::abs(up.norm() - 1) < tol && std::abs(dir.norm() - 1) < tol;
    const bool ortho = std::abs(right.dot(up)) < tol && std::abs(right.dot(dir)) < tol && std::abs(up.dot(dir)) < tol;
    if (!unit || !ortho) throw InputError("view", "the view frame (right, up, dir) is not orthonormal");
    if (right.cross(up).dot(dir) < 0) throw InputError("view", "the view frame (right, up, dir) is left-handed");
    // Views fitted to a scene's geometry are finite (world coordinates are checked where a scene is
    // made, scene.h); a box that is not comes from a caller that set it.
    const std::pair<const char*, double> bounds[] = {{"xmin", xmin}, {"xmax", xmax},   {"ymin", ymin},
                                                     {"ymax", ymax}, {"znear", znear}, {"zfar", zfar}};
    for (const auto& [name, d] : bounds)
        if (!std::isfinite(d))
            throw InputError(
                "view", std::string("the view box's ") + name + " is " + std::to_string(d) + ", not a finite number");
    if (!(xmin < xmax) || !(ymin < ymax) || !(znear < zfar))
        throw InputError("view", "the view box is empty (need xmin < xmax, ymin < ymax, znear < zfar)");
    if (!std::isfinite(xmax - xmin) || !std::isfinite(ymax - ymin) || !std::isfinite(zfar - znear))
        throw InputError("view", "the view box is too large");
    if (width < 1 || width > kMaxViewportSide || height < 1 || height > kMaxViewportSide)
        throw InputError("view",
                         "the viewport must be 1.." + std::to_string(kMaxViewportSide) + " pixels per side, got " +
                             std::to_string(width) + "x" + std::to_string(height));
    if (tiled()) {
        if (gridWidth < 1 || gridWidth > kMaxViewportSide || gridHeight < 1 || gridHeight > kMaxViewportSide)
            throw InputError("view",
                             "a tile's grid must be 1.." + std::to_string(kMaxViewportSide) + " pixels per side, got " +
                                 std::to_string(gridWidth) + "x" + std::to_string(gridHeight));
        if (originX < 0 || originY < 0 || originX > gridWidth - width || originY > gridHeight - height)
            throw InputError("view",
                             "the tile " + std::to_string(width) + "x" + std::to_string(height) + " at (" +
                                 std::to_string(originX) + ", " + std::to_string(originY) +
                                 ") does not lie inside its " + std::to_string(gridWidth) + "x" +
                                 std::to_string(gridHeight) + " grid");
    } else if (originX != 0 || originY != 0) {
        throw InputError("view", "a view with an origin needs its grid (gridWidth, gridHeight)");
    }
    if (depth.kind == DepthFormat::Kind::Unorm && (depth.bits < 8 || depth.bits > 32))
        throw InputError("view", "unorm depth needs 8 to 32 bits, got " + std::to_string(depth.bits));
    if (depth.kind == DepthFormat::Kind::Float32 && depth.bits != 32)
        throw InputError("view", "a float depth format has 32 bits");
}

// ---------------------------------------------------------------------------------------------
// CommandList

void CommandList::clear(double depth) {
    if (!(depth >= 0.0 && depth <= 1.0))
        throw InputError("command list", "clear depth must lie in [0,1], got " + std::to_string(depth));
    Command c{Command::Op::Clear};
    c.clearDepth = depth;
    commands_.push_back(c);
}

void CommandList::depthFunc(DepthFunc f) {
    Command c{Command::Op::SetDepthFunc};
    c.func = f;
    commands_.push_back(c);
}

void CommandList::depthMask(bool write) {
    Command c{Command::Op::SetDepthMask};
    c.mask = write;
    commands_.push_back(c);
}

uint32_t CommandList::beginQuery(QueryKind kind) {
    if (inQuery_)
        throw InputError("command list",
                         "beginQuery() while query " + std::to_string(queries_ - 1) + " is open (queries do not nest)");
    Command c{Command::Op::BeginQuery};
    c.queryKind = kind;
    commands_.push_back(c);
    inQuery_ = true;
    return queries_++;
}

void CommandList::endQuery() {
    if (!inQuery_) throw InputError("command list", "endQuery() without an open query");
    commands_.push_back(Command{Command::Op::EndQuery});
    inQuery_ = false;
}

namespace {

// A draw command (`op`) of the triangles [first, first + count); InputError when the range
// overflows 32-bit triangle indices.
Command drawCommand(Command::Op op, uint32_t first, uint32_t count) {
    if (uint64_t(first) + count > std::numeric_limits<uint32_t>::max())
        throw InputError("command list",
                         "draw range [" + std::to_string(first) + ", +" + std::to_string(count) +
                             ") overflows 32-bit triangle indices");
    Command c{op};
    c.first = first;
    c.count = count;
    return c;
}

}  // namespace

void CommandList::draw(uint32_t first, uint32_t count) {
    commands_.push_back(drawCommand(Command::Op::Draw, first, count));
    ++draws_;
}

void CommandList::clearIntervals() {
    commands_.push_back(Command{Command::Op::ClearIntervals});
    ++conservative_;
}

void CommandList::drawConservative(uint32_t first, uint32_t count, bool test, bool write) {
    if (!test && !write) throw InputError("command list", "a conservative draw must test, write or both");
    Command c = drawCommand(Command::Op::DrawConservative, first, count);
    c.test = test;
    c.write = write;
    commands_.push_back(c);
    ++draws_;
    ++conservative_;
}

void CommandList::reset() {
    commands_.clear();
    queries_ = 0;
    draws_ = 0;
    conservative_ = 0;
    inQuery_ = false;
}

// ---------------------------------------------------------------------------------------------
// DepthImage

double DepthImage::depth(int x, int y) const {
    const uint32_t v = at(x, y);
    if (format.kind == DepthFormat::Kind::Float32) return double(std::bit_cast<float>(v));
    return double(v) / (std::ldexp(1.0, format.bits) - 1.0);
}

// ---------------------------------------------------------------------------------------------
// ImmediateContext

void ImmediateContext::run() {
    if (inQuery_) return;  // buffered until endQuery()
    backend_.execute(list_);
    list_.reset();
}

void ImmediateContext::clear(double depth) {
    list_.clear(depth);
    run();
}

void ImmediateContext::depthFunc(DepthFunc f) {
    list_.depthFunc(f);
    run();
}

void ImmediateContext::depthMask(bool write) {
    list_.depthMask(write);
    run();
}

void ImmediateContext::draw(uint32_t first, uint32_t count) {
    list_.draw(first, count);
    run();
}

void ImmediateContext::beginQuery(QueryKind kind) {
    list_.beginQuery(kind);  // throws when one is open
    inQuery_ = true;
}

uint64_t ImmediateContext::endQuery() {
    list_.endQuery();  // throws without an open query
    inQuery_ = false;
    const std::vector<uint64_t> results = backend_.execute(list_);
    list_.reset();
    CULLIDE_CHECK(results.size() == 1, "an immediate query list must yield exactly one result");
    return results[0];
}

}  // namespace cullide
