// The peers: the collision detectors a user would pick instead of cullide (FCL, Embree, Bullet,
// CGAL), each behind one interface, used as its own documentation recommends for deforming
// meshes, so that the study and the benchmarks judge them by the same oracle and time them the
// same way (docs/peers.md).
//
// Conventions
//   - A Peer is made once per frame sequence and given its frames in order. The first frame (or
//     one whose objects or triangles differ from the last one's) builds the peer's structures
//     (its BVHs); later frames update them the way the library recommends for moving and
//     deforming meshes (refit, or a new transform for an object whose model positions did not
//     change) and query. PeerFrame's times include that build or update.
//   - Geometry: each object's mesh in model space and its transform (Scene's), the same float
//     coordinates as the rest of cullide; how a peer places them (world positions, or a BVH in
//     model space and a transform) is its own business.
//   - Pairs: every pair of triangles the library reports as intersecting, as TrianglePair (a < b),
//     sorted, each once. Pairs within one object only when PeerInfo::selfPairs (FCL and Bullet
//     test objects against each other only: their self pairs are untested, as the original
//     method's are).
//   - Threads: a peer uses threads where its library has them (TBB, under the caller's
//     task_arena); the pairs do not depend on the thread count.
//   - Deterministic: the same frames give the same pairs.
//   - Errors: InputError("peer", ...) for an unknown name; InputError("scene", ...) for geometry a
//     library cannot take (CGAL needs each object to be a valid polygon mesh), naming the object.
#pragma once

#include "cullide/scene.h"

#include <memory>
#include <string>
#include <vector>

namespace cullide::peers {

struct PeerInfo {
    std::string name;  // "fcl" | "embree" | "bullet" | "cgal": the study's method name
    std::string library;  // "FCL 0.7.0": the library and the version this build was compiled against
    bool selfPairs = false;  // whether it reports pairs within one object
    std::string usage;  // one line: how it is used (build quality, refit, its triangle test, margin)
};

struct PeerFrame {
    std::vector<TrianglePair> pairs;  // sorted, each once
    bool built = false;  // this frame built the structures (else it updated them)
    double updateSeconds = 0;  // build or refit (or new transforms)
    double querySeconds = 0;  // the collision query and the triangle tests
    double seconds() const { return updateSeconds + querySeconds; }
};

struct PeerOptions {
    // Bullet's collision margin, in world units: GImpact's triangle test counts pairs closer than
    // it as colliding (the sum of two shapes' margins, so each shape gets half); the study sets it
    // to its tolerance.
    double margin = 0;
};

class Peer {
public:
    virtual ~Peer() = default;
    virtual const PeerInfo& info() const = 0;
    // The pairs of the next frame of the sequence (see the conventions).
    virtual PeerFrame collide(const Scene& scene) = 0;
};

// The peers this build has, in the order the study and the charts list them.
const std::vector<std::string>& peerNames();
bool isPeer(const std::string& name);
// A new peer for a frame sequence; InputError("peer", ...) for a name not in peerNames().
std::unique_ptr<Peer> makePeer(const std::string& name, const PeerOptions& options = {});

}  // namespace cullide::peers
