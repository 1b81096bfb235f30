# assimp 5.2 (libassimp-dev): loads body meshes of any common format.
include(require)
find_package(assimp 5.2 QUIET)
sd_require_target(assimp::assimp libassimp-dev "assimp 5.2")
