// The options' own checks (include/hsr/options.hpp).
#include <hsr/options.hpp>

namespace hsr {

void switchOff(TiledSwitches& switches, const std::string& name) {
  if (name == "defer-back-faces") switches.deferBackFaces = false;
  else if (name == "defer-clusters") switches.deferClusters = false;
  else if (name == "mesh-culling") switches.meshCulling = false;
  else if (name == "background-pump") switches.backgroundPump = false;
  else
    throw InputError(Setting::SwitchOff, name,
                     "no such switch (defer-back-faces, defer-clusters, mesh-culling, background-pump)");
}

}  // namespace hsr
