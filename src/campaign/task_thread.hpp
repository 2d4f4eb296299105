// A thread that runs posted tasks one at a time, in the order posted: rank 0's chunk writes and
// statistics merges (result_store.hpp), so that the thread answering the workers does not do them.
// Posting blocks while more than max_queued_bytes of posted tasks wait (each task says how many
// bytes it holds), so a slow thread slows rank 0 instead of growing its memory. The first task that
// throws stops the rest: post and drain rethrow its exception.
#pragma once
#include <condition_variable>
#include <cstddef>
#include <deque>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>
#include <utility>

namespace truss::campaign {

class TaskThread {
 public:
  explicit TaskThread(std::size_t max_queued_bytes);
  ~TaskThread();  // waits for the running task; the tasks still queued are dropped
  TaskThread(const TaskThread&) = delete;
  TaskThread& operator=(const TaskThread&) = delete;

  void post(std::function<void()> task, std::size_t bytes);
  void drain();             // returns once every posted task has run
  double calc_cpu_s() const;  // the thread's CPU time so far (its own clock, read from here)

 private:
  void loop();
  void rethrow_locked();
  std::mutex m_;
  std::condition_variable work_, space_, idle_;
  std::deque<std::pair<std::function<void()>, std::size_t>> queue_;
  std::size_t queued_ = 0, max_;
  bool busy_ = false, stop_ = false;
  std::exception_ptr error_;
  std::thread thread_;
  std::thread::native_handle_type handle_{};
};

}  // namespace truss::campaign
