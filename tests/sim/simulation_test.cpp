#include "sim/simulation.hpp"

#include <gtest/gtest.h>

#include "test_scenes.hpp"

namespace sd::sim {
namespace {

TEST(Simulation, Placeholder) { SUCCEED(); }

}  // namespace
}  // namespace sd::sim
