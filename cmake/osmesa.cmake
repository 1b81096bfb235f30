# OSMesa (libosmesa6-dev): OpenGL without a display, on the CPU (llvmpipe). Link OSMesa only:
# adding -lGL as well makes glGetString return NULL.
include(require)
find_package(PkgConfig QUIET)
if(PkgConfig_FOUND)
  pkg_check_modules(OSMESA QUIET IMPORTED_TARGET osmesa)
endif()
sd_require_target(PkgConfig::OSMESA libosmesa6-dev "OSMesa")
