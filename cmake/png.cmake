# libpng 1.6 (libpng-dev): writes the rendered images.
include(require)
find_package(PNG 1.6 QUIET)
sd_require_target(PNG::PNG libpng-dev "libpng 1.6")
