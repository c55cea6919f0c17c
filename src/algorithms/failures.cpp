// The known, explained mismatches of the list-priority algorithms that order faces by one key:
// the scenes on which the order is wrong with the scene's own camera. The conformance suite
// checks both ways: wrong pixels on each scene listed, none wherever depth ranges are separate
// (depthRangesSeparate). The reasons are in docs/algorithms/painter.md.
#include "algorithms/algorithms.hpp"

namespace hsr::algo {

std::vector<std::string> listPriorityFailureScenes(const std::string& key) {
  // The nearest vertex orders the midpoint scene's tilted polygon right: its near end is nearest.
  if (key == "min") return {"builtin:painter-cycle", "builtin:interpenetrate"};
  return {"builtin:painter-midpoint", "builtin:painter-cycle", "builtin:interpenetrate"};
}

}  // namespace hsr::algo
