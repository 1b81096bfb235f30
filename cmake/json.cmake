# nlohmann-json 3.11 (nlohmann-json3-dev): sketch files (with // comments), reports, corpora.
include(require)
find_package(nlohmann_json 3.10 QUIET)
sd_require_target(nlohmann_json::nlohmann_json nlohmann-json3-dev "nlohmann-json")
