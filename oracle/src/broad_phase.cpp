// Broad phase on Embree 3 (rtcCollide), following the pattern of Embree's "collide" tutorial:
// one user geometry per object, a bounds callback per primitive, both BVHs descended together.
// Embree's own narrow phase there (a float test that skips pairs sharing a vertex) is not used.
#include "broad_phase.h"

#include "cullide/parallel.h"
#include "cullide/uninstrumented.h"

#include <embree3/rtcore.h>

#include <chrono>
#include <cstddef>
#include <memory>
#include <stdexcept>
#include <string>

namespace cullide::oracle::detail {
namespace {

static_assert(sizeof(Candidate) == sizeof(RTCCollision));
static_assert(offsetof(Candidate, object0) == offsetof(RTCCollision, geomID0));
static_assert(offsetof(Candidate, prim0) == offsetof(RTCCollision, primID0));
static_assert(offsetof(Candidate, object1) == offsetof(RTCCollision, geomID1));
static_assert(offsetof(Candidate, prim1) == offsetof(RTCCollision, primID1));

// Embree runs its build and its collision jobs on TBB workers inside libembree, where
// ThreadSanitizer cannot see the joins: the tokens tell it what rtcCommitScene/rtcCollide
// guarantee (the caller's writes before, the callbacks' writes after; parallel.h).
char buildToken, collideBefore, collideAfter;

void boundsFn(const RTCBoundsFunctionArguments* args) {
    tsanAcquire(&buildToken);
    const Box& b = (*static_cast<const std::span<const Box>*>(args->geometryUserPtr))[args->primID];
    RTCBounds* o = args->bounds_o;
    o->lower_x = b.lo[0], o->lower_y = b.lo[1], o->lower_z = b.lo[2];
    o->upper_x = b.hi[0], o->upper_y = b.hi[1], o->upper_z = b.hi[2];
}

struct Forward {
    CandidateFn fn;
    void* user;
};

void collideFn(void* user, RTCCollision* pairs, unsigned int n) {
    tsanAcquire(&collideBefore);
    const Forward& f = *static_cast<const Forward*>(user);
    f.fn(f.user, reinterpret_cast<const Candidate*>(pairs), n);
    tsanRelease(&collideAfter);
}

struct SceneDeleter {
    void operator()(RTCScene s) const { rtcReleaseScene(s); }
};

void check(RTCDevice device, const char* what) {
    const RTCError e = rtcGetDeviceError(device);
    if (e != RTC_ERROR_NONE)
        throw std::runtime_error(std::string("embree: ") + what + " failed (error " + std::to_string(int(e)) + ")");
}

double seconds(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

BroadPhaseTimes collideAll(std::span<const std::span<const Box>> objects, CandidateFn fn, void* user) {
    BroadPhaseTimes times;
    auto t0 = std::chrono::steady_clock::now();
    // One device for the process (creating one costs milliseconds; a device is thread-safe and
    // its error state is per thread). Never released: it lives until exit.
    static const RTCDevice sharedDevice = rtcNewDevice(nullptr);
    if (!sharedDevice) throw std::runtime_error("embree: cannot create a device");
    const RTCDevice device = sharedDevice;
    std::unique_ptr<RTCSceneTy, SceneDeleter> scene(rtcNewScene(device));
    check(device, "rtcNewScene");
    // Medium (binned SAH): the same candidates as HIGH, built faster; LOW (Morton) builds faster
    // still but doubles the candidates on bunny75k.
    rtcSetSceneBuildQuality(scene.get(), RTC_BUILD_QUALITY_MEDIUM);
    size_t prims = 0;
    for (size_t i = 0; i < objects.size(); ++i) {
        RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_USER);
        rtcSetGeometryUserPrimitiveCount(g, unsigned(objects[i].size()));
        rtcSetGeometryUserData(g, const_cast<std::span<const Box>*>(&objects[i]));
        rtcSetGeometryBoundsFunction(g, boundsFn, nullptr);
        rtcCommitGeometry(g);
        rtcAttachGeometryByID(scene.get(), g, unsigned(i));
        rtcReleaseGeometry(g);
        prims += objects[i].size();
    }
    check(device, "geometry setup");
    tsanRelease(&buildToken);
    callUninstrumented([&] { rtcCommitScene(scene.get()); });
    check(device, "rtcCommitScene");
    times.buildSeconds = seconds(t0);
    if (prims == 0) return times;

    t0 = std::chrono::steady_clock::now();
    Forward f{fn, user};
    tsanRelease(&collideBefore);
    callUninstrumented([&] { rtcCollide(scene.get(), scene.get(), collideFn, &f); });
    tsanAcquire(&collideAfter);
    check(device, "rtcCollide");
    times.collideSeconds = seconds(t0);
    return times;
}

}  // namespace cullide::oracle::detail
