// The viewer's solver thread: live interpolation and keyframe posing off the UI thread.
//
// Interpolation: the timeline is `rate` frames per unit of scene time over the
// keyframes' range. The UI says which frame it shows now (request()); the worker
// solves that frame first, warm-started from the neighbouring solved frame (the
// previous one in the playback direction), then keeps solving ahead of it, so
// playback runs from the cache once the worker is ahead and a scrub restarts from
// the new place after at most the frame in progress. Solved frames are cached until
// the keyframes change (set_keyframes() starts a new generation).
//
// Posing: pose() queues a point-to-point solve (author_keyframe, certified so it
// never folds); while a handle is dragged only the newest request is solved
// (a short solve per mouse move), the final one on release runs to convergence.
#pragma once

#include <atomic>
#include <condition_variable>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "hsi/interpolation.h"
#include "hsi/keyframes.h"
#include "hsi/runtime/backend.h"
#include "hsi/shape_setup.h"

namespace hsi::viewer {

struct SolvedFrame {
  int index = 0;
  double t = 0;
  HarmonicMap map;
  Eigen::VectorXd x;  // warm start for the neighbours
  bool keyframe = false, certified = false, converged = false;
  NewtonStop stop = NewtonStop::Converged;  // why the solve stopped (FrameResult::stop)
  int iterations = 0;
  double ms = 0, energy = 0;
  Distortion distortion;            // sampled at the certificate's breakpoints
  Distortion distortion_certified;  // the certificate's bounds (NaN when not certified)
  std::string message;  // the certificate's reason when not certified
};

struct PoseRequest {
  uint64_t id = 0;  // increasing; results carry it
  int keyframe = -1;
  std::vector<cd> handles, targets;
  HarmonicMap start;
  bool final = false;  // run to convergence (on release) rather than a short interactive solve
};

struct PoseResult {
  uint64_t id = 0;
  int keyframe = -1;
  bool final = false;
  std::vector<cd> targets;
  KeyframeResult result;
  std::string error;  // an exception's message (e.g. a handle off the shape)
};

class Solver {
 public:
  // backend: the Newton core (hsi/runtime/backend.h); cuda that cannot be had throws
  // runtime::BackendUnavailable, auto may fall back to the CPU (backend_choice() says why).
  Solver(std::shared_ptr<const ShapeSetup> setup, double rate, runtime::Backend backend, InterpolationOptions options = {});
  ~Solver();
  Solver(const Solver&) = delete;
  Solver& operator=(const Solver&) = delete;

  // New keyframes (times increasing, certified maps): drops every solved frame.
  // timings: one per keyframe (timing.h), or empty for linear everywhere.
  void set_keyframes(std::vector<double> times, std::vector<HarmonicMap> maps, std::vector<KeyTiming> timings = {});
  int frame_count() const;
  double time_of(int frame) const;
  int frame_at(double t) const;  // nearest frame
  double t_begin() const;
  double t_end() const;
  uint64_t generation() const;

  // The frame shown now and the playback direction (+1 / −1) for solving ahead.
  void request(int frame, int direction = 1);
  std::shared_ptr<const SolvedFrame> get(int frame) const;
  // Per frame: 0 not solved, 1 certified, 2 not certified, 3 certified but not
  // converged (Newton stopped at its iteration limit) (for the timeline).
  std::vector<uint8_t> solved_states() const;

  void pose(PoseRequest request);
  std::optional<PoseResult> take_pose_result();
  bool posing() const;  // a pose request is queued or running

  std::string backend() const { return backend_; }
  const runtime::BackendChoice& backend_choice() const { return choice_; }
  // The solve time of the most recent frame, ms.
  double last_solve_ms() const { return last_ms_.load(); }

 private:
  void run();
  std::unique_ptr<NewtonCore> make_core() const;
  int next_frame_locked() const;

  std::shared_ptr<const ShapeSetup> setup_;
  double rate_;
  runtime::BackendChoice choice_;  // fixed at construction: every later core is of choice_.used
  InterpolationOptions options_;
  std::string backend_;

  mutable std::mutex mutex_;
  std::condition_variable wake_;
  bool stop_ = false;
  uint64_t generation_ = 0;
  std::vector<double> times_;
  std::vector<HarmonicMap> maps_;
  std::vector<KeyTiming> timings_;
  bool rebuild_ = false;
  int count_ = 1;
  int requested_ = 0, direction_ = 1;
  std::vector<std::shared_ptr<const SolvedFrame>> frames_;
  std::optional<PoseRequest> pose_;
  bool pose_running_ = false;
  std::deque<PoseResult> pose_results_;
  std::atomic<double> last_ms_{0};
  std::thread thread_;
};

}  // namespace hsi::viewer
