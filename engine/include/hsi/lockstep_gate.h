// The gathering point of a lockstep batch (issue #23): the threads of a group (one per
// sequence, each running its own Newton loop unchanged) post their stepper calls here,
// and once every thread still in the group has posted, the calls are served together,
// one batch per kind of call (its key), so that a batched backend makes each kind's
// launches once for the whole group. A thread blocks in call() until its batch has been
// served; the last thread to post serves every pending batch itself (no dispatcher
// thread, no extra hand-over). Threads whose loops end leave(), and the others stop
// waiting for them. The design it belongs to: bench/results/lockstep_stages_2026-12-07.md.
#pragma once

#include <algorithm>
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

  struct Stats {
    std::uint64_t rounds = 0;   // times every live thread had posted
    std::uint64_t batches = 0;  // serve calls
    std::uint64_t calls = 0;    // requests served
  };

  LockstepGate(int participants, Serve serve) : live_(participants), serve_(std::move(serve)) {
    if (participants < 1) throw std::invalid_argument("LockstepGate: at least one participant");
  }
  LockstepGate(const LockstepGate&) = delete;
  LockstepGate& operator=(const LockstepGate&) = delete;

  // Posts `request` under `key` and returns once it has been served (rethrowing what
  // the serve threw for its batch). A participant makes one call at a time.
  void call(Request& request, int key) {
    Slot slot{&request, key, false, nullptr};
    std::unique_lock lock(mutex_);
    if (live_ <= 0) throw std::logic_error("LockstepGate: call after every participant left");
    pending_.push_back(&slot);
    if (static_cast<int>(pending_.size()) == live_) serve_round(lock);
    else served_.wait(lock, [&] { return slot.done; });
    if (slot.error) std::rethrow_exception(slot.error);
  }

  // The calling participant makes no more calls: the round waits for one thread fewer,
  // and if every other live thread has posted, this one serves them before it goes.
  void leave() {
    std::unique_lock lock(mutex_);
    if (live_ <= 0) throw std::logic_error("LockstepGate: more leaves than participants");
    --live_;
    if (live_ > 0 && !pending_.empty() && static_cast<int>(pending_.size()) == live_) serve_round(lock);
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
    Request* request;
    int key;
    bool done = false;
    std::exception_ptr error;
  };

  // Every live participant has posted (the lock is held, and no one posts until the
  // round is served, since each waits on its own slot): the pending requests, grouped
  // by key in increasing key order and by posting order within a key, are served
  // outside the lock, then their threads are woken.
  void serve_round(std::unique_lock<std::mutex>& lock) {
    std::vector<Slot*> round;
    round.swap(pending_);
    ++stats_.rounds;
    lock.unlock();
    std::stable_sort(round.begin(), round.end(), [](const Slot* a, const Slot* b) { return a->key < b->key; });
    std::vector<Request*> batch;
    std::uint64_t batches = 0;
    for (size_t i = 0; i < round.size();) {
      size_t j = i;
      batch.clear();
      while (j < round.size() && round[j]->key == round[i]->key) batch.push_back(round[j++]->request);
      try {
        serve_(round[i]->key, std::span<Request* const>(batch));
      } catch (...) {
        const std::exception_ptr e = std::current_exception();
        for (size_t k = i; k < j; ++k) round[k]->error = e;
      }
      ++batches;
      i = j;
    }
    lock.lock();
    for (Slot* s : round) s->done = true;
    stats_.batches += batches;
    stats_.calls += round.size();
    served_.notify_all();
  }

  mutable std::mutex mutex_;
  std::condition_variable served_;
  std::vector<Slot*> pending_;
  int live_;
  Serve serve_;
  Stats stats_;
};

}  // namespace hsi
