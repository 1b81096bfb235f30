#include "meshing/check.hpp"

#include <gtest/gtest.h>

#include <string>

namespace sd {
namespace {

TEST(Check, PassingCheckDoesNotEvaluateItsMessage) {
  int messages_built = 0;
  const auto message = [&] {
    ++messages_built;
    return std::string("never");
  };
  SD_CHECK(1 + 1 == 2, message());
  SD_DCHECK(1 + 1 == 2, message());
  EXPECT_EQ(messages_built, 0);
}

TEST(Check, FailingCheckThrowsWithPlaceConditionAndMessage) {
  try {
    SD_CHECK(2 < 1, "two is not below one");
    FAIL() << "SD_CHECK(false) did not throw";
  } catch (const InvariantError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("check_test.cpp:"), std::string::npos) << what;
    EXPECT_NE(what.find("'2 < 1'"), std::string::npos) << what;
    EXPECT_NE(what.find("two is not below one"), std::string::npos) << what;
  }
}

TEST(Check, DebugCheckIsOnExactlyInDebugBuilds) {
  bool threw = false;
  try {
    SD_DCHECK(false, "debug only");
  } catch (const InvariantError&) {
    threw = true;
  }
#ifdef NDEBUG
  EXPECT_FALSE(threw);
#else
  EXPECT_TRUE(threw);
#endif
}

}  // namespace
}  // namespace sd
