# FindEGL: libEGL alone (Debian: libegl-dev). CMake's OpenGL::EGL target also links
# OpenGL::OpenGL (libOpenGL), whose gl* symbols are the trap DESIGN.md describes; Canopy resolves
# every gl* entry point through eglGetProcAddress and links no GL library.
find_path(EGL_INCLUDE_DIR NAMES EGL/egl.h)
find_library(EGL_LIBRARY NAMES EGL)
include(FindPackageHandleStandardArgs)
find_package_handle_standard_args(EGL REQUIRED_VARS EGL_LIBRARY EGL_INCLUDE_DIR)
if(EGL_FOUND AND NOT TARGET EGL::EGL)
  add_library(EGL::EGL UNKNOWN IMPORTED)
  set_target_properties(EGL::EGL PROPERTIES
    IMPORTED_LOCATION "${EGL_LIBRARY}"
    INTERFACE_INCLUDE_DIRECTORIES "${EGL_INCLUDE_DIR}")
endif()
mark_as_advanced(EGL_INCLUDE_DIR EGL_LIBRARY)
