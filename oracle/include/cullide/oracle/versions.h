// Versions of the libraries behind the exact oracle, for `cullide --version` and reports.
#pragma once

#include <string>

namespace cullide::oracle {

// "Embree 3.13.5, CGAL 5.5.1" - the versions this build was compiled against.
std::string libraryVersions();

}  // namespace cullide::oracle
