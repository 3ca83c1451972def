# FindOSMesa: Mesa's off-screen rendering library (Debian: libosmesa6-dev).
# Defines OSMesa_FOUND and the imported target OSMesa::OSMesa (libOSMesa only; Canopy resolves
# every gl* entry point through OSMesaGetProcAddress, so no libGL is linked).
find_path(OSMesa_INCLUDE_DIR NAMES GL/osmesa.h)
find_library(OSMesa_LIBRARY NAMES OSMesa)
include(FindPackageHandleStandardArgs)
find_package_handle_standard_args(OSMesa REQUIRED_VARS OSMesa_LIBRARY OSMesa_INCLUDE_DIR)
if(OSMesa_FOUND AND NOT TARGET OSMesa::OSMesa)
  add_library(OSMesa::OSMesa UNKNOWN IMPORTED)
  set_target_properties(OSMesa::OSMesa PROPERTIES
    IMPORTED_LOCATION "${OSMesa_LIBRARY}"
    INTERFACE_INCLUDE_DIRECTORIES "${OSMesa_INCLUDE_DIR}")
endif()
mark_as_advanced(OSMesa_INCLUDE_DIR OSMesa_LIBRARY)
