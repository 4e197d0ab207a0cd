// format/base/parallel.h: every item runs once, on a named worker, and the first error reaches the caller.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <mutex>
#include <set>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "format/base/parallel.h"

namespace vxl {
namespace {

TEST(Parallel, ZeroThreadsMeansAllHardwareThreads) {
  EXPECT_EQ(resolve_threads(3), 3u);
  EXPECT_EQ(resolve_threads(0), std::max(1u, std::thread::hardware_concurrency()));
}

TEST(Parallel, EveryItemRunsExactlyOnceOnAWorkerBelowTheThreadCount) {
  const std::uint64_t count = 10000;
  std::vector<std::atomic<int>> runs(count);
  std::atomic<unsigned> highest_worker{0};
  parallel_for(count, 4, [&](std::uint64_t i, unsigned t) {
    ++runs[i];
    unsigned seen = highest_worker.load();
    while (t > seen && !highest_worker.compare_exchange_weak(seen, t)) {
    }
  });
  for (std::uint64_t i = 0; i < count; ++i) ASSERT_EQ(runs[i].load(), 1) << "item " << i;
  EXPECT_LT(highest_worker.load(), 4u);
}

TEST(Parallel, NoMoreWorkersThanItems) {
  std::set<unsigned> workers;
  std::mutex m;
  parallel_for(2, 16, [&](std::uint64_t, unsigned t) {
    std::lock_guard lock(m);
    workers.insert(t);
  });
  EXPECT_LE(*workers.rbegin(), 1u);
}

TEST(Parallel, TheFirstErrorIsRethrownOnTheCallerAndStopsTheHandOut) {
  for (unsigned threads : {1u, 2u, 4u}) {
    const std::uint64_t count = 200;
    std::atomic<std::uint64_t> ran{0};
    try {
      parallel_for(count, threads, [&](std::uint64_t i, unsigned) {
        ++ran;
        if (i == 0) throw std::runtime_error("item 0");
        std::this_thread::sleep_for(std::chrono::milliseconds(1));  // the others take a while
      });
      FAIL() << "no exception with " << threads << " threads";
    } catch (const std::runtime_error& e) {
      EXPECT_STREQ(e.what(), "item 0");
    }
    // Items already handed out finish; the rest never start.
    EXPECT_LT(ran.load(), count) << threads << " threads";
  }
}

// Item 0 throws last (after item 2 has thrown), yet its error is the one rethrown, and every item ran.
TEST(Parallel, InOrderTheLowestItemsErrorIsRethrownWhateverTheTiming) {
  for (unsigned threads : {1u, 3u}) {
    std::atomic<int> ran{0};
    try {
      parallel_for_first_error_in_order(3, threads, [&](std::uint64_t i, unsigned) {
        ++ran;
        if (i == 0) {
          std::this_thread::sleep_for(std::chrono::milliseconds(threads > 1 ? 30 : 0));
          throw std::runtime_error("item 0");
        }
        if (i == 2) throw std::runtime_error("item 2");
      });
      ADD_FAILURE() << "nothing was rethrown";
    } catch (const std::runtime_error& e) {
      EXPECT_STREQ(e.what(), "item 0") << threads << " threads";
    }
    EXPECT_EQ(ran.load(), 3) << threads << " threads";
  }
}

// Handed out in a given order: one thread runs the items in that order; the lowest item's error is still the one
// rethrown though it was handed out last; an order that is not of the items is refused.
TEST(Parallel, InOrderItemsAreHandedOutInTheOrderGivenAndTheLowestErrorStillWins) {
  const std::vector<std::uint64_t> order = {3, 4, 1, 2, 0};
  std::vector<std::uint64_t> ran;
  parallel_for_first_error_in_order(
      5, 1, [&](std::uint64_t i, unsigned) { ran.push_back(i); }, order);
  EXPECT_EQ(ran, order);
  for (unsigned threads : {1u, 2u}) {
    std::atomic<int> count{0};
    try {
      parallel_for_first_error_in_order(
          5, threads,
          [&](std::uint64_t i, unsigned) {
            ++count;
            if (i == 0 || i == 3) throw std::runtime_error("item " + std::to_string(i));
          },
          order);
      ADD_FAILURE() << "nothing was rethrown";
    } catch (const std::runtime_error& e) {
      EXPECT_STREQ(e.what(), "item 0") << threads << " threads";
    }
    EXPECT_EQ(count.load(), 5) << threads << " threads";
  }
  EXPECT_THROW(parallel_for_first_error_in_order(
                   3, 1, [](std::uint64_t, unsigned) {}, order),
               std::logic_error);
}

TEST(Parallel, InvokeRunsBothAndRethrows) {
  for (bool concurrent : {false, true}) {
    int a = 0, b = 0;
    parallel_invoke(
        concurrent, [&] { a = 1; }, [&] { b = 2; });
    EXPECT_EQ(a + b, 3);
    EXPECT_THROW(parallel_invoke(
                     concurrent, [] {}, [] { throw std::logic_error("b"); }),
                 std::logic_error);
  }
}

TEST(BackgroundTask, RunsOnAnotherThreadWhileTheCallerGoesOn) {
  std::atomic<bool> caller_went_on{false};
  const std::thread::id caller = std::this_thread::get_id();
  BackgroundTask<std::thread::id> task([&] {
    // Returns only once the caller has gone on past the task's start: the task must not run inline.
    while (!caller_went_on) std::this_thread::yield();
    return std::this_thread::get_id();
  });
  EXPECT_TRUE(task.valid());
  caller_went_on = true;
  EXPECT_NE(task.get(), caller);
  EXPECT_FALSE(task.valid()) << "get() empties the task";
}

TEST(BackgroundTask, GetRethrowsTheTasksExceptionOnTheCaller) {
  BackgroundTask<> failing([] { throw std::runtime_error("written badly"); });
  try {
    failing.get();
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "written badly");
  }
  BackgroundTask<int> value([]() -> int { throw std::logic_error("no value"); });
  EXPECT_THROW(value.get(), std::logic_error);
}

TEST(BackgroundTask, ADestroyedOrReplacedTaskIsWaitedFor) {
  std::atomic<int> finished{0};
  auto slow = [&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    ++finished;
  };
  { BackgroundTask<> task(slow); }
  EXPECT_EQ(finished.load(), 1) << "the destructor returned before the task finished";
  BackgroundTask<> task(slow);
  task = BackgroundTask<>(slow);  // waits for the first before taking the second
  EXPECT_GE(finished.load(), 2);
  task.get();
  EXPECT_EQ(finished.load(), 3);
  BackgroundTask<> ignored([] { throw std::runtime_error("dropped"); });  // joined, not rethrown, when destroyed
}

// ready() answers without waiting: false while the task runs, true once get() would return at once.
TEST(BackgroundTask, ReadySaysWithoutWaitingWhetherTheResultIsThere) {
  std::atomic<bool> release{false};
  BackgroundTask<int> task([&] {
    while (!release.load()) std::this_thread::yield();
    return 7;
  });
  EXPECT_TRUE(task.valid());
  EXPECT_FALSE(task.ready()) << "the task waits for the release";
  release = true;
  const auto t0 = std::chrono::steady_clock::now();
  while (!task.ready() && std::chrono::steady_clock::now() - t0 < std::chrono::seconds(60)) std::this_thread::yield();
  ASSERT_TRUE(task.ready());
  EXPECT_EQ(task.get(), 7);
  EXPECT_FALSE(task.ready()) << "an empty task has nothing to give";
}

TEST(BackgroundTask, MovingATaskKeepsItsResult) {
  BackgroundTask<std::vector<int>> task([] { return std::vector<int>{1, 2, 3}; });
  BackgroundTask<std::vector<int>> moved = std::move(task);
  EXPECT_FALSE(task.valid());  // NOLINT(bugprone-use-after-move): a moved-from task is empty
  EXPECT_EQ(moved.get(), (std::vector<int>{1, 2, 3}));
}

}  // namespace
}  // namespace vxl
