#include "viewer/platform/gl_driver_pinning.h"

#include <dlfcn.h>
#include <link.h>

#include <string>
#include <vector>

namespace vxl {

void pin_dri_drivers() noexcept {
  std::vector<std::string> names;
  dl_iterate_phdr(
      [](dl_phdr_info* info, size_t, void* data) {
        const std::string name = info->dlpi_name ? info->dlpi_name : "";
        const std::string suffix = "_dri.so";
        if (name.size() > suffix.size() && name.compare(name.size() - suffix.size(), suffix.size(), suffix) == 0)
          static_cast<std::vector<std::string>*>(data)->push_back(name);
        return 0;
      },
      &names);
  // RTLD_NODELETE on an already loaded library marks it never to be unloaded.
  for (const std::string& name : names)
    if (void* h = dlopen(name.c_str(), RTLD_LAZY | RTLD_NOLOAD | RTLD_NODELETE)) dlclose(h);
}

}  // namespace vxl
