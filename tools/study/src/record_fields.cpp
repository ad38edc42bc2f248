// The fields every run's record shares (record_fields.h).
#include "record_fields.h"

#include <string>

namespace cullide::study {

nlohmann::ordered_json recordHead(const RunConfig& c, const Scene& scene) {
    nlohmann::ordered_json j;
    j["index"] = c.index;
    j["id"] = c.id();
    j["scene"] = c.scene;
    j["frame"] = c.frame;
    j["triangles"] = scene.triangleCount();
    j["objects"] = scene.objects.size();
    j["method"] = c.method;
    return j;
}

void addOracleColumnsEmpty(nlohmann::ordered_json& j) {
    for (const char* k : {"oracle_pairs",      "oracle_crossing", "oracle_touching",   "colliding",   "false_prunes",
                          "fp_crossing",       "fp_touching",     "fp_depth_rounding", "fp_sampling", "fp_edge_on",
                          "fp_untested",       "fp_unexplained",  "missed_pairs",      "mp_crossing", "mp_touching",
                          "mp_depth_rounding", "mp_sampling",     "mp_edge_on",        "mp_untested", "mp_unexplained",
                          "false_positives",   "efficiency",      "attribution_ms"})
        j[k] = nullptr;
}

void addPairMeasure(nlohmann::ordered_json& j, const PairMeasure& m) {
    using Json = nlohmann::ordered_json;
    j["family"] = toString(m.family);
    j["time_to_pairs_ms"] = m.timeToPairsSeconds >= 0 ? Json(1e3 * m.timeToPairsSeconds) : nullptr;
    for (const char* k : {"pairs_found", "pairs_missed", "pairs_spurious", "tolerance"}) j[k] = nullptr;
    for (oracle::AuditCause c : oracle::missedCauses()) j[std::string("missed_") + toString(c)] = nullptr;
    for (oracle::AuditCause c : oracle::spuriousCauses()) j[std::string("spurious_") + toString(c)] = nullptr;
    if (!m.truth) return;
    if (!m.audit) {  // image-space: the exact stage's pairs are the truth's less the missed ones
        j["pairs_found"] = m.truth->pairs.size() - m.missed;
        j["pairs_missed"] = m.missed;
        j["pairs_spurious"] = 0;
        return;
    }
    const oracle::Audit& a = *m.audit;
    j["pairs_found"] = a.found;
    j["pairs_missed"] = a.missed.size();
    j["pairs_spurious"] = a.spurious.size();
    j["tolerance"] = m.tolerance;
    for (oracle::AuditCause c : oracle::missedCauses()) j[std::string("missed_") + toString(c)] = a.missedBy[size_t(c)];
    for (oracle::AuditCause c : oracle::spuriousCauses())
        j[std::string("spurious_") + toString(c)] = a.spuriousBy[size_t(c)];
}

}  // namespace cullide::study
