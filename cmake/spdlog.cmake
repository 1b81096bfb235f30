# spdlog 1.10 (libspdlog-dev): levelled logs on stderr (--quiet / --verbose).
include(require)
find_package(spdlog 1.10 QUIET)
sd_require_target(spdlog::spdlog libspdlog-dev "spdlog")
