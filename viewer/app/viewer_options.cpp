#include "viewer/app/viewer_options.h"

namespace vxl::app {

std::string ViewerOptions::inputs_name() const {
  std::string name = inputs.empty() ? std::string() : inputs.front();
  if (inputs.size() > 1) name += " + " + std::to_string(inputs.size() - 1) + " more";
  return name;
}

}  // namespace vxl::app
