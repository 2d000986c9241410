// LockstepGate (engine/include/hsi/lockstep_gate.h): threads that post calls of
// different kinds are served only once every live thread has posted, one batch per kind,
// each call exactly once with its own result; threads that finish early leave without
// stalling the others; what a serve throws reaches that batch's callers alone.
#include <catch2/catch.hpp>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <mutex>
#include <random>
#include <set>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "hsi/lockstep_gate.h"

namespace {

struct Call {
  int thread = 0, index = 0, value = 0;
  int result = 0;
  std::uint64_t round = 0;  // the serve's round, to check that a thread's calls are served in order
};

}  // namespace

TEST_CASE("a lockstep gate serves each round once every live thread has posted, one batch per key", "[lockstep]") {
  constexpr int kThreads = 8;
  std::mutex log_mutex;
  std::uint64_t serves = 0;
  std::vector<int> batch_sizes;
  bool mixed_keys = false, served_twice = false;
  std::set<std::pair<int, int>> served;  // (thread, index)
  hsi::LockstepGate<Call> gate(kThreads, [&](int key, std::span<Call* const> batch) {
    std::lock_guard lock(log_mutex);
    batch_sizes.push_back(static_cast<int>(batch.size()));
    ++serves;
    for (Call* c : batch) {
      if (c->value % 5 != key) mixed_keys = true;
      c->result = 3 * c->value + c->thread;
      c->round = serves;
      if (!served.insert({c->thread, c->index}).second) served_twice = true;
    }
  });
  std::vector<std::thread> threads;
  std::vector<int> wrong(kThreads, 0), out_of_order(kThreads, 0), calls_made(kThreads, 0);
  for (int t = 0; t < kThreads; ++t)
    threads.emplace_back([&, t] {
      std::mt19937 rng(static_cast<unsigned>(100 + t));
      const int calls = 20 + 15 * t;  // threads finish at different times
      std::uint64_t last_round = 0;
      for (int i = 0; i < calls; ++i) {
        Call c;
        c.thread = t;
        c.index = i;
        c.value = static_cast<int>(rng() % 1000);
        gate.call(c, c.value % 5);
        if (c.result != 3 * c.value + t) ++wrong[size_t(t)];
        if (i > 0 && c.round <= last_round) ++out_of_order[size_t(t)];
        last_round = c.round;
        ++calls_made[size_t(t)];
      }
      gate.leave();
    });
  for (auto& th : threads) th.join();
  int total = 0;
  for (int t = 0; t < kThreads; ++t) {
    CHECK(wrong[size_t(t)] == 0);
    CHECK(out_of_order[size_t(t)] == 0);
    total += calls_made[size_t(t)];
  }
  CHECK(static_cast<int>(served.size()) == total);
  CHECK_FALSE(mixed_keys);
  CHECK_FALSE(served_twice);
  CHECK(gate.live() == 0);
  const auto stats = gate.stats();
  CHECK(stats.calls == static_cast<std::uint64_t>(total));
  CHECK(stats.batches == batch_sizes.size());
  // Rounds: while all 8 threads run, each round holds one call per thread. The longest
  // thread makes 125 calls, so there are at least 125 rounds and far fewer than the
  // 580 calls: the calls were served together.
  CHECK(stats.rounds >= 125);
  CHECK(stats.rounds < static_cast<std::uint64_t>(total) / 3);
  CHECK(*std::max_element(batch_sizes.begin(), batch_sizes.end()) > 1);
}

TEST_CASE("a lockstep gate holds a round until every live thread has posted", "[lockstep]") {
  // Two threads: the first posts and must stay blocked until the second posts.
  std::atomic<bool> second_posted{false}, first_served_early{false};
  hsi::LockstepGate<Call> gate(2, [&](int, std::span<Call* const> batch) {
    if (!second_posted.load()) first_served_early = true;
    for (Call* c : batch) c->result = c->value + 1;
  });
  std::atomic<int> first_result{0};
  std::thread first([&] {  // (Catch2's assertions are not thread-safe: results are checked on this thread)
    Call c;
    c.value = 1;
    gate.call(c, 0);
    first_result = c.result;
    gate.leave();
  });
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  Call c;
  c.value = 10;
  second_posted = true;
  gate.call(c, 1);  // another key: the round holds two batches
  CHECK(c.result == 11);
  gate.leave();
  first.join();
  CHECK(first_result.load() == 2);
  CHECK_FALSE(first_served_early.load());
  CHECK(gate.stats().rounds == 1);
  CHECK(gate.stats().batches == 2);
}

TEST_CASE("a lockstep gate: a thread that leaves releases the others, and a serve's error reaches its batch alone", "[lockstep]") {
  hsi::LockstepGate<Call> gate(3, [&](int key, std::span<Call* const> batch) {
    if (key == 7) throw std::runtime_error("batch of key 7 failed");
    for (Call* c : batch) c->result = -c->value;
  });
  std::atomic<int> threw{0}, fine{0};
  std::vector<std::thread> threads;
  for (int t = 0; t < 2; ++t)
    threads.emplace_back([&, t] {
      Call c;
      c.value = 5 + t;
      try {
        gate.call(c, t == 0 ? 7 : 3);
        if (c.result == -c.value) ++fine;
      } catch (const std::runtime_error& e) {
        if (std::string(e.what()).find("key 7") != std::string::npos) ++threw;
      }
      gate.leave();
    });
  // The third participant never calls: whether it leaves before the others post or after
  // (then its leave() serves them), the round completes without it.
  std::this_thread::sleep_for(std::chrono::milliseconds(30));
  gate.leave();
  for (auto& th : threads) th.join();
  CHECK(threw.load() == 1);
  CHECK(fine.load() == 1);
  CHECK(gate.live() == 0);
  Call late;
  CHECK_THROWS_WITH(gate.call(late, 0), Catch::Contains("after every participant left"));
  CHECK_THROWS_WITH(gate.leave(), Catch::Contains("more leaves than participants"));
  CHECK_THROWS_WITH(hsi::LockstepGate<Call>(0, [](int, std::span<Call* const>) {}), Catch::Contains("at least one participant"));
}

TEST_CASE("a lockstep gate serves a chain in order in one round, common tails together; a failed request ends its chain",
          "[lockstep]") {
  // Three threads: chains [10, 3, 5], [3, 5] and [9, 5], where a request of value < 0 fails.
  std::mutex log_mutex;
  std::vector<std::pair<int, int>> log;  // (key, batch size) in serve order
  std::vector<std::vector<int>> order(3);  // per thread: the values served, in order
  hsi::LockstepGate<Call> gate(
      3,
      [&](int key, std::span<Call* const> batch) {
        std::lock_guard lock(log_mutex);
        log.push_back({key, static_cast<int>(batch.size())});
        for (Call* c : batch) {
          c->result = c->value * 2;
          order[size_t(c->thread)].push_back(c->value);
        }
      },
      [](const Call& c) { return c.value < 0; });
  const std::vector<std::vector<int>> keys = {{10, 3, 5}, {3, 5}, {9, 5}};
  std::vector<std::vector<Call>> calls(3);
  std::vector<std::thread> threads;
  for (int t = 0; t < 3; ++t)
    threads.emplace_back([&, t] {
      std::vector<Call>& cs = calls[size_t(t)];
      for (size_t i = 0; i < keys[size_t(t)].size(); ++i) {
        Call c;
        c.thread = t;
        c.value = 100 * t + static_cast<int>(i);
        cs.push_back(c);
      }
      std::vector<Call*> chain;
      for (Call& c : cs) chain.push_back(&c);
      gate.call(std::span<Call* const>(chain), std::span<const int>(keys[size_t(t)]));
      gate.leave();
    });
  for (auto& th : threads) th.join();
  CHECK(gate.stats().rounds == 1);
  for (int t = 0; t < 3; ++t) {
    INFO("thread " << t);
    std::vector<int> expected;
    for (const Call& c : calls[size_t(t)]) {
      CHECK(c.result == 2 * c.value);
      expected.push_back(c.value);
    }
    CHECK(order[size_t(t)] == expected);  // each chain in its own order
  }
  // The longest chain first (key 10), then key 3 for both chains that have it next, then
  // key 9 (the third chain, the last with two left), then key 5 for all three: 4 batches.
  CHECK(log == std::vector<std::pair<int, int>>{{10, 1}, {3, 2}, {9, 1}, {5, 3}});

  // A failed request: the rest of its chain is not served; the other chain goes on.
  hsi::LockstepGate<Call> one(2, [&](int, std::span<Call* const> batch) {
    for (Call* c : batch) c->result = 1;
  }, [](const Call& c) { return c.value < 0; });
  Call a1, a2, b1;
  a1.value = -1;  // fails
  a2.value = 7;
  b1.value = 3;
  std::thread other([&] {
    Call* chain[] = {&b1};
    const int k[] = {2};
    one.call(std::span<Call* const>(chain), std::span<const int>(k));
    one.leave();
  });
  Call* chain[] = {&a1, &a2};
  const int k[] = {1, 2};
  one.call(std::span<Call* const>(chain), std::span<const int>(k));
  one.leave();
  other.join();
  CHECK(a1.result == 1);
  CHECK(a2.result == 0);  // not served
  CHECK(b1.result == 1);
  Call* none[] = {&a1};
  const int two_keys[] = {1, 2};
  CHECK_THROWS_WITH(gate.call(std::span<Call* const>(none), std::span<const int>(two_keys)), Catch::Contains("one key per request"));
}

TEST_CASE("a lockstep gate with a window serves a call without a thread that stays away", "[lockstep]") {
  // Two threads; the second posts only 300 ms later. With a 5 ms window the first
  // thread's two calls are served long before that, each a round of its own.
  std::atomic<bool> second_posted{false};
  std::atomic<int> served_before_second{0};
  hsi::LockstepGate<Call> gate(
      2,
      [&](int, std::span<Call* const> batch) {
        for (Call* c : batch) {
          c->result = c->value + 1;
          if (!second_posted.load()) ++served_before_second;
        }
      },
      nullptr, std::chrono::milliseconds(5));
  std::thread away([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    Call c;
    c.value = 10;
    second_posted = true;
    gate.call(c, 0);
    gate.leave();
  });
  for (int i = 0; i < 2; ++i) {
    Call c;
    c.value = i;
    gate.call(c, 0);
    CHECK(c.result == i + 1);
  }
  CHECK(served_before_second.load() == 2);
  gate.leave();
  away.join();
  const auto stats = gate.stats();
  CHECK(stats.rounds == 3);
  CHECK(stats.window_rounds == 2);
  CHECK_THROWS_WITH(hsi::LockstepGate<Call>(1, [](int, std::span<Call* const>) {}, nullptr, std::chrono::milliseconds(-1)),
                    Catch::Contains("negative window"));
}
