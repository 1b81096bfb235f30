# CLI11 (libcli11-dev), header only: subcommands, --help and typed options for the sketchdrape CLI.
include(require)
find_package(CLI11 2.1 QUIET CONFIG)
sd_require_target(CLI11::CLI11 libcli11-dev "CLI11")
