# Debian's OpenSubdiv CMake package is broken (it references a static library that is not
# shipped), so find the CPU library and headers directly. Defines OpenSubdiv::osdCPU.
find_path(OpenSubdiv_INCLUDE_DIR opensubdiv/version.h)
find_library(OpenSubdiv_CPU_LIBRARY NAMES osdCPU)
include(FindPackageHandleStandardArgs)
find_package_handle_standard_args(OpenSubdivDebian
  REQUIRED_VARS OpenSubdiv_CPU_LIBRARY OpenSubdiv_INCLUDE_DIR)
if(OpenSubdivDebian_FOUND AND NOT TARGET OpenSubdiv::osdCPU)
  add_library(OpenSubdiv::osdCPU UNKNOWN IMPORTED)
  set_target_properties(OpenSubdiv::osdCPU PROPERTIES
    IMPORTED_LOCATION "${OpenSubdiv_CPU_LIBRARY}"
    INTERFACE_INCLUDE_DIRECTORIES "${OpenSubdiv_INCLUDE_DIR}")
endif()
