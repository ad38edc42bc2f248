// FCL 0.7 as its documentation uses it for meshes: a BVHModel<OBBRSS> per object (the bounding
// volume of FCL's own mesh examples and benchmarks; oriented, so collide works on it in place
// under any transform, where for AABB models it copies both and moves them into the world on
// every call), refitted bottom-up when its positions change
// (beginReplaceModel / replaceSubModel / endReplaceModel), a new transform when only its pose
// changes, and a DynamicAABBTreeCollisionManager over the objects whose callback runs
// fcl::collide with room for every contact. FCL tests objects against each other only (its
// self-collision is unimplemented), in one thread, with its double triangle test.
#include "frames.h"
#include "peer_makers.h"

#include <fcl/broadphase/broadphase_dynamic_AABB_tree.h>
#include <fcl/config.h>
#include <fcl/geometry/bvh/BVH_model.h>
#include <fcl/narrowphase/collision.h>

#include <limits>
#include <memory>
#include <stdexcept>
#include <string>

namespace cullide::peers::detail {
namespace {

using Model = fcl::BVHModel<fcl::OBBRSSd>;

struct FclObject {
    std::shared_ptr<Model> model;
    std::unique_ptr<fcl::CollisionObjectd> object;
    RigidPlacement placement;
};

std::vector<fcl::Vector3d> toFcl(const std::vector<Vec3f>& positions) {
    std::vector<fcl::Vector3d> out;
    out.reserve(positions.size());
    for (const Vec3f& p : positions) out.emplace_back(double(p.x()), double(p.y()), double(p.z()));
    return out;
}

void check(int status, const char* what) {
    if (status != fcl::BVH_OK)
        throw std::runtime_error(std::string("fcl: ") + what + " failed (" + std::to_string(status) + ")");
}

void place(FclObject& o) {
    o.object->setTransform(o.placement.rotation, o.placement.translation);
    o.object->computeAABB();
}

struct QueryContext {
    fcl::CollisionRequestd request;
    std::vector<TrianglePair> pairs;
};

bool collideObjects(fcl::CollisionObjectd* o1, fcl::CollisionObjectd* o2, void* user) {
    auto& context = *static_cast<QueryContext*>(user);
    fcl::CollisionResultd result;
    fcl::collide(o1, o2, context.request, result);
    const uint32_t a = uint32_t(reinterpret_cast<uintptr_t>(o1->getUserData()));
    const uint32_t b = uint32_t(reinterpret_cast<uintptr_t>(o2->getUserData()));
    // Between two meshes FCL never swaps the objects: b1 is a triangle of o1, b2 of o2 (Contact's
    // o1 may be a copy of o1's model, for bounding volumes that are not oriented).
    for (size_t k = 0; k < result.numContacts(); ++k) {
        const fcl::Contactd& c = result.getContact(k);
        context.pairs.push_back(TrianglePair::make({a, uint32_t(c.b1)}, {b, uint32_t(c.b2)}));
    }
    return false;  // never done: every pair of objects
}

class FclPeer final : public Peer {
public:
    FclPeer() {
        info_.name = "fcl";
        info_.library = std::string("FCL ") + FCL_VERSION;
        info_.selfPairs = false;
        info_.usage =
            "BVHModel<OBBRSS> per object, refitted bottom-up when positions change, setTransform when only "
            "the pose does; DynamicAABBTreeCollisionManager + collide (every contact); double triangle test; "
            "one thread";
    }
    const PeerInfo& info() const override { return info_; }

    PeerFrame collide(const Scene& scene) override {
        return timedFrame(
            tracker_, scene, [&](const FrameChanges& c) { c.build ? build(scene) : update(scene, c); },
            [&] { return query(); });
    }

private:
    // fcl::collide on every pair of objects whose boxes meet, room for every contact.
    std::vector<TrianglePair> query() {
        QueryContext context;
        context.request.num_max_contacts = std::numeric_limits<size_t>::max();
        context.request.enable_contact = false;  // the triangles' ids come with every contact anyway
        manager_->collide(&context, collideObjects);
        sortPairs(context.pairs);
        return std::move(context.pairs);
    }

    void build(const Scene& scene) {
        objects_.clear();
        manager_ = std::make_unique<fcl::DynamicAABBTreeCollisionManagerd>();
        std::vector<fcl::CollisionObjectd*> registered;
        for (size_t i = 0; i < scene.objects.size(); ++i) {
            const Object& source = scene.objects[i];
            FclObject o;
            o.placement = rigidPlacement(source.transform);
            o.model = std::make_shared<Model>();
            std::vector<fcl::Triangle> triangles;
            triangles.reserve(source.mesh.triangles.size());
            for (const Triangle& t : source.mesh.triangles) triangles.emplace_back(t[0], t[1], t[2]);
            check(o.model->beginModel(int(triangles.size()), int(source.mesh.positions.size())), "beginModel");
            check(o.model->addSubModel(toFcl(bvhPositions(source, o.placement)), triangles), "addSubModel");
            check(o.model->endModel(), "endModel");
            o.model->computeLocalAABB();
            o.object = std::make_unique<fcl::CollisionObjectd>(o.model);
            o.object->setUserData(reinterpret_cast<void*>(uintptr_t(i)));
            place(o);
            registered.push_back(o.object.get());
            objects_.push_back(std::move(o));
        }
        manager_->registerObjects(registered);
        manager_->setup();
    }

    void update(const Scene& scene, const FrameChanges& changes) {
        bool moved = false;
        for (size_t i = 0; i < scene.objects.size(); ++i) {
            FclObject& o = objects_[i];
            const RigidPlacement now = rigidPlacement(scene.objects[i].transform);
            if (needsRefit(o.placement, now, changes.positions[i], changes.transform[i])) {
                check(o.model->beginReplaceModel(), "beginReplaceModel");
                check(o.model->replaceSubModel(toFcl(bvhPositions(scene.objects[i], now))), "replaceSubModel");
                check(o.model->endReplaceModel(true, true), "endReplaceModel");  // refit, bottom-up
                o.model->computeLocalAABB();
            } else if (!changes.transform[i]) {
                continue;
            }
            o.placement = now;
            place(o);
            moved = true;
        }
        if (moved) manager_->update();
    }

    PeerInfo info_;
    FrameTracker tracker_;
    std::vector<FclObject> objects_;
    std::unique_ptr<fcl::DynamicAABBTreeCollisionManagerd> manager_;
};

}  // namespace

std::unique_ptr<Peer> makeFclPeer(const PeerOptions&) {
    return std::make_unique<FclPeer>();
}

}  // namespace cullide::peers::detail
