// Embree 3's rtcCollide as its `collide` tutorial uses it: one user geometry per object (a bounds
// callback per triangle, reading the object's world positions), a scene built at
// RTC_BUILD_QUALITY_LOW with RTC_SCENE_FLAG_DYNAMIC, and on later frames the changed geometries
// committed again and the scene with them; rtcCollide(scene, scene) gives the box pairs within
// and between objects, and the callback keeps those the tutorial's float triangle test accepts
// (it skips two triangles of one object that share a vertex, and counts corners within a
// tolerance of the other's plane as on it: the tutorial's 1e-5, made relative to the pair's size,
// see trianglesIntersect). Embree builds and collides on TBB, in the caller's task_arena.
#include "cullide/parallel.h"
#include "cullide/uninstrumented.h"
#include "frames.h"
#include "peer_makers.h"

#include <embree3/rtcore.h>
#include <oneapi/tbb/enumerable_thread_specific.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>

namespace cullide::peers::detail {
namespace {

// ---- The tutorial's float triangle-triangle test ----------------------------------------------

using Vec2f = Eigen::Vector2f;

// Which side of the line a0-a1 p lies on (on it counts as one side).
bool sideOf(const Vec2f& p, const Vec2f& a0, const Vec2f& a1) {
    const Vec2f u = p - a0, v = a0 - a1;
    return u.x() * v.y() - u.y() * v.x() >= 0.0f;
}

bool insideTriangle(const Vec2f& p, const Vec2f& a, const Vec2f& b, const Vec2f& c) {
    const bool ab = sideOf(p, a, b);
    return ab == sideOf(p, b, c) && ab == sideOf(p, c, a);
}

bool segmentsCross(const Vec2f& a0, const Vec2f& a1, const Vec2f& b0, const Vec2f& b1) {
    return sideOf(b0, a0, a1) != sideOf(b1, a0, a1) && sideOf(a0, b0, b1) != sideOf(a1, b0, b1);
}

// Two triangles in one plane, projected: an edge of one crosses an edge of the other, or one
// lies inside the other.
bool overlap2d(const Vec2f (&a)[3], const Vec2f (&b)[3]) {
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            if (segmentsCross(a[i], a[(i + 1) % 3], b[j], b[(j + 1) % 3])) return true;
    const auto allInside = [](const Vec2f(&p)[3], const Vec2f(&t)[3]) {
        return insideTriangle(p[0], t[0], t[1], t[2]) && insideTriangle(p[1], t[0], t[1], t[2]) &&
            insideTriangle(p[2], t[0], t[1], t[2]);
    };
    return allInside(a, b) || allInside(b, a);
}

// The interval that triangle (p, d) covers on the line where the planes meet: p are the corners'
// projections on the line's direction, d their signed distances to the other plane.
struct Interval {
    float lo = std::numeric_limits<float>::infinity(), hi = -std::numeric_limits<float>::infinity();
};
Interval onLine(const float (&p)[3], const float (&d)[3]) {
    Interval out;
    for (int i = 0; i < 3; ++i) {
        const int j = (i + 1) % 3;
        if (std::min(d[i], d[j]) <= 0.0f && std::max(d[i], d[j]) >= 0.0f && std::abs(d[i] - d[j]) > 0.0f) {
            const float t = p[i] + (p[j] - p[i]) * d[i] / (d[i] - d[j]);
            out.lo = std::min(out.lo, t);
            out.hi = std::max(out.hi, t);
        }
    }
    return out;
}

// The longest edge of the two triangles.
float pairSize(const Vec3f (&a)[3], const Vec3f (&b)[3]) {
    float size = 0;
    for (int i = 0; i < 3; ++i)
        size = std::max({size, (a[(i + 1) % 3] - a[i]).norm(), (b[(i + 1) % 3] - b[i]).norm()});
    return size;
}

bool trianglesIntersect(const Vec3f (&a)[3], const Vec3f (&b)[3]) {
    // The tutorial's tolerance is 1e-5 in the units of its unnormalised plane equations, made for
    // its cloth of triangles about a unit across. Taken as written it is absolute, so on a mesh a
    // few hundredths across (the bundled bunny) nearly every pair of nearby triangles falls within
    // it and counts as coplanar: ten times the true pairs. Here the planes are normalised and the
    // tolerance is 1e-5 of the pair's longest edge, the tutorial's test at any scale.
    Vec3f na = (a[1] - a[0]).cross(a[2] - a[0]), nb = (b[1] - b[0]).cross(b[2] - b[0]);
    const float la = na.norm(), lb = nb.norm();
    if (!(la > 0.0f) || !(lb > 0.0f)) return false;  // a degenerate triangle has no plane
    na /= la, nb /= lb;
    const float eps = 1e-5f * pairSize(a, b);
    const float ca = na.dot(a[0]), cb = nb.dot(b[0]);
    const float da[3] = {nb.dot(a[0]) - cb, nb.dot(a[1]) - cb, nb.dot(a[2]) - cb};
    if (std::max({da[0], da[1], da[2]}) < -eps || std::min({da[0], da[1], da[2]}) > eps) return false;
    const float db[3] = {na.dot(b[0]) - ca, na.dot(b[1]) - ca, na.dot(b[2]) - ca};
    if (std::max({db[0], db[1], db[2]}) < -eps || std::min({db[0], db[1], db[2]}) > eps) return false;
    const auto flat = [&](const float(&d)[3]) {
        return std::abs(d[0]) < eps && std::abs(d[1]) < eps && std::abs(d[2]) < eps;
    };
    if (flat(da) || flat(db)) {  // coplanar: project along a's largest normal component
        int z = 0;
        na.cwiseAbs().maxCoeff(&z);
        const int x = (z + 1) % 3, y = (x + 1) % 3;
        const Vec2f pa[3] = {{a[0][x], a[0][y]}, {a[1][x], a[1][y]}, {a[2][x], a[2][y]}};
        const Vec2f pb[3] = {{b[0][x], b[0][y]}, {b[1][x], b[1][y]}, {b[2][x], b[2][y]}};
        return overlap2d(pa, pb);
    }
    const Vec3f line = na.cross(nb);
    const float pa[3] = {line.dot(a[0]), line.dot(a[1]), line.dot(a[2])};
    const float pb[3] = {line.dot(b[0]), line.dot(b[1]), line.dot(b[2])};
    const Interval ia = onLine(pa, da), ib = onLine(pb, db);
    return ia.lo <= ib.hi && ib.lo <= ia.hi;
}

// ---- The peer ------------------------------------------------------------------------------------

// Embree runs its build and its collision jobs on TBB workers inside libembree, where
// ThreadSanitizer cannot see the joins: the tokens say what rtcCommitScene and rtcCollide
// guarantee (parallel.h).
char buildToken, collideBefore, collideAfter;

struct EmbreeObject {
    std::vector<Vec3f> positions;  // world
    std::vector<Triangle> triangles;
    RTCGeometry geometry = nullptr;
};

void boundsOf(const RTCBoundsFunctionArguments* args) {
    tsanAcquire(&buildToken);
    const auto& o = *static_cast<const EmbreeObject*>(args->geometryUserPtr);
    const Triangle& t = o.triangles[args->primID];
    const Vec3f lo = o.positions[t[0]].cwiseMin(o.positions[t[1]]).cwiseMin(o.positions[t[2]]);
    const Vec3f hi = o.positions[t[0]].cwiseMax(o.positions[t[1]]).cwiseMax(o.positions[t[2]]);
    RTCBounds* b = args->bounds_o;
    b->lower_x = lo.x(), b->lower_y = lo.y(), b->lower_z = lo.z();
    b->upper_x = hi.x(), b->upper_y = hi.y(), b->upper_z = hi.z();
}

struct CollideContext {
    const std::vector<EmbreeObject>* objects;
    tbb::enumerable_thread_specific<std::vector<TrianglePair>> pairs;
};

// Embree gives both orders of a pair within one scene; each is tested, as the tutorial does.
bool collides(const std::vector<EmbreeObject>& objects, const RTCCollision& c) {
    const EmbreeObject& o0 = objects[c.geomID0];
    const EmbreeObject& o1 = objects[c.geomID1];
    const Triangle& t0 = o0.triangles[c.primID0];
    const Triangle& t1 = o1.triangles[c.primID1];
    if (c.geomID0 == c.geomID1)
        for (uint32_t v : t1)
            if (v == t0[0] || v == t0[1] || v == t0[2]) return false;  // topological neighbours
    const Vec3f a[3] = {o0.positions[t0[0]], o0.positions[t0[1]], o0.positions[t0[2]]};
    const Vec3f b[3] = {o1.positions[t1[0]], o1.positions[t1[1]], o1.positions[t1[2]]};
    return trianglesIntersect(a, b);
}

void collideCallback(void* user, RTCCollision* collisions, unsigned int count) {
    tsanAcquire(&collideBefore);
    auto& context = *static_cast<CollideContext*>(user);
    std::vector<TrianglePair>& out = context.pairs.local();
    for (unsigned int k = 0; k < count; ++k)
        if (collides(*context.objects, collisions[k]))
            out.push_back(TrianglePair::make({collisions[k].geomID0, collisions[k].primID0},
                                             {collisions[k].geomID1, collisions[k].primID1}));
    tsanRelease(&collideAfter);
}

void check(RTCDevice device, const char* what) {
    const RTCError e = rtcGetDeviceError(device);
    if (e != RTC_ERROR_NONE)
        throw std::runtime_error(std::string("embree: ") + what + " failed (error " + std::to_string(int(e)) + ")");
}

RTCDevice sharedDevice() {
    // One device for the process (making one costs milliseconds; a device is thread-safe and its
    // error state is per thread). Never released: it lives until exit.
    static const RTCDevice device = rtcNewDevice(nullptr);
    if (!device) throw std::runtime_error("embree: cannot create a device");
    return device;
}

void worldPositions(const Object& source, std::vector<Vec3f>& out) {
    out.resize(source.mesh.positions.size());
    for (size_t v = 0; v < out.size(); ++v) out[v] = applyTransform(source.transform, source.mesh.positions[v]);
}

class EmbreePeer final : public Peer {
public:
    EmbreePeer() : device_(sharedDevice()) {
        info_.name = "embree";
        info_.library = "Embree " RTC_VERSION_STRING;
        info_.selfPairs = true;
        info_.usage =
            "rtcCollide on one user geometry per object (RTC_BUILD_QUALITY_LOW, RTC_SCENE_FLAG_DYNAMIC, "
            "changed geometries committed again); the collide tutorial's float triangle test, which skips "
            "triangles of one object that share a vertex; TBB threads";
    }
    ~EmbreePeer() override { release(); }
    const PeerInfo& info() const override { return info_; }

    PeerFrame collide(const Scene& scene) override {
        return timedFrame(
            tracker_, scene, [&](const FrameChanges& c) { update(scene, c); }, [&] { return query(); });
    }

private:
    // rtcCollide(scene, scene) with the triangle test in its callback, the threads' pairs merged.
    std::vector<TrianglePair> query() {
        CollideContext context{&objects_, {}};
        tsanRelease(&collideBefore);
        callUninstrumented([&] { rtcCollide(scene_, scene_, collideCallback, &context); });
        tsanAcquire(&collideAfter);
        check(device_, "rtcCollide");
        std::vector<TrianglePair> pairs;
        for (std::vector<TrianglePair>& local : context.pairs) pairs.insert(pairs.end(), local.begin(), local.end());
        sortPairs(pairs);
        return pairs;
    }

    void update(const Scene& scene, const FrameChanges& changes) {
        if (changes.build) build(scene);
        for (size_t i = 0; i < scene.objects.size(); ++i) {
            if (!changes.build && !changes.positions[i] && !changes.transform[i]) continue;
            worldPositions(scene.objects[i], objects_[i].positions);
            rtcCommitGeometry(objects_[i].geometry);
        }
        check(device_, "geometry update");
        tsanRelease(&buildToken);
        callUninstrumented([&] { rtcCommitScene(scene_); });
        check(device_, "rtcCommitScene");
    }

    void build(const Scene& scene) {
        release();
        scene_ = rtcNewScene(device_);
        check(device_, "rtcNewScene");
        rtcSetSceneFlags(scene_, RTC_SCENE_FLAG_DYNAMIC);
        rtcSetSceneBuildQuality(scene_, RTC_BUILD_QUALITY_LOW);
        objects_.resize(scene.objects.size());
        for (size_t i = 0; i < scene.objects.size(); ++i) {
            EmbreeObject& o = objects_[i];
            o.triangles = scene.objects[i].mesh.triangles;
            o.geometry = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_USER);
            rtcSetGeometryUserPrimitiveCount(o.geometry, unsigned(o.triangles.size()));
            rtcSetGeometryUserData(o.geometry, &o);
            rtcSetGeometryBoundsFunction(o.geometry, boundsOf, nullptr);
            rtcAttachGeometryByID(scene_, o.geometry, unsigned(i));
        }
        check(device_, "geometry setup");
    }

    void release() {
        for (EmbreeObject& o : objects_)
            if (o.geometry) rtcReleaseGeometry(o.geometry);
        objects_.clear();
        if (scene_) rtcReleaseScene(scene_);
        scene_ = nullptr;
    }

    PeerInfo info_;
    FrameTracker tracker_;
    RTCDevice device_;
    RTCScene scene_ = nullptr;
    std::vector<EmbreeObject> objects_;  // never resized while Embree holds pointers to its entries
};

}  // namespace

std::unique_ptr<Peer> makeEmbreePeer(const PeerOptions&) {
    return std::make_unique<EmbreePeer>();
}

}  // namespace cullide::peers::detail
