// campaign/task_thread.hpp: tasks run one at a time in the order posted, posting waits for room,
// the first error stops the rest and reaches the poster. Also run under ThreadSanitizer
// (journal_tsan's binary, scripts/sanitize.sh): the tasks touch plain (non-atomic) state that the
// poster reads after drain, so a missing happens-before is a reported race.
#include <catch2/catch.hpp>

#include <atomic>
#include <chrono>
#include <memory>
#include <stdexcept>
#include <thread>
#include <vector>

#include "campaign/task_thread.hpp"

using truss::campaign::TaskThread;

TEST_CASE("a task thread runs every task, in order, while posting waits for room", "[campaign][task_thread]") {
  std::vector<int> order;  // written by the tasks only, read after drain
  TaskThread t(1000);      // bytes: a few tasks at a time
  for (int i = 0; i < 2000; ++i) {
    const std::size_t bytes = 100 + static_cast<std::size_t>(i % 7) * 50;
    auto payload = std::make_shared<std::vector<char>>(bytes, static_cast<char>(i));  // what a task keeps alive
    t.post([&order, payload, i] {
      order.push_back(i + static_cast<int>(payload->size()) * 0);
      if (i % 500 == 0) std::this_thread::sleep_for(std::chrono::milliseconds(2));  // posts pile up behind it
    }, bytes);
  }
  t.drain();
  REQUIRE(order.size() == 2000);
  int wrong = 0;
  for (int i = 0; i < 2000; ++i) wrong += order[static_cast<std::size_t>(i)] != i;
  CHECK(wrong == 0);
  CHECK(t.calc_cpu_s() >= 0.0);
  t.post([&order] { order.push_back(-1); }, 5000);  // larger than the limit: accepted on its own
  t.drain();
  CHECK(order.back() == -1);
}

TEST_CASE("a task thread's first error stops the rest and reaches the poster", "[campaign][task_thread]") {
  int ran = 0;
  TaskThread t(1 << 20);
  t.post([&ran] { ++ran; }, 1);
  t.post([] { throw std::runtime_error("disk full"); }, 1);
  t.post([&ran] { ++ran; std::this_thread::sleep_for(std::chrono::milliseconds(1)); }, 1);
  CHECK_THROWS_WITH(t.drain(), Catch::Contains("disk full"));
  CHECK(ran == 1);  // the task after the error did not run
  CHECK_THROWS_WITH(t.post([&ran] { ++ran; }, 1), Catch::Contains("disk full"));
  CHECK(ran == 1);
}

TEST_CASE("a task thread stopped with tasks queued finishes the running one, drops the rest, joins", "[campaign][task_thread]") {
  std::atomic<int> ran{0};
  std::atomic<bool> started{false};
  {
    TaskThread t(1 << 20);
    t.post([&] {
      started = true;
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
      ++ran;
    }, 1);
    for (int i = 0; i < 100; ++i) t.post([&ran] { ++ran; }, 1);
    while (!started) std::this_thread::yield();
  }
  CHECK(ran.load() == 1);  // the running task completed; none queued behind it ran
}
