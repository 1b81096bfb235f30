#include "sim/parallel.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <random>
#include <vector>

#include "sim/body_collider.hpp"
#include "tests/sim/test_bodies.hpp"

namespace sd::sim {
namespace {

// Restores the process-wide thread count after a test changes it.
class ThreadCount : public ::testing::Test {
 protected:
  void TearDown() override { set_thread_count(0); }
};

TEST_F(ThreadCount, ChunksCoverTheRangeOnceInOrderWhateverTheThreads) {
  for (int threads : {1, 2, 4}) {
    set_thread_count(threads);
    EXPECT_EQ(thread_count(), threads);
    for (int n : {0, 1, 255, 256, 1000, 100003}) {
      const int chunks = chunk_count(n, 256);
      std::vector<int> begins(static_cast<std::size_t>(chunks), -1),
          ends(static_cast<std::size_t>(chunks), -1);
      std::vector<std::atomic<int>> hits(static_cast<std::size_t>(n));
      parallel_chunks(n, 256, [&](int c, int first, int last) {
        begins[static_cast<std::size_t>(c)] = first;
        ends[static_cast<std::size_t>(c)] = last;
        for (int i = first; i < last; ++i) ++hits[static_cast<std::size_t>(i)];
      });
      for (int i = 0; i < n; ++i) ASSERT_EQ(hits[static_cast<std::size_t>(i)], 1) << n << " " << i;
      for (int c = 0; c < chunks; ++c) {
        EXPECT_EQ(begins[static_cast<std::size_t>(c)],
                  c == 0 ? 0 : ends[static_cast<std::size_t>(c - 1)]);
        // At least the grain long, except when the range itself is shorter.
        EXPECT_GE(ends[static_cast<std::size_t>(c)] - begins[static_cast<std::size_t>(c)],
                  std::min(n, 256));
      }
      if (chunks > 0) {
        EXPECT_EQ(ends.back(), n);
      }
    }
  }
  set_thread_count(0);
  EXPECT_GE(thread_count(), 1);
}

// The contact queries give the same contacts, in the same order, with the same counts, on one
// thread and on four: the chunks depend on the vertex count only.
TEST_F(ThreadCount, ContactQueriesAreTheSameOnOneAndManyThreads) {
  const BodyCollider body(testing::make_sphere(0.3, 4));
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-0.36, 0.36);
  Eigen::VectorXd x0(3 * 5000), x1(3 * 5000);
  for (Eigen::Index i = 0; i < x0.size(); ++i) {
    x0[i] = u(rng);
    x1[i] = x0[i] + 0.1 * u(rng);
  }
  ContactQuery query;
  query.thickness = 0.01;
  const auto run = [&](int threads, bool swept) {
    set_thread_count(threads);
    ContactCache cache;
    ContactQueryStats stats;
    std::vector<BodyContact> contacts =
        swept ? body.find_contacts_swept(x0, x1, query, &cache, &stats)
              : body.find_contacts(x1, query, &cache, &stats);
    return std::make_pair(contacts, stats);
  };
  for (bool swept : {false, true}) {
    const auto [one, one_stats] = run(1, swept);
    const auto [four, four_stats] = run(4, swept);
    ASSERT_GT(one.size(), 100u) << "the sample must put many points near the sphere";
    ASSERT_EQ(one.size(), four.size());
    for (std::size_t k = 0; k < one.size(); ++k) {
      EXPECT_EQ(one[k].vertex, four[k].vertex);
      EXPECT_EQ(one[k].triangle, four[k].triangle);
      EXPECT_EQ(one[k].distance, four[k].distance);  // bit for bit
      EXPECT_EQ(one[k].crossed, four[k].crossed);
    }
    EXPECT_EQ(one_stats.vertices, 5000);
    EXPECT_EQ(four_stats.vertices, 5000);
    EXPECT_EQ(one_stats.bounded_searches, four_stats.bounded_searches);
    EXPECT_EQ(one_stats.full_searches, four_stats.full_searches);
    EXPECT_EQ(one_stats.sweep_samples, four_stats.sweep_samples);
    EXPECT_EQ(one_stats.crossings, four_stats.crossings);
  }
}

}  // namespace
}  // namespace sd::sim
