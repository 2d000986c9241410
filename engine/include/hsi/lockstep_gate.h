// The gathering point of a lockstep batch (issue #23): the threads of a group (one per
// sequence, each running its own Newton loop unchanged) post their stepper calls here,
// and once every thread still in the group has posted, the calls are served together,
// one batch per kind of call (its key), so that a batched backend makes each kind's
// launches once for the whole group. A thread blocks in call() until its batch has been
// served; a thread that finds the round ready serves it itself (no dispatcher thread,
// no extra hand-over). Threads whose loops end leave(), and the others stop waiting for
// them. With a window, a round is also served once its oldest call has waited that
// long, without the threads still away (a thread building its next Interpolator or
// checking a frame's overlap does not hold the others up): the systems are independent,
// so which calls share a batch changes only how fast they are served, never a result.
// The design it belongs to: bench/results/lockstep_stages_2026-12-07.md.
#pragma once

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <exception>
#include <functional>
#include <mutex>
#include <span>
#include <stdexcept>
#include <vector>

namespace hsi {

template <class Request>
class LockstepGate {
 public:
  // Serves one batch: the requests of one key, in the order their threads posted them.
  // Called by one thread at a time, never with an empty batch. What it throws reaches
  // every caller in that batch (and no other).
  using Serve = std::function<void(int key, std::span<Request* const> batch)>;
  // Whether a served request failed (optional): the rest of its chain is then not served.
  using Failed = std::function<bool(const Request&)>;

  struct Stats {
    std::uint64_t rounds = 0;   // rounds served (every live thread had posted, or the window ran out)
    std::uint64_t window_rounds = 0;  // of them, served when the window ran out
    std::uint64_t batches = 0;  // serve calls
    std::uint64_t calls = 0;    // requests served
    double serve_s = 0;         // wall time inside serve, summed
    // Per key (index = key, for keys ≥ 0): serve calls, requests and wall time in serve.
    std::vector<std::uint64_t> key_batches, key_calls;
    std::vector<double> key_serve_s;
  };

  // window: how long a posted call waits for the threads that have not posted before
  // its round is served without them (zero: until every live thread has posted).
  LockstepGate(int participants, Serve serve, Failed failed = nullptr,
               std::chrono::steady_clock::duration window = std::chrono::steady_clock::duration::zero())
      : live_(participants), serve_(std::move(serve)), failed_(std::move(failed)), window_(window) {
    if (participants < 1) throw std::invalid_argument("LockstepGate: at least one participant");
    if (window < std::chrono::steady_clock::duration::zero()) throw std::invalid_argument("LockstepGate: a negative window");
  }
  LockstepGate(const LockstepGate&) = delete;
  LockstepGate& operator=(const LockstepGate&) = delete;

  // Posts `request` under `key` and returns once it has been served (rethrowing what
  // the serve threw for its batch). A participant makes one call at a time.
  void call(Request& request, int key) {
    Request* chain[1] = {&request};
    const int keys[1] = {key};
    call(std::span<Request* const>(chain), std::span<const int>(keys));
  }

  // Posts a chain: chain[i] under keys[i], served in that order within one round (so a
  // thread's calls whose results it does not wait for travel with the next that it
  // does), and returns once the chain has been served, or has stopped at a request that
  // failed (Failed) or whose batch threw (rethrown here).
  void call(std::span<Request* const> chain, std::span<const int> keys) {
    if (chain.empty() || chain.size() != keys.size()) throw std::invalid_argument("LockstepGate: a chain needs one key per request");
    Slot slot;
    slot.chain = chain;
    slot.keys = keys;
    std::unique_lock lock(mutex_);
    if (live_ <= 0) throw std::logic_error("LockstepGate: call after every participant left");
    slot.posted = std::chrono::steady_clock::now();
    pending_.push_back(&slot);
    while (!slot.done) {
      if (!serving_ && ready(std::chrono::steady_clock::now())) {
        serve_round(lock);
        continue;
      }
      if (serving_ || window_ == std::chrono::steady_clock::duration::zero() || pending_.empty())
        served_.wait(lock);
      else
        served_.wait_until(lock, pending_.front()->posted + window_);
    }
    if (slot.error) std::rethrow_exception(slot.error);
  }

  // The calling participant makes no more calls: the round waits for one thread fewer,
  // and if every other live thread has posted, this one serves them before it goes.
  void leave() {
    std::unique_lock lock(mutex_);
    if (live_ <= 0) throw std::logic_error("LockstepGate: more leaves than participants");
    --live_;
    if (live_ > 0 && !serving_ && !pending_.empty() && static_cast<int>(pending_.size()) == live_) serve_round(lock);
  }

  int live() const {
    std::lock_guard lock(mutex_);
    return live_;
  }
  Stats stats() const {
    std::lock_guard lock(mutex_);
    return stats_;
  }

 private:
  struct Slot {
    std::span<Request* const> chain;
    std::span<const int> keys;
    size_t next = 0;  // the chain's first request not yet served
    std::chrono::steady_clock::time_point posted;
    bool done = false;
    std::exception_ptr error;
    bool open() const { return !error && next < chain.size(); }
  };

  // Whether the pending calls are to be served now: every live participant has posted,
  // or the oldest has waited the window out.
  bool ready(std::chrono::steady_clock::time_point now) const {
    if (pending_.empty()) return false;
    if (static_cast<int>(pending_.size()) >= live_) return true;
    return window_ > std::chrono::steady_clock::duration::zero() && now - pending_.front()->posted >= window_;
  }

  // The pending chains (the lock is held; no other round is being served) are served
  // outside the lock, one batch per step, then their threads are woken; calls posted
  // meanwhile wait for the next round. Each step takes
  // the head key of the chain with the most requests left (ties: the smaller key) and
  // serves every chain whose head has that key, in posting order: chains of different
  // lengths that end alike (a result call after calls not waited for) meet at their
  // common tail, and a round of single calls is one batch per key in key order.
  void serve_round(std::unique_lock<std::mutex>& lock) {
    std::vector<Slot*> round;
    round.swap(pending_);
    ++stats_.rounds;
    if (static_cast<int>(round.size()) < live_) ++stats_.window_rounds;
    serving_ = true;
    lock.unlock();
    std::vector<Request*> batch;
    std::vector<Slot*> members;
    struct Served {
      int key;
      std::uint64_t calls;
      double s;
    };
    std::vector<Served> served;
    for (;;) {
      const Slot* pick = nullptr;
      for (const Slot* s : round) {
        if (!s->open()) continue;
        const size_t left = s->chain.size() - s->next, pick_left = pick ? pick->chain.size() - pick->next : 0;
        if (!pick || left > pick_left || (left == pick_left && s->keys[s->next] < pick->keys[pick->next])) pick = s;
      }
      if (!pick) break;
      const int key = pick->keys[pick->next];
      batch.clear();
      members.clear();
      for (Slot* s : round)
        if (s->open() && s->keys[s->next] == key) {
          batch.push_back(s->chain[s->next]);
          members.push_back(s);
        }
      const auto t0 = std::chrono::steady_clock::now();
      try {
        serve_(key, std::span<Request* const>(batch));
        for (Slot* s : members)
          if (failed_ && failed_(*s->chain[s->next])) s->next = s->chain.size();  // the rest of its chain not served
          else ++s->next;
      } catch (...) {
        const std::exception_ptr e = std::current_exception();
        for (Slot* s : members) s->error = e;
      }
      served.push_back({key, batch.size(), std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count()});
    }
    lock.lock();
    serving_ = false;
    for (Slot* s : round) s->done = true;
    stats_.batches += served.size();
    for (const Served& b : served) {
      stats_.calls += b.calls;
      stats_.serve_s += b.s;
      if (b.key < 0) continue;
      const size_t k = static_cast<size_t>(b.key);
      if (stats_.key_batches.size() <= k) {
        stats_.key_batches.resize(k + 1, 0);
        stats_.key_calls.resize(k + 1, 0);
        stats_.key_serve_s.resize(k + 1, 0.0);
      }
      ++stats_.key_batches[k];
      stats_.key_calls[k] += b.calls;
      stats_.key_serve_s[k] += b.s;
    }
    served_.notify_all();
  }

  mutable std::mutex mutex_;
  std::condition_variable served_;
  std::vector<Slot*> pending_;
  int live_;
  bool serving_ = false;  // a round is being served (outside the lock)
  Serve serve_;
  Failed failed_;
  std::chrono::steady_clock::duration window_;
  Stats stats_;
};

}  // namespace hsi
