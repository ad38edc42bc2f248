// The 0.1.0 reference build's connectivity hierarchy build, frozen (bench/baseline.json names the
// build; its core/src/hierarchy.cpp, before the build moved to flat arrays): the specification
// today's build must reproduce node for node and triangle for triangle (tests/hierarchy_test.cpp;
// every prune's PCS depends on the hierarchy), and the peer of BM_Hierarchy, which runs it in the
// same process as today's build so that their ratio holds on whatever machine it runs. Not part of
// any library.
#pragma once

#include "cullide/hierarchy.h"
#include "cullide/mesh.h"

namespace cullide::v010 {

// The 0.1.0 reference build's buildHierarchy for HierarchyKind::Connectivity (options.kind is not read): recursive
// graph-growing bisection over triangle ids, one thread, a vector per set, per piece and per part.
Hierarchy buildConnectivityHierarchy(const Mesh& mesh, const HierarchyOptions& options);

// Whether two hierarchies have the same order and the same nodes, field for field.
bool sameHierarchy(const Hierarchy& a, const Hierarchy& b);

}  // namespace cullide::v010
