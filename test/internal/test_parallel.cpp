// run_concurrently of internal/parallel.h: both parts run, at the same time when parallel, and neither an
// exception nor a return leaves the background part running.
#include <CGAL_ext/internal/parallel.h>

#include <CGAL/tags.h>

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#ifdef CGAL_LINKED_WITH_TBB
#include <tbb/info.h>
#endif

using namespace CGAL_ext::internal;

namespace {

/// Waits until `flag` is set, for at most ten seconds; returns whether it was set.
bool wait_for(const std::atomic<bool>& flag)
{
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while(!flag.load() && std::chrono::steady_clock::now() < deadline) std::this_thread::yield();
  return flag.load();
}

} // namespace

TEST(RunConcurrently, SequentialRunsTheBackgroundFirst)
{
  std::vector<std::string> order;
  run_concurrently<CGAL::Sequential_tag>([&] { order.push_back("background"); }, [&] { order.push_back("foreground"); });
  EXPECT_EQ(order, (std::vector<std::string>{"background", "foreground"}));
}

#ifdef CGAL_LINKED_WITH_TBB
TEST(RunConcurrently, ParallelRunsBothAtOnce)
{
  if(tbb::info::default_concurrency() < 2) GTEST_SKIP() << "one thread: nothing can overlap";
  // Each part waits for the other to have started: they meet only if they run at the same time.
  std::atomic<bool> background_started{false}, foreground_started{false};
  bool background_saw_foreground = false, foreground_saw_background = false;
  run_concurrently<CGAL::Parallel_tag>(
    [&] {
      background_started = true;
      background_saw_foreground = wait_for(foreground_started);
    },
    [&] {
      foreground_started = true;
      foreground_saw_background = wait_for(background_started);
    });
  EXPECT_TRUE(background_saw_foreground);
  EXPECT_TRUE(foreground_saw_background);
}

TEST(RunConcurrently, ExceptionsArriveAfterBothPartsAreDone)
{
  std::atomic<bool> done{false};
  // The background's exception, once the foreground has finished.
  try {
    run_concurrently<CGAL::Parallel_tag>([] { throw std::runtime_error("background"); },
                                         [&] {
                                           std::this_thread::sleep_for(std::chrono::milliseconds(50));
                                           done = true;
                                         });
    ADD_FAILURE() << "nothing thrown";
  } catch(const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), "background");
    EXPECT_TRUE(done.load());
  }
  // The foreground's, once the background has finished (its locals would be gone otherwise), even when the
  // background throws too.
  for(const bool background_throws : {false, true}) {
    done = false;
    try {
      run_concurrently<CGAL::Parallel_tag>(
        [&] {
          std::this_thread::sleep_for(std::chrono::milliseconds(50));
          done = true;
          if(background_throws) throw std::logic_error("background");
        },
        [] { throw std::runtime_error("foreground"); });
      ADD_FAILURE() << "nothing thrown";
    } catch(const std::runtime_error& e) {
      EXPECT_EQ(std::string(e.what()), "foreground");
      EXPECT_TRUE(done.load());
    } catch(const std::logic_error&) {
      ADD_FAILURE() << "the background's exception replaced the foreground's";
    }
  }
}
#endif
