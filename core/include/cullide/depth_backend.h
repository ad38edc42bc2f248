// The depth-query backend interface: exactly what Cullide asks of a GPU, and nothing more.
//
// A backend owns a depth buffer (no colour) and occlusion-query counters. Per frame it receives
// the geometry once (positions + triangles); per reducePCS pass it receives a view and executes
// a command list, returning every query's result. Two implementations stand behind it: the
// deterministic CPU reference (raster/) and OpenGL (raster/gl/).
//
// Conventions
//   - View space: an orthonormal frame (right, up, dir). A world point p has view coordinates
//     x = right.p, y = up.p, z = dir.p; the camera looks along +dir, so depth grows along dir
//     ("near" is the smallest z).
//   - The view box [xmin,xmax] x [ymin,ymax] x [znear,zfar] maps to GL window coordinates:
//       xw = (x - xmin) / (xmax - xmin) * width,   yw = (y - ymin) / (ymax - ymin) * height,
//       zw = (z - znear) / (zfar - znear)          (glDepthRange(0, 1); y up, origin bottom-left)
//     OrthoView::toWindow() is that map, evaluated in double from float positions; every backend
//     uses it (or reproduces it) so both see the same window coordinates.
//   - Depth functions and queries have GL's meaning (GL 4.6 §17.3.4, §17.3.5). A fragment passes
//     when `incoming FUNC stored` holds, compared on the stored representation of the format.
//   - State persists across execute() calls, as in GL: depth buffer contents, depth function
//     (initially LESS), depth mask (initially true). Changing the viewport size makes the depth
//     contents undefined until the next clear.
//   - Conservative mode (optional; supportsConservative()): a second buffer, the *interval
//     buffer*, holds per pixel [lo, hi] in the stored representation of the depth format, the
//     union (min of lo, max of hi) of the conservative fragments written since its last clear
//     (cleared: empty, lo = max code, hi = 0). A conservative fragment exists at every pixel whose
//     closed square the triangle overlaps at all (degenerate triangles included), with the
//     interval of the triangle's depth over that pixel, clamped to the triangle's own depth range
//     and rounded outwards in the depth format. Its test "conflicts" unless the interval lies
//     strictly in front of (hi < stored lo) or strictly behind (lo > stored hi) everything stored
//     at the pixel; a query counts conflicting fragments. The GL depth buffer, functions and mask
//     are not involved. Used by the reliable method (docs/reliable.md); the CPU backend's rules
//     are in cullide/raster/rules.h.
#pragma once

#include "cullide/mesh.h"

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace cullide {

// The eight GL depth functions, in GL's enum order (GL_NEVER + k).
enum class DepthFunc : uint8_t { Never, Less, Equal, LEqual, Greater, NotEqual, GEqual, Always };

const char* toString(DepthFunc f);

// Whether `incoming FUNC stored` holds; T is the stored representation (uint32_t or float).
template <typename T>
constexpr bool depthTest(DepthFunc f, T incoming, T stored) {
    switch (f) {
        case DepthFunc::Never: return false;
        case DepthFunc::Less: return incoming < stored;
        case DepthFunc::Equal: return incoming == stored;
        case DepthFunc::LEqual: return incoming <= stored;
        case DepthFunc::Greater: return incoming > stored;
        case DepthFunc::NotEqual: return incoming != stored;
        case DepthFunc::GEqual: return incoming >= stored;
        case DepthFunc::Always: return true;
    }
    return false;
}

enum class QueryKind : uint8_t {
    SamplesPassed,  // number of fragments that passed the depth test
    AnySamplesPassed,  // 1 if any fragment passed, else 0
};

// Largest viewport side, 2^14 pixels: OrthoView::validate, the option parsers and the CLI enforce
// it, and the CPU rasterizer's fixed-point ranges rely on it (cullide/raster/rules.h).
inline constexpr int kMaxViewportSide = 16384;

// How depth is stored: unsigned normalized with n bits (8..32), k = round(z * (2^n - 1)) after
// clamping z to [0,1]; or IEEE 32-bit float (z clamped to [0,1], stored as float).
struct DepthFormat {
    enum class Kind : uint8_t { Unorm, Float32 };
    Kind kind = Kind::Unorm;
    int bits = 24;

    static DepthFormat unorm(int n);  // throws InputError("depth format", ...) unless 8 <= n <= 32
    static DepthFormat float32() { return {Kind::Float32, 32}; }
    // Parses "24", "d24", "unorm24", "float", "f32", "d32f" (case-insensitive); throws InputError.
    // Defined with the other option parsers (options.cpp).
    static DepthFormat parse(const std::string& text);

    std::string name() const;  // "D24", "D32F"
    // Size of one unit in the last place over [0,1]: 1/(2^n - 1) for unorm; 2^-24 (ulp at 1) for float.
    double resolution() const;
    friend bool operator==(const DepthFormat&, const DepthFormat&) = default;
};

// An orthographic view: frame, box, viewport and depth format.
struct OrthoView {
    Vec3d right{1, 0, 0}, up{0, 1, 0}, dir{0, 0, 1};  // orthonormal, right-handed
    double xmin = -1, xmax = 1, ymin = -1, ymax = 1, znear = -1, zfar = 1;
    int width = 500, height = 500;
    DepthFormat depth;
    // A tile: this view is the pixels [originX, originX + width) x [originY, originY + height) of
    // the view of gridWidth x gridHeight pixels over the same box (0: the view is whole, its grid
    // is width x height). Window coordinates are the whole view's minus the origin, an exact
    // integer shift, so a tile rasterizes exactly the fragments the whole view has there (every
    // rule of cullide/raster/rules.h is invariant under integer translation). Cullide draws a call
    // in tiles when its viewport exceeds DepthBackend::maxViewportSide().
    int originX = 0, originY = 0, gridWidth = 0, gridHeight = 0;

    int fullWidth() const { return gridWidth ? gridWidth : width; }
    int fullHeight() const { return gridHeight ? gridHeight : height; }
    bool tiled() const { return gridWidth != 0 || gridHeight != 0; }
    // The tile [x, x + w) x [y, y + h) of this (whole) view.
    OrthoView tile(int x, int y, int w, int h) const;

    // Window coordinates (xw, yw, zw) of a world point, in double (see the conventions above; for a
    // tile, xw = (x - xmin) / (xmax - xmin) * gridWidth - originX, likewise yw).
    Vec3d toWindow(const Vec3f& p) const;
    // A frame whose `dir` is the given direction (normalized), with right/up chosen
    // deterministically (right = normalize(cross(helper, dir)) with helper the world axis least
    // aligned with dir; up = cross(dir, right)).
    static OrthoView looking(const Vec3d& direction);
    // Throws InputError("view", ...) on a non-orthonormal frame, an empty box, a viewport outside
    // 1..kMaxViewportSide per side, a tile outside its grid (or a grid over kMaxViewportSide), or
    // non-finite numbers.
    void validate() const;
};

// One recorded command. Use CommandList's methods to build them.
struct Command {
    enum class Op : uint8_t {
        Clear,
        SetDepthFunc,
        SetDepthMask,
        BeginQuery,
        EndQuery,
        Draw,
        ClearIntervals,  // conservative mode: empty every pixel's interval
        DrawConservative,  // conservative mode: triangles [first, first+count) with test/write below
    };
    Op op;
    DepthFunc func = DepthFunc::Less;  // SetDepthFunc
    QueryKind queryKind = QueryKind::SamplesPassed;  // BeginQuery
    bool mask = true;  // SetDepthMask
    double clearDepth = 1.0;  // Clear: window-space depth in [0,1]
    uint32_t first = 0, count = 0;  // Draw, DrawConservative: triangles [first, first+count)
    bool test = false, write = false;  // DrawConservative: count conflicts / merge intervals
};

// A command list: what one reducePCS pass (or any depth-only workload) asks a backend to do.
// Queries may not nest (GL allows one active query per target); results are numbered in the
// order of beginQuery() calls. Misuse is reported when recorded, as InputError("command list",
// cause): beginQuery() while a query is open, endQuery() without one, a clear depth outside
// [0,1] (or NaN), a draw range whose end overflows 32 bits. Draw ranges are checked against the
// geometry by the backend's execute().
class CommandList {
public:
    void clear(double depth = 1.0);
    void depthFunc(DepthFunc f);
    void depthMask(bool write);
    uint32_t beginQuery(QueryKind kind = QueryKind::SamplesPassed);  // returns the query's index
    void endQuery();
    void draw(uint32_t first, uint32_t count);
    // Conservative mode (see the conventions; only for a backend whose supportsConservative()):
    // clearIntervals() empties the interval buffer; drawConservative() rasterizes the triangles
    // conservatively and, per fragment, first tests it against the stored interval when `test`
    // (inside a query, a conflicting fragment counts as a passed sample), then merges its interval
    // into the stored one when `write`. Throws InputError("command list", ...) when neither is set
    // or the range overflows, like draw().
    void clearIntervals();
    void drawConservative(uint32_t first, uint32_t count, bool test, bool write);
    bool queryOpen() const { return inQuery_; }
    size_t conservativeCount() const { return conservative_; }  // ClearIntervals + DrawConservative

    const std::vector<Command>& commands() const { return commands_; }
    uint32_t queryCount() const { return queries_; }
    size_t drawCount() const { return draws_; }
    void reset();

private:
    std::vector<Command> commands_;
    uint32_t queries_ = 0;
    size_t draws_ = 0;
    size_t conservative_ = 0;
    bool inQuery_ = false;
};

// The stored depth buffer, for tests and debug pictures. Row 0 is the bottom row (GL window
// coordinates). For unorm formats `values` holds k; for float it holds the float's bit pattern.
struct DepthImage {
    int width = 0, height = 0;
    DepthFormat format;
    std::vector<uint32_t> values;

    uint32_t at(int x, int y) const { return values[size_t(y) * size_t(width) + size_t(x)]; }
    double depth(int x, int y) const;  // as a window depth in [0,1]
};

class DepthBackend {
public:
    virtual ~DepthBackend() = default;

    // A short description of the implementation ("cpu reference (8 subpixel bits, 4 threads)",
    // "gl: llvmpipe (LLVM 15.0.7, 256 bits), 4.5 core").
    virtual std::string describe() const = 0;

    // Geometry for the frame: the backend copies what it needs; the spans may die afterwards.
    // Indices must be < positions.size() (validated meshes guarantee it).
    virtual void setGeometry(std::span<const Vec3f> positions, std::span<const Triangle> triangles) = 0;
    // setGeometry for a caller that keeps both arrays alive and unchanged until its next
    // setGeometry or borrowGeometry (runCullide lends its own arrays for the run and takes them
    // back with borrowGeometry({}, {}) before it returns). A backend that can read the geometry in
    // place skips the copy and returns true (the CPU reference: 18 bytes per triangle of a
    // prune's peak); the default copies (setGeometry) and returns false.
    virtual bool borrowGeometry(std::span<const Vec3f> positions, std::span<const Triangle> triangles) {
        setGeometry(positions, triangles);
        return false;
    }

    // The view for the following execute() calls (validated; throws InputError on a bad view).
    virtual void setView(const OrthoView& view) = 0;

    // Executes the commands in order and returns one result per query (index = query number).
    // Draw ranges must lie inside the current geometry and no query may be left open; otherwise
    // throws InputError("command list", ...) before executing anything. Needs setView() first.
    // A backend without supportsConservative() must refuse conservative commands the same way.
    virtual std::vector<uint64_t> execute(const CommandList& commands) = 0;

    // Whether execute() implements the conservative commands (ClearIntervals, DrawConservative).
    // The CPU reference does; GL only where the driver offers conservative rasterization.
    virtual bool supportsConservative() const { return false; }

    // The largest viewport side this backend can draw (at most kMaxViewportSide). A Cullide call
    // whose viewport is larger draws it as tiles of at most this side (OrthoView::tile), one
    // execute() of the call's command list per tile, adding their query results.
    virtual int maxViewportSide() const { return kMaxViewportSide; }

    // The current depth buffer.
    virtual DepthImage readDepth() = 0;
    // The same into `out`, whose buffer a backend may reuse: for callers that read many images
    // in a row (the study's false-prune causes read three per missed pair), where a fresh
    // buffer per image costs its page faults every time.
    virtual void readDepthInto(DepthImage& out) { out = readDepth(); }
};

// Immediate mode over any backend, for tests and exploration. Outside a query each call executes
// at once (a one-command list). Between beginQuery() and endQuery() the commands are buffered and
// run as one list at endQuery(), which returns the query's result (so a backend never sees a
// query split across lists). Misuse throws InputError("command list", ...) as CommandList does.
class ImmediateContext {
public:
    explicit ImmediateContext(DepthBackend& backend) : backend_(backend) {}
    void clear(double depth = 1.0);
    void depthFunc(DepthFunc f);
    void depthMask(bool write);
    void beginQuery(QueryKind kind = QueryKind::SamplesPassed);
    void draw(uint32_t first, uint32_t count);
    uint64_t endQuery();

private:
    void run();
    DepthBackend& backend_;
    CommandList list_;
    bool inQuery_ = false;
};

}  // namespace cullide
