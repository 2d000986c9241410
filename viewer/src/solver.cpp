// The viewer's solver thread (see solver.h).
#include "solver.h"

#include <algorithm>
#include <chrono>
#include <cmath>

namespace hsi::viewer {

Solver::Solver(std::shared_ptr<const ShapeSetup> setup, double rate, runtime::Backend backend, InterpolationOptions options)
    : setup_(std::move(setup)), rate_(rate), options_(options) {
  if (!(rate_ > 0)) throw InputError("viewer: the frame rate must be positive");
  runtime::NewtonCoreChoice first = runtime::make_newton_core(*setup_, backend);
  choice_ = first.choice;
  backend_ = first.core->name();
  thread_ = std::thread([this] { run(); });
}

Solver::~Solver() {
  {
    std::lock_guard lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();  // after the solve in progress, if any
}

std::unique_ptr<NewtonCore> Solver::make_core() const { return runtime::make_newton_core(*setup_, choice_.used).core; }

void Solver::set_keyframes(std::vector<double> times, std::vector<HarmonicMap> maps, std::vector<KeyTiming> timings) {
  if (times.empty() || times.size() != maps.size()) throw InputError("viewer: keyframes need a time and a map each");
  {
    std::lock_guard lock(mutex_);
    times_ = std::move(times);
    maps_ = std::move(maps);
    timings_ = std::move(timings);
    ++generation_;
    rebuild_ = true;
    count_ = std::max(1, static_cast<int>(std::lround((times_.back() - times_.front()) * rate_)) + 1);
    frames_.assign(static_cast<size_t>(count_), nullptr);
    requested_ = std::clamp(requested_, 0, count_ - 1);
  }
  wake_.notify_all();
}

int Solver::frame_count() const {
  std::lock_guard lock(mutex_);
  return count_;
}
double Solver::t_begin() const {
  std::lock_guard lock(mutex_);
  return times_.empty() ? 0 : times_.front();
}
double Solver::t_end() const {
  std::lock_guard lock(mutex_);
  return times_.empty() ? 0 : times_.back();
}
uint64_t Solver::generation() const {
  std::lock_guard lock(mutex_);
  return generation_;
}

double Solver::time_of(int frame) const {
  std::lock_guard lock(mutex_);
  if (times_.empty()) return 0;
  if (frame >= count_ - 1) return times_.back();  // the last frame is the last keyframe exactly
  return times_.front() + std::max(0, frame) / rate_;
}

int Solver::frame_at(double t) const {
  std::lock_guard lock(mutex_);
  if (times_.empty()) return 0;
  return std::clamp(static_cast<int>(std::lround((t - times_.front()) * rate_)), 0, count_ - 1);
}

void Solver::request(int frame, int direction) {
  {
    std::lock_guard lock(mutex_);
    const int f = std::clamp(frame, 0, count_ - 1);
    const int d = direction < 0 ? -1 : 1;
    if (f == requested_ && d == direction_) return;
    requested_ = f;
    direction_ = d;
  }
  wake_.notify_all();
}

std::shared_ptr<const SolvedFrame> Solver::get(int frame) const {
  std::lock_guard lock(mutex_);
  if (frame < 0 || frame >= count_) return nullptr;
  return frames_[static_cast<size_t>(frame)];
}

std::vector<uint8_t> Solver::solved_states() const {
  std::lock_guard lock(mutex_);
  std::vector<uint8_t> s(frames_.size(), 0);
  for (size_t i = 0; i < frames_.size(); ++i)
    if (frames_[i]) s[i] = !frames_[i]->certified ? 2 : frames_[i]->converged ? 1 : 3;
  return s;
}

void Solver::pose(PoseRequest request) {
  {
    std::lock_guard lock(mutex_);
    pose_ = std::move(request);  // only the newest matters
  }
  wake_.notify_all();
}

std::optional<PoseResult> Solver::take_pose_result() {
  std::lock_guard lock(mutex_);
  if (pose_results_.empty()) return std::nullopt;
  PoseResult r = std::move(pose_results_.front());
  pose_results_.pop_front();
  return r;
}

bool Solver::posing() const {
  std::lock_guard lock(mutex_);
  return pose_.has_value() || pose_running_ || !pose_results_.empty();
}

// The requested frame if unsolved, else the first unsolved one ahead of it in the
// playback direction (wrapping around); −1 when every frame is solved.
int Solver::next_frame_locked() const {
  if (rebuild_ || frames_.empty()) return -1;
  for (int k = 0; k < count_; ++k) {
    const int j = ((requested_ + k * direction_) % count_ + count_) % count_;
    if (!frames_[static_cast<size_t>(j)]) return j;
  }
  return -1;
}

void Solver::run() {
  std::unique_ptr<Interpolator> interp;
  std::vector<double> times;
  std::vector<HarmonicMap> maps;
  std::unique_lock lock(mutex_);
  for (;;) {
    wake_.wait(lock, [&] { return stop_ || pose_ || rebuild_ || next_frame_locked() >= 0; });
    if (stop_) return;

    if (pose_) {
      PoseRequest req = std::move(*pose_);
      pose_.reset();
      pose_running_ = true;
      lock.unlock();
      PoseResult res;
      res.id = req.id;
      res.keyframe = req.keyframe;
      res.final = req.final;
      res.targets = req.targets;
      try {
        KeyframeOptions ko;
        if (!req.final) {  // interactive: a short solve that follows the mouse
          ko.stages = 1;
          ko.newton.max_iterations = 8;
          ko.newton.tolerance = 1e-7;
        } else {
          ko.stages = 2;
        }
        res.result = author_keyframe(*setup_, req.handles, req.targets, req.start, ko);
      } catch (const std::exception& e) {
        res.error = e.what();
      }
      lock.lock();
      pose_results_.push_back(std::move(res));
      pose_running_ = false;
      continue;
    }

    if (rebuild_) {
      times = times_;
      maps = maps_;
      InterpolationOptions options = options_;
      options.timing = timings_;
      const uint64_t gen = generation_;
      rebuild_ = false;
      lock.unlock();
      std::unique_ptr<Interpolator> built;
      std::string error;
      try {
        if (times.size() >= 2) built = std::make_unique<Interpolator>(*setup_, times, maps, options, make_core());
      } catch (const std::exception& e) {
        error = e.what();
      }
      lock.lock();
      if (gen != generation_) continue;  // changed again meanwhile
      interp = std::move(built);
      if (!error.empty()) {  // keyframes the interpolator refuses: every frame says why
        for (int i = 0; i < count_; ++i) {
          auto f = std::make_shared<SolvedFrame>();
          f->index = i;
          f->map = maps.front();
          f->message = error;
          frames_[static_cast<size_t>(i)] = std::move(f);
        }
      }
      continue;
    }

    const int i = next_frame_locked();
    if (i < 0) continue;
    const uint64_t gen = generation_;
    Eigen::VectorXd warm;
    for (int d : {-direction_, direction_}) {
      const int j = i + d;
      if (j >= 0 && j < count_ && frames_[static_cast<size_t>(j)] && frames_[static_cast<size_t>(j)]->x.size() > 0) {
        warm = frames_[static_cast<size_t>(j)]->x;
        break;
      }
    }
    const double t = i >= count_ - 1 ? times.back() : times.front() + i / rate_;
    lock.unlock();
    auto f = std::make_shared<SolvedFrame>();
    f->index = i;
    f->t = t;
    if (!interp) {  // one keyframe: it is every frame
      f->map = maps.front();
      f->keyframe = f->certified = f->converged = true;
      f->message = "one keyframe: add another to interpolate";
    } else {
      try {
        FrameResult r = interp->frame(t, warm);
        f->map = std::move(r.map);
        f->x = std::move(r.x);
        f->keyframe = r.keyframe;
        f->certified = r.certified;
        f->converged = r.converged;
        f->stop = r.stop;
        f->iterations = r.iterations;
        f->ms = r.ms;
        f->energy = r.energy;
        f->distortion = r.distortion;
        f->distortion_certified = r.distortion_certified;
        f->message = r.certified ? r.message : r.certificate.reason;
        last_ms_.store(r.ms);
      } catch (const std::exception& e) {
        f->map = maps.front();
        f->message = e.what();
      }
    }
    lock.lock();
    if (gen == generation_ && i < count_) frames_[static_cast<size_t>(i)] = std::move(f);
  }
}

}  // namespace hsi::viewer
