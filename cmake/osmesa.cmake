# OSMesa (libosmesa6-dev): OpenGL without a display, on the CPU (llvmpipe). Link OSMesa only:
# adding -lGL as well makes glGetString return NULL.
#
# sd_osmesa_headers: OSMesa's include directories and SD_OSMESA_LIBRARY, the name of its shared
# library with the major version (libOSMesa.so.8), for sd_render, which opens it with dlopen
# when the first image is rendered (src/render/gl.hpp). PkgConfig::OSMESA links it directly.
include(require)
find_package(PkgConfig QUIET)
if(PkgConfig_FOUND)
  pkg_check_modules(OSMESA QUIET IMPORTED_TARGET osmesa)
endif()
sd_require_target(PkgConfig::OSMESA libosmesa6-dev "OSMesa")

set(sd_osmesa_soname "libOSMesa.so")
foreach(library IN LISTS OSMESA_LINK_LIBRARIES)
  get_filename_component(real "${library}" REALPATH)
  get_filename_component(name "${real}" NAME)
  if(name MATCHES "^(lib[^.]+\\.so\\.[0-9]+)")
    set(sd_osmesa_soname "${CMAKE_MATCH_1}")
  endif()
endforeach()
add_library(sd_osmesa_headers INTERFACE)
target_include_directories(sd_osmesa_headers SYSTEM INTERFACE ${OSMESA_INCLUDE_DIRS})
target_compile_definitions(sd_osmesa_headers INTERFACE SD_OSMESA_LIBRARY="${sd_osmesa_soname}")
