#include "cullide/oracle/versions.h"

#include "cullide/oracle/cgal_reference.h"

#include <embree3/rtcore_config.h>

namespace cullide::oracle {

std::string libraryVersions() {
    // CGAL's version from the one file here that includes CGAL (cgal_reference.cpp).
    return std::string("Embree " RTC_VERSION_STRING ", CGAL ") + cgalVersion();
}

}  // namespace cullide::oracle
