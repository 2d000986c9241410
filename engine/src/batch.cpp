// Sequences solved together by a pool of workers (hsi/batch.h): the runs of every
// sequence handed out to threads that keep their own Newton cores and interpolators.
#include "hsi/batch.h"

#include "hsi/lockstep.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <map>
#include <mutex>
#include <thread>

#ifdef _OPENMP
#include <omp.h>
#endif

namespace hsi {

int BatchResult::failed() const {
  return static_cast<int>(std::count_if(sequences.begin(), sequences.end(), [](const BatchSequenceResult& s) { return !s.error.empty(); }));
}

std::vector<std::pair<int, int>> independent_runs(const std::vector<double>& key_times, const std::vector<KeyTiming>& timing,
                                                  const std::vector<double>& times) {
  std::vector<std::pair<int, int>> runs;
  const int n = static_cast<int>(times.size());
  int begin = 0;
  for (int i = 1; i < n; ++i)
    if (keyframe_itself(key_times, timing, times[static_cast<size_t>(i)])) {
      runs.emplace_back(begin, i);
      begin = i;
    }
  if (n > 0) runs.emplace_back(begin, n);
  return runs;
}

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }


struct Run {
  int sequence = 0, begin = 0, end = 0;
};

// Hands out runs so that a worker keeps to one setup (its cores are per setup) and
// one sequence (its interpolator is per sequence) as long as it can: its own
// sequence's next run; else a sequence nobody has started in its setup; else the
// setup with the most frames left per worker on it, where it starts a fresh sequence
// or helps with the last run of the one with the most left. Decides only who solves
// what, never the frames.
class Scheduler {
 public:
  Scheduler(const std::vector<BatchSequence>& sequences, std::vector<Run> runs) : runs_(std::move(runs)), claimed_(runs_.size(), false) {
    seq_runs_.resize(sequences.size());
    started_.assign(sequences.size(), false);
    for (size_t r = 0; r < runs_.size(); ++r) seq_runs_[static_cast<size_t>(runs_[r].sequence)].push_back(static_cast<int>(r));
    std::map<const ShapeSetup*, int> group_of_setup;
    for (size_t s = 0; s < sequences.size(); ++s) {
      const auto [it, added] = group_of_setup.emplace(sequences[s].setup, static_cast<int>(groups_.size()));
      if (added) groups_.emplace_back();
      group_.push_back(it->second);
      groups_[static_cast<size_t>(it->second)].sequences.push_back(static_cast<int>(s));
    }
    for (const Run& r : runs_) groups_[static_cast<size_t>(group_[static_cast<size_t>(r.sequence)])].left += r.end - r.begin;
  }

  // The next run for a worker that last solved a run of `sequence` in `group` (−1: none),
  // or −1 when none is left; updates both.
  int claim(int& sequence, int& group) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (sequence >= 0)
      for (int r : seq_runs_[static_cast<size_t>(sequence)])
        if (!claimed_[static_cast<size_t>(r)]) return take(r, sequence, group);
    if (group >= 0)
      if (const int r = fresh_run(group); r >= 0) return take(r, sequence, group);
    // The setup with the most frames left per worker (this one not counted where it is).
    int best = -1;
    double best_score = 0;
    for (size_t g = 0; g < groups_.size(); ++g) {
      const Group& G = groups_[g];
      const double score = static_cast<double>(G.left) / (1 + G.workers - (static_cast<int>(g) == group ? 1 : 0));
      if (G.left > 0 && score > best_score) best = static_cast<int>(g), best_score = score;
    }
    if (best < 0) return -1;
    if (const int r = fresh_run(best); r >= 0) return take(r, sequence, group, best);
    // Help: the last run of the sequence with the most frames left.
    int help = -1, help_left = 0;
    for (int s : groups_[static_cast<size_t>(best)].sequences) {
      int left = 0;
      for (int r : seq_runs_[static_cast<size_t>(s)])
        if (!claimed_[static_cast<size_t>(r)]) left += runs_[static_cast<size_t>(r)].end - runs_[static_cast<size_t>(r)].begin;
      if (left > help_left) help = s, help_left = left;
    }
    const std::vector<int>& rs = seq_runs_[static_cast<size_t>(help)];
    for (auto it = rs.rbegin(); it != rs.rend(); ++it)
      if (!claimed_[static_cast<size_t>(*it)]) return take(*it, sequence, group, best);
    return -1;  // unreachable: the group has frames left
  }

  // A failed sequence's unclaimed runs are dropped.
  void drop(int sequence) {
    std::lock_guard<std::mutex> lock(mutex_);
    for (int r : seq_runs_[static_cast<size_t>(sequence)])
      if (!claimed_[static_cast<size_t>(r)]) mark(r);
  }
  void leave(int group) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (group >= 0) --groups_[static_cast<size_t>(group)].workers;
  }
  const Run& run(int r) const { return runs_[static_cast<size_t>(r)]; }

 private:
  struct Group {
    std::vector<int> sequences;
    long left = 0;  // frames in unclaimed runs
    int workers = 0;
  };
  int fresh_run(int group) const {
    for (int s : groups_[static_cast<size_t>(group)].sequences)
      if (!started_[static_cast<size_t>(s)] && !seq_runs_[static_cast<size_t>(s)].empty() &&
          !claimed_[static_cast<size_t>(seq_runs_[static_cast<size_t>(s)].front())])
        return seq_runs_[static_cast<size_t>(s)].front();
    return -1;
  }
  void mark(int r) {
    claimed_[static_cast<size_t>(r)] = true;
    const Run& run = runs_[static_cast<size_t>(r)];
    started_[static_cast<size_t>(run.sequence)] = true;
    groups_[static_cast<size_t>(group_[static_cast<size_t>(run.sequence)])].left -= run.end - run.begin;
  }
  int take(int r, int& sequence, int& group, int new_group = -1) {
    mark(r);
    sequence = runs_[static_cast<size_t>(r)].sequence;
    if (new_group >= 0 && new_group != group) {
      if (group >= 0) --groups_[static_cast<size_t>(group)].workers;
      ++groups_[static_cast<size_t>(new_group)].workers;
      group = new_group;
    }
    return r;
  }

  std::mutex mutex_;
  std::vector<Run> runs_;
  std::vector<bool> claimed_, started_;
  std::vector<std::vector<int>> seq_runs_;
  std::vector<int> group_;  // per sequence
  std::vector<Group> groups_;
};

struct Cancelled {};

// The input a sequence needs before any run of it starts; "" when fine.
std::string check_sequence(const BatchSequence& s) {
  if (!s.setup) return "no shape setup";
  if (s.key_times.size() != s.keyframes.size())
    return std::to_string(s.key_times.size()) + " keyframe times for " + std::to_string(s.keyframes.size()) + " keyframes";
  if (s.key_times.size() < 2) return "interpolation needs at least two keyframes (got " + std::to_string(s.key_times.size()) + ")";
  if (s.times.empty()) return "no frame times";
  for (size_t i = 0; i < s.times.size(); ++i)
    if (!(s.times[i] >= s.key_times.front() && s.times[i] <= s.key_times.back()) || (i > 0 && !(s.times[i] > s.times[i - 1])))
      return "frame times must increase within the keyframes' range [" + std::to_string(s.key_times.front()) + ", " +
             std::to_string(s.key_times.back()) + "]; time " + std::to_string(i) + " is " + std::to_string(s.times[i]);
  return "";
}

}  // namespace

BatchResult solve_batch(const std::vector<BatchSequence>& sequences, const BatchOptions& options, const BatchProgress& progress) {
  if (options.workers < 1) throw InputError("a batch needs at least 1 worker (got " + std::to_string(options.workers) + ")");
  if (options.threads_per_worker < 0)
    throw InputError("threads per worker must be 0 (OpenMP's default) or more (got " + std::to_string(options.threads_per_worker) + ")");
  const auto t0 = Clock::now();
  BatchResult out;
  out.sequences.resize(sequences.size());
  std::vector<Run> runs;
  size_t total = 0;
  for (size_t s = 0; s < sequences.size(); ++s) {
    const BatchSequence& q = sequences[s];
    if (std::string why = check_sequence(q); !why.empty()) {
      out.sequences[s].error = q.name + ": " + why;
      out.sequences[s].exception = std::make_exception_ptr(InputError(out.sequences[s].error));
      continue;
    }
    out.sequences[s].frames.resize(q.times.size());
    total += q.times.size();
    for (const auto& [b, e] : independent_runs(q.key_times, q.options.timing, q.times)) runs.push_back({static_cast<int>(s), b, e});
  }
  BatchStats& stats = out.stats;
  stats.runs = static_cast<int>(runs.size());
  stats.workers = std::min(options.workers, stats.runs);
  Scheduler scheduler(sequences, runs);

  std::mutex mutex;                       // guards errors, stats and progress calls
  struct RunError {
    int run = -1;  // the earliest failed run
    std::string message;
    std::exception_ptr exception;
  };
  std::vector<RunError> run_error(sequences.size());
  std::vector<char> run_done(runs.size(), 0);  // written by the run's worker only
  std::atomic<bool> cancel{false};
  std::atomic<size_t> done{0};

  // A run failed: its sequence's other runs are dropped; the earliest run's message is kept
  // (which runs were tried before the drop depends on timing, the earliest failing one does not).
  std::vector<char> seq_failed(sequences.size(), 0);  // guarded by `mutex` (the lockstep groups' drop)
  const auto fail = [&](int r, int sequence, const std::string& what) {
    scheduler.drop(sequence);
    std::lock_guard<std::mutex> lock(mutex);
    seq_failed[static_cast<size_t>(sequence)] = 1;
    RunError& e = run_error[static_cast<size_t>(sequence)];
    if (e.run < 0 || r < e.run) e = {r, what, std::current_exception()};
  };
  // Run r's frames by `interp` (its sequence's), reported as they come; cancelling throws
  // Cancelled out of it.
  const auto solve_run = [&](int r, Interpolator& interp) {
    const Run& run = runs[static_cast<size_t>(r)];
    const BatchSequence& q = sequences[static_cast<size_t>(run.sequence)];
    const std::vector<double> times(q.times.begin() + run.begin, q.times.begin() + run.end);
    std::vector<FrameResult> frames = interp.sequence(times, [&](const FrameResult& f, int i, int) {
      const size_t d = ++done;
      if (!progress) return;
      std::lock_guard<std::mutex> lock(mutex);
      if (!cancel.load() && !progress(f, run.sequence, run.begin + i, d, total)) cancel = true;
      if (cancel.load()) throw Cancelled{};
    });
    // Runs write disjoint ranges of a vector sized before the workers started.
    std::move(frames.begin(), frames.end(), out.sequences[static_cast<size_t>(run.sequence)].frames.begin() + run.begin);
    run_done[static_cast<size_t>(r)] = 1;
  };
  const auto work = [&] {
#ifdef _OPENMP
    if (options.threads_per_worker > 0) omp_set_num_threads(options.threads_per_worker);  // this thread's parallel regions only
#endif
    std::map<const ShapeSetup*, std::unique_ptr<NewtonCore>> cores;
    std::map<const ShapeSetup*, std::unique_ptr<MeshEvaluator>> boundaries;  // made with the cores (null: the setup's)
    std::unique_ptr<Interpolator> interp;
    int interp_sequence = -1, sequence = -1, group = -1;
    int cores_made = 0, built = 0;
    double set_up_s = 0, core_set_up_s = 0;
    for (int r; !cancel.load() && (r = scheduler.claim(sequence, group)) >= 0;) {
      const Run& run = scheduler.run(r);
      const BatchSequence& q = sequences[static_cast<size_t>(run.sequence)];
      try {
        if (interp_sequence != run.sequence) {
          interp.reset();
          interp_sequence = -1;
          const auto ts = Clock::now();
          std::unique_ptr<NewtonCore>& core = cores[q.setup];
          if (!core) {
            core = options.make_core ? options.make_core(*q.setup) : make_cpu_newton_core(q.setup->D_G, q.setup->H);
            if (!core) throw InputError("the core factory made no core");
            ++cores_made;
            if (options.make_boundary) boundaries[q.setup] = options.make_boundary(*q.setup);
            core_set_up_s += seconds_since(ts);
          }
          const auto lent = boundaries.find(q.setup);
          MeshEvaluator* const boundary = lent == boundaries.end() ? nullptr : lent->second.get();
          interp = std::make_unique<Interpolator>(*q.setup, q.key_times, q.keyframes, q.options, borrow_core(*core),
                                                  boundary ? borrow_evaluator(*boundary) : nullptr);
          interp_sequence = run.sequence;
          ++built;
          set_up_s += seconds_since(ts);
        }
        solve_run(r, *interp);
      } catch (const Cancelled&) {
        // The sequence is left unfinished: reported as cancelled below.
      } catch (const std::exception& e) {
        fail(r, run.sequence, e.what());
      } catch (...) {
        fail(r, run.sequence, "unknown error");
      }
    }
    scheduler.leave(group);
    std::lock_guard<std::mutex> lock(mutex);
    stats.cores_made += cores_made;
    stats.interpolators_built += built;
    stats.set_up_s += set_up_s;
    stats.core_set_up_s += core_set_up_s;
  };
  // Lockstep: one group of threads per setup, each thread a system of its group's
  // batched stepper; a thread takes the group's next run (runs in sequence order), keeps
  // its Interpolator while the runs stay in one sequence, and leaves the group when none
  // is left (or the batch is cancelled).
  struct LockGroup {
    const ShapeSetup* setup = nullptr;
    std::vector<int> runs;
    size_t next = 0;
    std::unique_ptr<LockstepBackend> backend;
    std::unique_ptr<LockstepGroup> group;
  };
  std::vector<LockGroup> lock_groups;
  std::string thread_error;                           // likewise: a lockstep thread that could not start
  const auto lockstep_thread = [&](LockGroup& lg, int system) {
#ifdef _OPENMP
    if (options.threads_per_worker > 0) omp_set_num_threads(options.threads_per_worker);
#endif
    std::unique_ptr<MeshEvaluator> boundary;
    std::unique_ptr<Interpolator> interp;
    int interp_sequence = -1, built = 0;
    double set_up_s = 0, core_set_up_s = 0;
    std::unique_ptr<NewtonCore> core;
    try {
      core = make_lockstep_core(*lg.setup, *lg.backend, *lg.group, system);
      const auto tb = Clock::now();
      if (options.make_boundary) boundary = options.make_boundary(*lg.setup);
      core_set_up_s += seconds_since(tb);
      set_up_s += seconds_since(tb);
    } catch (...) {
      lg.group->done();
      throw;
    }
    for (;;) {
      int r = -1;
      {
        std::lock_guard<std::mutex> lock(mutex);
        while (lg.next < lg.runs.size() && seq_failed[static_cast<size_t>(runs[static_cast<size_t>(lg.runs[lg.next])].sequence)]) ++lg.next;
        if (!cancel.load() && lg.next < lg.runs.size()) r = lg.runs[lg.next++];
      }
      if (r < 0) break;
      const Run& run = runs[static_cast<size_t>(r)];
      const BatchSequence& q = sequences[static_cast<size_t>(run.sequence)];
      try {
        if (interp_sequence != run.sequence) {
          interp.reset();
          interp_sequence = -1;
          const auto ts = Clock::now();
          interp = std::make_unique<Interpolator>(*q.setup, q.key_times, q.keyframes, q.options, borrow_core(*core),
                                                  boundary ? borrow_evaluator(*boundary) : nullptr);
          interp_sequence = run.sequence;
          ++built;
          set_up_s += seconds_since(ts);
        }
        solve_run(r, *interp);
      } catch (const Cancelled&) {
        break;
      } catch (const std::exception& e) {
        fail(r, run.sequence, e.what());
      } catch (...) {
        fail(r, run.sequence, "unknown error");
      }
    }
    interp.reset();
    lg.group->done();
    std::lock_guard<std::mutex> lock(mutex);
    stats.interpolators_built += built;
    stats.set_up_s += set_up_s;
    stats.core_set_up_s += core_set_up_s;
  };

  std::vector<std::thread> pool;
  if (options.make_lockstep) {
    if (options.lockstep_systems < 1)
      throw InputError("a lockstep group needs at least 1 system (got " + std::to_string(options.lockstep_systems) + ")");
    if (options.lockstep_window.count() < 0)
      throw InputError("a lockstep window cannot be negative (got " + std::to_string(options.lockstep_window.count()) + " us)");
    std::map<const ShapeSetup*, size_t> group_of;
    for (size_t r = 0; r < runs.size(); ++r) {
      const ShapeSetup* setup = sequences[static_cast<size_t>(runs[r].sequence)].setup;
      const auto [it, added] = group_of.emplace(setup, lock_groups.size());
      if (added) lock_groups.push_back(LockGroup{setup, {}, 0, nullptr, nullptr});
      lock_groups[it->second].runs.push_back(static_cast<int>(r));
    }
    stats.workers = 0;
    for (LockGroup& lg : lock_groups) {
      const int systems = static_cast<int>(std::min<size_t>(static_cast<size_t>(options.lockstep_systems), lg.runs.size()));
      try {
        const auto ts = Clock::now();
        lg.backend = options.make_lockstep(*lg.setup, systems);
        if (!lg.backend) throw InputError("the lockstep factory made no backend");
        lg.group = std::make_unique<LockstepGroup>(lg.backend->batch(), options.lockstep_window);
        stats.cores_made += 1;
        stats.core_set_up_s += seconds_since(ts);
        stats.set_up_s += seconds_since(ts);
      } catch (const std::exception& e) {
        for (int r : lg.runs) fail(r, runs[static_cast<size_t>(r)].sequence, e.what());
        lg.runs.clear();
        continue;
      }
      for (int t = 0; t < systems; ++t) {
        ++stats.workers;
        pool.emplace_back([&, t, g = &lg] {
          try {
            lockstep_thread(*g, t);
          } catch (const std::exception& e) {
            // The thread's core or evaluator could not be made: its group's runs go on
            // without it; runs no thread was left to solve get this message.
            std::lock_guard<std::mutex> lock(mutex);
            if (thread_error.empty()) thread_error = e.what();
          }
        });
      }
    }
  } else {
    for (int w = 0; w < stats.workers; ++w) pool.emplace_back(work);
  }
  for (std::thread& t : pool) t.join();
  lock_groups.clear();  // the groups' backends before the results are read (device work finished)

  stats.cancelled = cancel.load();
  std::vector<char> complete(sequences.size(), 1);
  for (size_t r = 0; r < runs.size(); ++r)
    if (!run_done[r]) complete[static_cast<size_t>(runs[r].sequence)] = 0;
  for (size_t s = 0; s < sequences.size(); ++s) {
    BatchSequenceResult& r = out.sequences[s];
    if (!r.error.empty()) continue;
    if (run_error[s].run >= 0) {
      r.error = sequences[s].name + ": " + run_error[s].message;
      r.exception = run_error[s].exception;
    } else if (!complete[s] && !stats.cancelled && !thread_error.empty()) {
      r.error = sequences[s].name + ": " + thread_error;
      r.exception = std::make_exception_ptr(std::runtime_error(r.error));
    } else if (!complete[s]) {
      r.error = sequences[s].name + ": cancelled before it was finished";
      r.cancelled = true;
    }
    if (!r.error.empty()) r.frames.clear();
  }
  stats.seconds = seconds_since(t0);
  return out;
}

}  // namespace hsi
