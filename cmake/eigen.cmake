# Eigen 3.4 (libeigen3-dev), header only. Found first: CGAL prepends its own FindEigen3 to the
# module path, after which FCL's config no longer finds Eigen3::Eigen.
include(require)
find_package(Eigen3 3.4 QUIET NO_MODULE)
sd_require_target(Eigen3::Eigen libeigen3-dev "Eigen 3.4")
