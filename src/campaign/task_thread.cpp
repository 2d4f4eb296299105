#include "campaign/task_thread.hpp"

#include <pthread.h>
#include <time.h>

namespace truss::campaign {

TaskThread::TaskThread(std::size_t max_queued_bytes) : max_(max_queued_bytes), thread_([this] { loop(); }) {
  handle_ = thread_.native_handle();
}

TaskThread::~TaskThread() {
  {
    std::lock_guard<std::mutex> l(m_);
    stop_ = true;
  }
  work_.notify_all();
  thread_.join();
}

void TaskThread::rethrow_locked() {
  if (error_) std::rethrow_exception(error_);
}

void TaskThread::post(std::function<void()> task, std::size_t bytes) {
  {
    std::unique_lock<std::mutex> l(m_);
    // At most max_ bytes wait, or a single task of any size on its own (so that none waits forever).
    space_.wait(l, [&] { return queued_ == 0 || queued_ + bytes <= max_ || error_; });
    rethrow_locked();
    queue_.emplace_back(std::move(task), bytes);
    queued_ += bytes;
  }
  work_.notify_one();
}

void TaskThread::drain() {
  std::unique_lock<std::mutex> l(m_);
  idle_.wait(l, [&] { return (queue_.empty() && !busy_) || error_; });
  rethrow_locked();
}

double TaskThread::calc_cpu_s() const {
  clockid_t id{};
  timespec ts{};
  if (pthread_getcpuclockid(handle_, &id) != 0 || clock_gettime(id, &ts) != 0)
    return -1.0;
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

void TaskThread::loop() {
  std::unique_lock<std::mutex> l(m_);
  for (;;) {
    work_.wait(l, [&] { return stop_ || (!queue_.empty() && !error_); });
    if (stop_) return;
    auto [task, bytes] = std::move(queue_.front());
    queue_.pop_front();
    busy_ = true;
    l.unlock();
    std::exception_ptr err;
    try {
      task();
    } catch (...) {
      err = std::current_exception();
    }
    task = nullptr;  // what the task held (the message its bytes are in) is released outside the lock
    l.lock();
    busy_ = false;
    queued_ -= bytes;
    if (err && !error_) error_ = err;
    space_.notify_all();
    idle_.notify_all();
  }
}

}  // namespace truss::campaign
