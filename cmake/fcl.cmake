# FCL 0.7 (libfcl-dev): body collision BVH. Its config defines the target 'fcl' (no namespace).
# Do not use fcl.pc: it forces -std=c++11.
include(require)
find_package(fcl 0.7 QUIET)
sd_require_target(fcl libfcl-dev "FCL 0.7")
