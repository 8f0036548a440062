/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <deque>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>
#include <utility>

namespace pcl_movers {
namespace io {

/** \brief What a full BoundedQueue does with a new item. */
enum class QueuePolicy {
  kBlock,      ///< the producer waits for room: nothing is lost (files)
  kDropOldest  ///< the oldest queued item is dropped and counted: the newest is kept (live)
};

/** \brief A FIFO queue of at most `capacity` items between one producer thread and one consumer
 * thread.
 *
 * push() either waits for room (QueuePolicy::kBlock) or drops the oldest waiting item and counts
 * it (QueuePolicy::kDropOldest), so the queue never grows without bound. close() ends the stream
 * from the producer's side (pop() hands out what is left, then returns false); cancel() ends it
 * from the consumer's side (push() and pop() return false at once, the items left are
 * discarded). Every call is thread-safe.
 */
template <typename T>
class BoundedQueue {
 public:
  /** \brief `capacity` is at least 1 (0 is taken as 1). */
  explicit BoundedQueue(std::size_t capacity, QueuePolicy policy = QueuePolicy::kBlock)
      : capacity_(capacity > 0 ? capacity : 1), policy_(policy) {}

  /** \brief Adds `item`; false (item not queued) once the queue is closed or cancelled. */
  bool push(T item) {
    std::unique_lock<std::mutex> lock(mutex_);
    if (policy_ == QueuePolicy::kBlock)
      not_full_.wait(lock, [&] { return items_.size() < capacity_ || closed_ || cancelled_; });
    if (closed_ || cancelled_) return false;
    while (items_.size() >= capacity_) {
      items_.pop_front();
      ++dropped_;
    }
    items_.push_back(std::move(item));
    ++pushed_;
    not_empty_.notify_one();
    return true;
  }

  /** \brief Waits for the next item; false when the queue is closed and empty, or cancelled. */
  bool pop(T& item) {
    std::unique_lock<std::mutex> lock(mutex_);
    not_empty_.wait(lock, [&] { return !items_.empty() || closed_ || cancelled_; });
    return take(item);
  }

  /** \brief As pop(), waiting at most `timeout`; false also when it passed without an item. */
  template <typename Rep, typename Period>
  bool popFor(T& item, const std::chrono::duration<Rep, Period>& timeout) {
    std::unique_lock<std::mutex> lock(mutex_);
    not_empty_.wait_for(lock, timeout, [&] { return !items_.empty() || closed_ || cancelled_; });
    return take(item);
  }

  /** \brief The producer is done: no more push(); pop() drains what is queued. */
  void close() {
    std::lock_guard<std::mutex> lock(mutex_);
    closed_ = true;
    not_empty_.notify_all();
    not_full_.notify_all();
  }

  /** \brief The consumer is gone: push() and pop() return false from now on, and a producer
   * waiting for room wakes up. */
  void cancel() {
    std::lock_guard<std::mutex> lock(mutex_);
    cancelled_ = true;
    items_.clear();
    not_empty_.notify_all();
    not_full_.notify_all();
  }

  std::size_t capacity() const { return capacity_; }
  QueuePolicy policy() const { return policy_; }
  /** \brief Items waiting now. */
  std::size_t size() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return items_.size();
  }
  /** \brief Items accepted by push() so far (dropped ones included). */
  std::size_t pushedCount() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return pushed_;
  }
  /** \brief Items handed out by pop() so far. */
  std::size_t poppedCount() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return popped_;
  }
  /** \brief Items dropped by QueuePolicy::kDropOldest so far. */
  std::size_t droppedCount() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return dropped_;
  }

 private:
  bool take(T& item) {
    if (cancelled_ || items_.empty()) return false;
    item = std::move(items_.front());
    items_.pop_front();
    ++popped_;
    not_full_.notify_one();
    return true;
  }

  const std::size_t capacity_;
  const QueuePolicy policy_;
  mutable std::mutex mutex_;
  std::condition_variable not_empty_, not_full_;
  std::deque<T> items_;
  bool closed_ = false, cancelled_ = false;
  std::size_t pushed_ = 0, popped_ = 0, dropped_ = 0;
};

/** \brief Frames produced on a thread of their own (reading, decoding) and consumed on the
 * caller's (detection), through a BoundedQueue.
 *
 * The producer is called on the stream's thread as `produce(frame)` until it returns false (end
 * of the input) or the stream is stopped; each frame it fills is queued. An exception thrown by
 * the producer ends the stream and is rethrown by next() after the frames queued before it. The
 * optional `interrupt` is called by stop() to wake a producer blocked in its input (a socket
 * waiting for packets); the destructor stops and joins the thread, so nothing outlives the stream.
 *
 * \code
 * pcl_movers::io::FrameStream<Frame> stream(
 *     [&](Frame& f) { return capture.next(f); }, 4, pcl_movers::io::QueuePolicy::kBlock);
 * Frame f;
 * while (stream.next(f)) detect(f);
 * \endcode
 */
template <typename T>
class FrameStream {
 public:
  using Producer = std::function<bool(T&)>;

  FrameStream(Producer produce, std::size_t capacity, QueuePolicy policy,
              std::function<void()> interrupt = {})
      : queue_(capacity, policy),
        produce_(std::move(produce)),
        interrupt_(std::move(interrupt)),
        thread_([this] { run(); }) {}

  ~FrameStream() { stop(); }
  FrameStream(const FrameStream&) = delete;
  FrameStream& operator=(const FrameStream&) = delete;

  /** \brief The next frame in the order produced; false at the end of the input (or once
   * stopped). Rethrows the producer's exception when the frames before it are consumed. */
  bool next(T& frame) {
    if (queue_.pop(frame)) return true;
    std::lock_guard<std::mutex> lock(error_mutex_);
    if (error_) std::rethrow_exception(std::exchange(error_, nullptr));
    return false;
  }

  /** \brief Ends the stream: the producer is interrupted and joined, queued frames discarded.
   * Call from the consumer's thread; idempotent. */
  void stop() {
    queue_.cancel();
    if (interrupt_ && thread_.joinable()) interrupt_();
    if (thread_.joinable()) thread_.join();
  }

  /** \brief Frames the producer gave so far. */
  std::size_t producedCount() const { return queue_.pushedCount(); }
  /** \brief Frames dropped because the consumer fell behind (QueuePolicy::kDropOldest). */
  std::size_t droppedCount() const { return queue_.droppedCount(); }
  std::size_t capacity() const { return queue_.capacity(); }

 private:
  void run() {
    try {
      for (;;) {
        T frame;
        if (!produce_(frame)) break;
        if (!queue_.push(std::move(frame))) break;
      }
    } catch (...) {
      std::lock_guard<std::mutex> lock(error_mutex_);
      error_ = std::current_exception();
    }
    queue_.close();
  }

  BoundedQueue<T> queue_;
  Producer produce_;
  std::function<void()> interrupt_;
  std::mutex error_mutex_;
  std::exception_ptr error_;
  std::thread thread_;  ///< last: starts once everything it uses exists
};

}  // namespace io
}  // namespace pcl_movers
