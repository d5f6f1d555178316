#pragma once
// Writes an LCM event log from a thread of its own. The receive thread only copies each message
// into a queue (Add), so a slow disk can never stall it: a stalled receive thread lets LCM's
// subscription queues overflow and drop messages (see KeepQueued in messages/receive_thread.h).

#include <lcm/lcm-cpp.hpp>

#include <condition_variable>
#include <cstdint>
#include <deque>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace hapsim::apps {

class LogWriter {
 public:
  // Opens `path` for writing; throws std::runtime_error if it cannot.
  explicit LogWriter(const std::string& path) : log_(path, "w") {
    if (!log_.good()) throw std::runtime_error("cannot write the LCM log " + path);
    thread_ = std::thread([this] { Run(); });
  }
  ~LogWriter() { Close(); }

  // Queues one message (called from the receive thread).
  void Add(const lcm::ReceiveBuffer* buffer, const std::string& channel) {
    Event event{buffer->recv_utime, channel,
                std::vector<std::uint8_t>(static_cast<const std::uint8_t*>(buffer->data),
                                          static_cast<const std::uint8_t*>(buffer->data) +
                                              buffer->data_size)};
    {
      std::lock_guard<std::mutex> lock(mutex_);
      queue_.push_back(std::move(event));
    }
    wake_.notify_one();
  }

  // Writes what is queued and closes the file.
  void Close() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      closing_ = true;
    }
    wake_.notify_one();
    if (thread_.joinable()) thread_.join();
  }

 private:
  struct Event {
    std::int64_t utime;
    std::string channel;
    std::vector<std::uint8_t> data;
  };

  void Run() {
    std::unique_lock<std::mutex> lock(mutex_);
    while (true) {
      wake_.wait(lock, [this] { return closing_ || !queue_.empty(); });
      if (queue_.empty() && closing_) return;
      Event event = std::move(queue_.front());
      queue_.pop_front();
      lock.unlock();
      lcm::LogEvent log_event;
      log_event.eventnum = num_written_++;
      log_event.timestamp = event.utime;
      log_event.channel = event.channel;
      log_event.datalen = static_cast<int32_t>(event.data.size());
      log_event.data = event.data.data();
      log_.writeEvent(&log_event);
      lock.lock();
    }
  }

  lcm::LogFile log_;
  std::mutex mutex_;
  std::condition_variable wake_;
  std::deque<Event> queue_;
  bool closing_ = false;
  long num_written_ = 0;
  std::thread thread_;
};

}  // namespace hapsim::apps
