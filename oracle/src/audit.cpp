// The audit (audit.h): a reported pair list merged against the oracle's truth, each disagreement
// given the first cause that holds (docs/oracle.md#audit).
#include "cullide/oracle/audit.h"

#include "audit_geometry.h"

#include "cullide/error.h"
#include "cullide/oracle/near_contacts.h"
#include "cullide/parse_number.h"
#include "cullide/predicates.h"

#include <algorithm>
#include <optional>
#include <string>
#include <vector>

namespace cullide::oracle {
namespace {

// The two triangles of a pair as the audit needs them: their corners in world space (double, from
// Scene::worldMesh's floats) and their vertex indices. World meshes are made on first use, so that
// an audit that agrees, or disagrees on a few objects, transforms no others.
class PairGeometry {
public:
    explicit PairGeometry(const Scene& scene) : scene_(scene), world_(scene.objects.size()) {}

    TrianglePoints corners(TriangleRef r) {
        const Mesh& m = world(r.object);
        const Triangle& t = m.triangles[r.triangle];
        return {m.positions[t[0]].cast<double>(), m.positions[t[1]].cast<double>(), m.positions[t[2]].cast<double>()};
    }
    const Triangle& indices(TriangleRef r) const { return scene_.objects[r.object].mesh.triangles[r.triangle]; }

private:
    const Mesh& world(uint32_t object) {
        if (!world_[object]) world_[object] = scene_.worldMesh(object);
        return *world_[object];
    }

    const Scene& scene_;
    std::vector<std::optional<Mesh>> world_;
};

// InputError unless each pair names two different triangles of `scene`.
void validate(const Scene& scene, std::span<const TrianglePair> reported, const std::string& source) {
    const auto check = [&](size_t k, TriangleRef r) {
        if (r.object >= scene.objects.size())
            throw InputError(source, "pair " + std::to_string(k) + ": the scene has no object " +
                                         std::to_string(r.object) + " (it has " +
                                         std::to_string(scene.objects.size()) + ")");
        if (r.triangle >= scene.objects[r.object].mesh.triangles.size())
            throw InputError(source, "pair " + std::to_string(k) + ": object " + std::to_string(r.object) +
                                         " has no triangle " + std::to_string(r.triangle));
    };
    for (size_t k = 0; k < reported.size(); ++k) {
        check(k, reported[k].a);
        check(k, reported[k].b);
        if (reported[k].a == reported[k].b)
            throw InputError(source, "pair " + std::to_string(k) + " pairs a triangle with itself");
    }
}

// Why a pair of the truth is missing from the list; sets its distance (the penetration depth of a
// crossing pair).
AuditedPair explainMissed(const IntersectingPair& p, PairGeometry& geometry, const AuditOptions& options) {
    AuditedPair out{TrianglePair{p.a(), p.b()}, p.cls, AuditCause::Unexplained, 0};
    const TrianglePoints a = geometry.corners(p.a()), b = geometry.corners(p.b());
    if (p.cls == PairClass::Crossing) out.distance = detail::penetrationDepth(a, b);
    const int shared = p.selfPair() ? detail::sharedIndices(geometry.indices(p.a()), geometry.indices(p.b())) : 0;
    if (p.selfPair() && !options.selfPairsTested) out.cause = AuditCause::Untested;
    else if (shared >= 2) out.cause = AuditCause::SharedEdge;
    else if (shared == 1) out.cause = AuditCause::SharedVertex;
    else if (p.cls == PairClass::Touching) out.cause = detail::coplanar(a, b) ? AuditCause::Coplanar : AuditCause::Touching;
    else if (out.distance <= options.tolerance) out.cause = AuditCause::WithinTolerance;
    return out;
}

bool isDegenerate(const Truth& truth, TriangleRef r) {
    return std::binary_search(truth.degenerate.begin(), truth.degenerate.end(), r);
}

// Why a reported pair is not in the truth; sets its distance (0 for a degenerate triangle, whose
// corners have no distance to speak of).
AuditedPair explainSpurious(const TrianglePair& p, const Truth& truth, PairGeometry& geometry,
                            const AuditOptions& options) {
    AuditedPair out{p, PairClass::Crossing, AuditCause::Unexplained, 0};
    if (isDegenerate(truth, p.a) || isDegenerate(truth, p.b)) {
        out.cause = AuditCause::Degenerate;
        return out;
    }
    const TrianglePoints a = geometry.corners(p.a), b = geometry.corners(p.b);
    out.distance = triangleDistance(a[0], a[1], a[2], b[0], b[1], b[2]);
    const int shared = p.selfPair() ? detail::sharedIndices(geometry.indices(p.a), geometry.indices(p.b)) : 0;
    const bool near = out.distance <= options.tolerance;
    if (shared >= 2) out.cause = AuditCause::SharedEdge;
    else if (shared == 1) out.cause = AuditCause::SharedVertex;
    else if (near && detail::coplanar(a, b)) out.cause = AuditCause::Coplanar;
    else if (near) out.cause = AuditCause::WithinTolerance;
    else if (shared == 0 && detail::behindFace(a, b) && detail::behindFace(b, a)) out.cause = AuditCause::BehindFace;
    return out;
}

}  // namespace

const char* toString(AuditCause c) {
    switch (c) {
        case AuditCause::Untested: return "untested";
        case AuditCause::Degenerate: return "degenerate";
        case AuditCause::SharedEdge: return "shared_edge";
        case AuditCause::SharedVertex: return "shared_vertex";
        case AuditCause::Coplanar: return "coplanar";
        case AuditCause::Touching: return "touching";
        case AuditCause::WithinTolerance: return "within_tolerance";
        case AuditCause::BehindFace: return "behind_face";
        case AuditCause::Unexplained: return "unexplained";
    }
    return "unexplained";
}

const std::vector<AuditCause>& missedCauses() {
    static const std::vector<AuditCause> causes = {AuditCause::Untested,        AuditCause::SharedEdge,
                                                   AuditCause::SharedVertex,    AuditCause::Coplanar,
                                                   AuditCause::Touching,        AuditCause::WithinTolerance,
                                                   AuditCause::Unexplained};
    return causes;
}

const std::vector<AuditCause>& spuriousCauses() {
    static const std::vector<AuditCause> causes = {AuditCause::Degenerate,   AuditCause::SharedEdge,
                                                   AuditCause::SharedVertex, AuditCause::Coplanar,
                                                   AuditCause::WithinTolerance, AuditCause::BehindFace,
                                                   AuditCause::Unexplained};
    return causes;
}

Audit audit(const Scene& scene, const Truth& truth, std::span<const TrianglePair> reported,
            const AuditOptions& options) {
    validate(scene, reported, options.source);
    if (!(options.tolerance >= 0))
        throw InputError(options.source, "tolerance " + realText(options.tolerance) + " is not a distance (>= 0)");
    std::vector<TrianglePair> list;
    list.reserve(reported.size());
    for (const TrianglePair& p : reported) list.push_back(TrianglePair::make(p.a, p.b));
    std::sort(list.begin(), list.end());
    list.erase(std::unique(list.begin(), list.end()), list.end());

    Audit out;
    out.reported = list.size();
    PairGeometry geometry(scene);
    // Both lists sorted by pair: one merge finds the found, missed and spurious pairs.
    auto r = list.begin();
    for (const IntersectingPair& p : truth.pairs) {
        const TrianglePair t{p.a(), p.b()};
        for (; r != list.end() && *r < t; ++r) out.spurious.push_back(explainSpurious(*r, truth, geometry, options));
        if (r != list.end() && *r == t) {
            ++out.found;
            ++r;
        } else {
            out.missed.push_back(explainMissed(p, geometry, options));
        }
    }
    for (; r != list.end(); ++r) out.spurious.push_back(explainSpurious(*r, truth, geometry, options));
    for (const AuditedPair& m : out.missed) {
        ++out.missedBy[size_t(m.cause)];
        ++out.missedByClass[size_t(m.cls)];
    }
    for (const AuditedPair& s : out.spurious) ++out.spuriousBy[size_t(s.cause)];
    return out;
}

}  // namespace cullide::oracle
