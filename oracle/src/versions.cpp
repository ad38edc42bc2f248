#include "cullide/oracle/versions.h"

#include <CGAL/version_macros.h>
#include <embree3/rtcore_config.h>

namespace cullide::oracle {

std::string libraryVersions() {
    return "Embree " RTC_VERSION_STRING ", CGAL " CGAL_VERSION_STR;
}

}  // namespace cullide::oracle
