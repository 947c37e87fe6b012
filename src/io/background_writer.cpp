#include "pc_ekf/io/background_writer.h"

#include <pthread.h>
#include <sched.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <exception>
#include <utility>

namespace pc_ekf {

BackgroundWriter::BackgroundWriter() : thread_([this] { loop(); }) {}

BackgroundWriter::~BackgroundWriter() {
  flush();
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  thread_.join();
}

void BackgroundWriter::submit(Job job) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (pending_) ++superseded_;
    pending_ = std::move(job);
  }
  wake_.notify_all();
}

void BackgroundWriter::flush() {
  std::unique_lock<std::mutex> lock(mutex_);
  idle_.wait(lock, [this] { return !pending_ && !running_; });
}

void BackgroundWriter::cancel() {
  std::unique_lock<std::mutex> lock(mutex_);
  if (pending_) {
    pending_ = nullptr;
    ++superseded_;
    idle_.notify_all();
  }
  idle_.wait(lock, [this] { return !running_; });
}

std::vector<std::string> BackgroundWriter::takeErrors() {
  std::lock_guard<std::mutex> lock(mutex_);
  return std::exchange(errors_, {});
}

std::uint64_t BackgroundWriter::written() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return written_;
}

std::uint64_t BackgroundWriter::superseded() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return superseded_;
}

void BackgroundWriter::loop() {
  // Lowest priority for this thread only: SCHED_IDLE (any other thread that
  // wakes up preempts it at once) or, where refused, nice 19 (nice is per
  // thread on Linux). On a busy machine the writes yield the CPU to the
  // sample callbacks. Best effort; a failure leaves the default priority.
  sched_param idle{};
  if (::pthread_setschedparam(::pthread_self(), SCHED_IDLE, &idle) != 0) {
    (void)::setpriority(PRIO_PROCESS, static_cast<id_t>(::syscall(SYS_gettid)), 19);
  }
  std::unique_lock<std::mutex> lock(mutex_);
  for (;;) {
    wake_.wait(lock, [this] { return stop_ || pending_; });
    if (!pending_) return;  // stop_ with nothing left to write
    Job job = std::exchange(pending_, nullptr);
    running_ = true;
    lock.unlock();
    std::string error;
    try {
      job();
    } catch (const std::exception& e) {
      error = e.what();
    } catch (...) {
      error = "background write: unknown exception";
    }
    job = nullptr;  // the snapshot it holds is freed off the caller's thread too
    lock.lock();
    running_ = false;
    if (error.empty()) {
      ++written_;
    } else {
      errors_.push_back(error);
    }
    idle_.notify_all();
  }
}

}  // namespace pc_ekf
