# CGAL 5.5 (libcgal-dev), header only; brings GMP/MPFR and -frounding-math. A CGAL translation unit
# costs ~20 s and ~1.2 GB to compile, so only a few .cpp files may include CGAL headers.
include(require)
set(CGAL_DO_NOT_WARN_ABOUT_CMAKE_BUILD_TYPE TRUE)
find_package(CGAL 5.5 QUIET)
sd_require_target(CGAL::CGAL libcgal-dev "CGAL 5.5")
