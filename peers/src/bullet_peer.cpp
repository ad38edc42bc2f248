// Bullet 3.24's GImpact as its collision algorithm uses it between two trimeshes: a
// btGImpactMeshShape per object over the object's own arrays (btTriangleIndexVertexArray),
// refitted when its positions change (postUpdate + updateBound), a new world transform when only
// its pose changes; between two objects, the pairs of the shapes' box sets
// (btGImpactBoxSet::find_collision, which btGImpactCollisionAlgorithm::gimpact_vs_gimpact calls)
// and on each pair its triangle test (btPrimitiveTriangle: overlap_test_conservative, then
// find_triangle_collision_clip_method, in float, with the shapes' collision margin), as
// collide_sat_triangles does. Taking the pairs from there, not from a collision world, keeps every
// pair: a contact manifold keeps four points. Objects against each other only (GImpact has no
// self-collision), one thread.
#include "cullide/error.h"
#include "frames.h"
#include "peer_makers.h"

#include <BulletCollision/CollisionShapes/btTriangleIndexVertexArray.h>
#include <BulletCollision/Gimpact/btGImpactShape.h>
#include <BulletCollision/Gimpact/btTriangleShapeEx.h>
#include <LinearMath/btAabbUtil2.h>
#include <LinearMath/btScalar.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <string>

namespace cullide::peers::detail {
namespace {

static_assert(sizeof(btScalar) == sizeof(float), "the shapes read cullide's float positions in place");
static_assert(sizeof(Vec3f) == 3 * sizeof(float) && sizeof(Triangle) == 3 * sizeof(int));

struct BulletObject {
    std::vector<Vec3f> positions;  // what the shape reads (model positions times the scale, or world)
    std::vector<Triangle> triangles;
    std::unique_ptr<btTriangleIndexVertexArray> arrays;
    std::unique_ptr<btGImpactMeshShape> shape;
    RigidPlacement placement;
    btTransform transform;
};

btTransform toBullet(const RigidPlacement& p) {
    const Eigen::Matrix3d& r = p.rotation;
    const btMatrix3x3 basis(btScalar(r(0, 0)), btScalar(r(0, 1)), btScalar(r(0, 2)), btScalar(r(1, 0)),
                            btScalar(r(1, 1)), btScalar(r(1, 2)), btScalar(r(2, 0)), btScalar(r(2, 1)),
                            btScalar(r(2, 2)));
    return btTransform(
        basis, btVector3(btScalar(p.translation.x()), btScalar(p.translation.y()), btScalar(p.translation.z())));
}

// The triangle pairs between two objects' mesh parts that GImpact reports as colliding.
void collideParts(const btGImpactMeshShapePart& part0, const btTransform& tr0, uint32_t object0,
                  const btGImpactMeshShapePart& part1, const btTransform& tr1, uint32_t object1,
                  std::vector<TrianglePair>& out) {
    btPairSet pairs;
    btGImpactBoxSet::find_collision(part0.getBoxSet(), tr0, part1.getBoxSet(), tr1, pairs);
    if (pairs.size() == 0) return;
    btPrimitiveTriangle tri0, tri1;
    GIM_TRIANGLE_CONTACT contact;
    part0.lockChildShapes();
    part1.lockChildShapes();
    for (int k = 0; k < pairs.size(); ++k) {
        const GIM_PAIR& pair = pairs[k];
        part0.getPrimitiveTriangle(pair.m_index1, tri0);
        part1.getPrimitiveTriangle(pair.m_index2, tri1);
        tri0.applyTransform(tr0);
        tri1.applyTransform(tr1);
        tri0.buildTriPlane();
        tri1.buildTriPlane();
        if (tri0.overlap_test_conservative(tri1) && tri0.find_triangle_collision_clip_method(tri1, contact))
            out.push_back(TrianglePair::make({object0, uint32_t(pair.m_index1)}, {object1, uint32_t(pair.m_index2)}));
    }
    part0.unlockChildShapes();
    part1.unlockChildShapes();
}

class BulletPeer final : public Peer {
public:
    explicit BulletPeer(const PeerOptions& options) : margin_(btScalar(options.margin)) {
        if (!(options.margin >= 0) || !std::isfinite(options.margin))
            throw InputError(
                "peer", "bullet: the margin must be finite and at least 0 (" + std::to_string(options.margin) + ")");
        info_.name = "bullet";
        info_.library =
            "Bullet " + std::to_string(BT_BULLET_VERSION / 100) + "." + std::to_string(BT_BULLET_VERSION % 100);
        info_.selfPairs = false;
        info_.usage =
            "btGImpactMeshShape per object, refitted (postUpdate + updateBound) when positions change, a new "
            "world transform when only the pose does; box-set pairs + btPrimitiveTriangle clip test in float "
            "with the collision margin; one thread";
    }
    const PeerInfo& info() const override { return info_; }

    PeerFrame collide(const Scene& scene) override {
        return timedFrame(
            tracker_, scene, [&](const FrameChanges& c) { c.build ? build(scene) : update(scene, c); },
            [&] { return query(); });
    }

private:
    void build(const Scene& scene) {
        objects_.clear();
        objects_.resize(scene.objects.size());
        for (size_t i = 0; i < scene.objects.size(); ++i) {
            const Object& source = scene.objects[i];
            BulletObject& o = objects_[i];
            o.placement = rigidPlacement(source.transform);
            o.transform = toBullet(o.placement);
            o.positions = bvhPositions(source, o.placement);
            o.triangles = source.mesh.triangles;
            o.arrays = std::make_unique<btTriangleIndexVertexArray>(
                int(o.triangles.size()), reinterpret_cast<int*>(o.triangles.data()), int(sizeof(Triangle)),
                int(o.positions.size()), reinterpret_cast<btScalar*>(o.positions.data()), int(sizeof(Vec3f)));
            o.shape = std::make_unique<btGImpactMeshShape>(o.arrays.get());
            // GImpact's triangle test counts pairs closer than the sum of the two shapes' margins:
            // half each, so that pairs closer than PeerOptions::margin count.
            o.shape->setMargin(margin_ / 2);
            o.shape->updateBound();  // builds the box sets
        }
    }

    void update(const Scene& scene, const FrameChanges& changes) {
        for (size_t i = 0; i < scene.objects.size(); ++i) {
            BulletObject& o = objects_[i];
            const RigidPlacement now = rigidPlacement(scene.objects[i].transform);
            if (needsRefit(o.placement, now, changes.positions[i], changes.transform[i])) {
                const std::vector<Vec3f> positions = bvhPositions(scene.objects[i], now);
                std::copy(positions.begin(), positions.end(), o.positions.begin());  // in place: the arrays point there
                o.shape->postUpdate();
                o.shape->updateBound();  // refits the box sets
            } else if (!changes.transform[i]) {
                continue;
            }
            o.placement = now;
            o.transform = toBullet(now);
        }
    }

    std::vector<TrianglePair> query() const {
        std::vector<TrianglePair> pairs;
        for (size_t i = 0; i < objects_.size(); ++i) {
            btVector3 lo0, hi0;
            objects_[i].shape->getAabb(objects_[i].transform, lo0, hi0);
            for (size_t j = i + 1; j < objects_.size(); ++j) {
                btVector3 lo1, hi1;
                objects_[j].shape->getAabb(objects_[j].transform, lo1, hi1);
                if (!TestAabbAgainstAabb2(lo0, hi0, lo1, hi1)) continue;
                const btGImpactMeshShape& s0 = *objects_[i].shape;
                const btGImpactMeshShape& s1 = *objects_[j].shape;
                for (int p0 = 0; p0 < s0.getMeshPartCount(); ++p0)
                    for (int p1 = 0; p1 < s1.getMeshPartCount(); ++p1)
                        collideParts(*s0.getMeshPart(p0), objects_[i].transform, uint32_t(i), *s1.getMeshPart(p1),
                                     objects_[j].transform, uint32_t(j), pairs);
            }
        }
        sortPairs(pairs);
        return pairs;
    }

    btScalar margin_;
    PeerInfo info_;
    FrameTracker tracker_;
    std::vector<BulletObject> objects_;
};

}  // namespace

std::unique_ptr<Peer> makeBulletPeer(const PeerOptions& options) {
    return std::make_unique<BulletPeer>(options);
}

}  // namespace cullide::peers::detail
