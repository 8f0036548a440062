/*
 * io::BoundedQueue and io::FrameStream: capacity, drop-oldest counting, blocking delivery in
 * order, errors and shutdown without hanging.
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/io/frame_stream.h>

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <future>
#include <stdexcept>
#include <thread>
#include <vector>

using pcl_movers::io::BoundedQueue;
using pcl_movers::io::FrameStream;
using pcl_movers::io::QueuePolicy;

namespace {

/** Runs `body` on a thread and fails (instead of hanging) when it takes over `seconds`. */
template <typename Body>
bool finishesWithin(double seconds, Body&& body) {
  auto done = std::async(std::launch::async, std::forward<Body>(body));
  return done.wait_for(std::chrono::duration<double>(seconds)) == std::future_status::ready;
}

}  // namespace

TEST(FrameStream, QueueCapacity) {
  BoundedQueue<int> queue(3, QueuePolicy::kDropOldest);
  EXPECT_EQ(queue.capacity(), 3u);
  for (int k = 0; k < 10; ++k) EXPECT_TRUE(queue.push(k));
  EXPECT_EQ(queue.size(), 3u);  // never more than its capacity
  BoundedQueue<int> zero(0);
  EXPECT_EQ(zero.capacity(), 1u);
}

TEST(FrameStream, DropOldestCounts) {
  BoundedQueue<int> queue(2, QueuePolicy::kDropOldest);
  for (int k = 0; k < 7; ++k) queue.push(k);
  EXPECT_EQ(queue.pushedCount(), 7u);
  EXPECT_EQ(queue.droppedCount(), 5u);
  queue.close();
  std::vector<int> got;
  int v = 0;
  while (queue.pop(v)) got.push_back(v);
  EXPECT_EQ(got, (std::vector<int>{5, 6}));  // the newest survive, in order
  EXPECT_EQ(queue.poppedCount(), 2u);
  EXPECT_FALSE(queue.push(7));  // closed
}

TEST(FrameStream, BlockingQueueWaitsForRoom) {
  BoundedQueue<int> queue(1, QueuePolicy::kBlock);
  ASSERT_TRUE(queue.push(1));
  std::atomic<bool> pushed{false};
  std::thread producer([&] {
    queue.push(2);
    pushed = true;
  });
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  EXPECT_FALSE(pushed.load());  // full: the producer waits
  int v = 0;
  ASSERT_TRUE(queue.pop(v));
  EXPECT_EQ(v, 1);
  producer.join();
  EXPECT_TRUE(pushed.load());
  ASSERT_TRUE(queue.pop(v));
  EXPECT_EQ(v, 2);
  EXPECT_EQ(queue.droppedCount(), 0u);
}

TEST(FrameStream, BlockingDeliversAllInOrder) {
  const int n = 2000;
  int produced = 0;
  FrameStream<int> stream([&](int& v) { return produced < n ? (v = produced++, true) : false; }, 2,
                          QueuePolicy::kBlock);
  std::vector<int> got;
  int v = 0;
  while (stream.next(v)) {
    got.push_back(v);
    if (got.size() % 500 == 0) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  ASSERT_EQ(got.size(), static_cast<std::size_t>(n));
  for (int k = 0; k < n; ++k) ASSERT_EQ(got[k], k);
  EXPECT_EQ(stream.droppedCount(), 0u);
  EXPECT_EQ(stream.producedCount(), static_cast<std::size_t>(n));
}

TEST(FrameStream, DropOldestWhenTheConsumerFallsBehind) {
  const int n = 50;
  int produced = 0;
  FrameStream<int> stream([&](int& v) { return produced < n ? (v = produced++, true) : false; }, 2,
                          QueuePolicy::kDropOldest);
  // The consumer starts only once everything was produced: it fell behind by all but 2 frames.
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (stream.producedCount() < static_cast<std::size_t>(n) &&
         std::chrono::steady_clock::now() < give_up)
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  std::vector<int> got;
  int v = 0;
  while (stream.next(v)) got.push_back(v);
  EXPECT_EQ(stream.producedCount(), static_cast<std::size_t>(n));
  EXPECT_EQ(got.size() + stream.droppedCount(), static_cast<std::size_t>(n));
  EXPECT_EQ(stream.droppedCount(), static_cast<std::size_t>(n - 2));
  for (std::size_t k = 1; k < got.size(); ++k) EXPECT_LT(got[k - 1], got[k]);  // still in order
  EXPECT_EQ(got.back(), n - 1);  // the newest frame is never the one dropped
}

TEST(FrameStream, ProducerErrorIsRethrownAfterItsFrames) {
  int produced = 0;
  FrameStream<int> stream(
      [&](int& v) {
        if (produced == 3) throw std::runtime_error("bad packet");
        v = produced++;
        return true;
      },
      8, QueuePolicy::kBlock);
  int v = 0, count = 0;
  EXPECT_THROW(
      {
        while (stream.next(v)) ++count;
      },
      std::runtime_error);
  EXPECT_EQ(count, 3);
}

TEST(FrameStream, ShutdownDoesNotHang) {
  // A producer blocked on a full queue (consumer gone) and one blocked in its input (a socket
  // without packets, woken by the interrupt) are both joined by stop()/the destructor.
  EXPECT_TRUE(finishesWithin(10.0, [] {
    FrameStream<int> stream([](int& v) { return v = 1, true; }, 1, QueuePolicy::kBlock);
    int v = 0;
    stream.next(v);
  }));
  EXPECT_TRUE(finishesWithin(10.0, [] {
    std::mutex m;
    std::condition_variable cv;
    bool woken = false;
    FrameStream<int> stream(
        [&](int&) {
          std::unique_lock<std::mutex> lock(m);
          cv.wait(lock, [&] { return woken; });
          return false;
        },
        1, QueuePolicy::kDropOldest,
        [&] {
          std::lock_guard<std::mutex> lock(m);
          woken = true;
          cv.notify_all();
        });
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    stream.stop();
    int v = 0;
    EXPECT_FALSE(stream.next(v));
  }));
  BoundedQueue<int> queue(1);
  int v = 0;
  EXPECT_TRUE(finishesWithin(10.0, [&] { return queue.popFor(v, std::chrono::milliseconds(20)); }));
  queue.cancel();
  EXPECT_FALSE(queue.pop(v));
}
