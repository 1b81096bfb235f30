# GoogleTest (libgtest-dev) for the tests, Google Benchmark (libbenchmark-dev) for tests/bench.
include(require)
find_package(GTest 1.11 QUIET)
sd_require_target(GTest::gtest_main libgtest-dev "GoogleTest")
include(GoogleTest)
if(SD_BUILD_BENCHMARKS)
  find_package(benchmark 1.6 QUIET)
  sd_require_target(benchmark::benchmark libbenchmark-dev "Google Benchmark")
endif()
