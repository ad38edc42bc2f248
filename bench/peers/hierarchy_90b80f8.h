// Commit 90b80f8's connectivity hierarchy build, frozen: the baseline of issue 16's hierarchy row,
// run in the same process as today's build so that BM_Hierarchy prints their ratio on whatever
// machine it runs (the recorded figure it replaced came from one machine, and the project's
// machines have changed under it). Not part of any library; only the benchmark builds it.
#pragma once

#include "cullide/hierarchy.h"
#include "cullide/mesh.h"

namespace cullide::peer90b80f8 {

// 90b80f8's buildHierarchy for HierarchyKind::Connectivity (options.kind is not read): the same
// nodes and order as today's (BM_Hierarchy checks), one thread, vectors per set and per piece,
// searches over triangle ids.
Hierarchy buildConnectivityHierarchy(const Mesh& mesh, const HierarchyOptions& options);

}  // namespace cullide::peer90b80f8
