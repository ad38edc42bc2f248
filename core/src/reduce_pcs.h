// The command lists of the reducePCS calls the Culler makes besides the public modified one
// (appendModifiedReducePcs, cullide.h): the original method's (Figure 2) and the reliable
// method's (docs/reliable.md). Private to core/.
#pragma once

#include "reliable.h"

#include "cullide/cullide.h"

#include <cstdint>
#include <span>
#include <utility>
#include <vector>

namespace cullide::detail {

// The commands of one original reducePCS call (the seed paper's Figure 2), both passes, appended
// to `list`: per object (a run of consecutive ranges with the same `objects` entry), forward in
// object order and reverse from the last object, every range of the object is queried with
// GEQUAL against the objects drawn so far, then all of them are drawn with LESS. Siblings (ranges
// of one object) never test each other. forwardQuery[i] and reverseQuery[i] receive the query
// numbers of ranges[i] (`objects` and both spans as long as `ranges`).
void appendOriginalReducePcs(CommandList& list, std::span<const TriangleRange> ranges, std::span<const uint32_t> objects,
                             std::span<uint32_t> forwardQuery, std::span<uint32_t> reverseQuery);

// The commands of one reliable reducePCS view on `units` (the PCS leaves), appended to `list`:
// per class b of the distance-2 colouring `colour` of the units' vertex-sharing graph `g`, with an
// emptied interval buffer: forward, for each unit y of b in order, test every unit whose (unique)
// neighbour in b is y, test y, then write y; then test the units with no neighbour in b. Reverse:
// the same in reverse order without the last step. Every unit is thus tested against every other
// unit not adjacent to it, exactly once per side, and never against a unit it shares a vertex
// with. Tests are ANY_SAMPLES_PASSED queries of conservative draws; returns (unit, query) for
// each, in list order.
std::vector<std::pair<uint32_t, uint32_t>> appendReliableReducePcs(CommandList& list,
                                                                   std::span<const TriangleRange> units,
                                                                   const UnitGraph& g,
                                                                   std::span<const uint32_t> colour);

}  // namespace cullide::detail
