// What the peers share (private): which objects a frame changed since the one before, how an
// object is placed for a library whose transforms are rigid (FCL, Bullet), and the pair list.
#pragma once

#include "cullide/peers/peer.h"
#include "cullide/scene.h"

#include <Eigen/Core>

#include <chrono>
#include <vector>

namespace cullide::peers::detail {

// A frame against the one before it: build everything, or update the objects whose model
// positions or transforms changed. Deciding this compares the frame with a copy of the last one,
// which an application that moves its own objects knows without comparing: the peers do it
// before they start their clocks.
struct FrameChanges {
    bool build = true;  // the first frame, or the objects or their triangles differ
    std::vector<char> positions;  // per object: its model positions differ
    std::vector<char> transform;  // per object: its transform differs
};

class FrameTracker {
public:
    FrameChanges next(const Scene& scene);
    void reset() { started_ = false; }  // the next frame builds (after a frame that failed)

private:
    std::vector<std::vector<Triangle>> triangles_;
    std::vector<std::vector<Vec3f>> positions_;
    std::vector<Transform> transforms_;
    bool started_ = false;
};

// An object's transform as FCL and Bullet take it: a rotation and a translation. A linear part
// that is a rotation times a uniform scale is split into both (the scale goes into the model
// positions the BVH holds, as those libraries ask); any other (a non-uniform scale, a shear)
// cannot be, and the BVH holds the object's world positions under the identity.
struct RigidPlacement {
    bool rigid = true;  // false: world positions under the identity
    float scale = 1;  // applied to the model positions (rigid only)
    Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
    Eigen::Vector3d translation = Eigen::Vector3d::Zero();
};
RigidPlacement rigidPlacement(const Transform& transform);

// The positions the BVH of `object` holds under `placement`: the model positions times the scale,
// or the world positions (Scene::worldMesh's, bit for bit).
std::vector<Vec3f> bvhPositions(const Object& object, const RigidPlacement& placement);

// Whether an object placed as `before` and now as `now` needs its BVH refitted (its positions
// changed, or the scale or the kind of placement, or it holds world positions and moved); else a
// new transform is enough.
bool needsRefit(const RigidPlacement& before, const RigidPlacement& now, bool positionsChanged, bool transformChanged);

// Runs a peer's build or update; when it throws, the next frame builds again rather than update
// structures left half made.
template <typename F>
void guarded(FrameTracker& tracker, const F& f) {
    try {
        f();
    } catch (...) {
        tracker.reset();
        throw;
    }
}

inline double secondsSince(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// A frame as every peer runs it: what changed since the last one (before the clock starts), the
// update (a build or a refit, guarded) timed, then the query timed.
template <typename Update, typename Query>
PeerFrame timedFrame(FrameTracker& tracker, const Scene& scene, const Update& update, const Query& query) {
    const FrameChanges changes = tracker.next(scene);
    PeerFrame frame;
    frame.built = changes.build;
    auto t0 = std::chrono::steady_clock::now();
    guarded(tracker, [&] { update(changes); });
    frame.updateSeconds = secondsSince(t0);
    t0 = std::chrono::steady_clock::now();
    frame.pairs = query();
    frame.querySeconds = secondsSince(t0);
    return frame;
}

// Sorted, each pair once.
void sortPairs(std::vector<TrianglePair>& pairs);

}  // namespace cullide::peers::detail
