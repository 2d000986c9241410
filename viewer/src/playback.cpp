// The viewer's playback: time, speed, loop, stepping.
#include "playback.h"

#include <algorithm>

namespace hsi::viewer {

Playback::Playback(const Solver& solver, const std::vector<Keyframe>& keyframes, double rate, bool lockstep)
    : solver_(solver), keyframes_(keyframes), rate_(rate), lockstep_(lockstep) {}

int Playback::keyframe_at(int frame) const {
  for (size_t k = 0; k < keyframes_.size(); ++k)
    if (solver_.frame_at(keyframes_[k].time) == frame) return static_cast<int>(k);
  return -1;
}

void Playback::toggle_play() {
  if (solver_.frame_count() < 2) return;
  playing_ = !playing_;
  if (playing_ && !loop && cur_ >= solver_.frame_count() - 1) cur_ = 0;
  acc_ = 0;
}

void Playback::step(int delta) {
  playing_ = false;
  const int n = solver_.frame_count();
  cur_ = loop ? ((cur_ + delta) % n + n) % n : std::clamp(cur_ + delta, 0, n - 1);
}

void Playback::seek(int frame) {
  playing_ = false;
  cur_ = std::clamp(frame, 0, solver_.frame_count() - 1);
}

void Playback::to_keyframe(bool next) {
  playing_ = false;
  int best = next ? solver_.frame_count() - 1 : 0;
  for (const Keyframe& k : keyframes_) {
    const int f = solver_.frame_at(k.time);
    if (next && f > cur_) best = std::min(best, f);
    if (!next && f < cur_) best = std::max(best, f);
  }
  cur_ = best;
}

void Playback::clamp_to_timeline() { cur_ = std::clamp(cur_, 0, solver_.frame_count() - 1); }

bool Playback::advance_one() {
  const int n = solver_.frame_count();
  int next = cur_ + 1;
  if (next >= n) {
    if (!loop) {
      playing_ = false;
      return false;
    }
    next = 0;
  }
  if (keyframe_at(next) < 0 && !solver_.get(next)) return false;
  cur_ = next;
  ++played_;
  advance_times_.push_back(Clock::now());
  return true;
}

void Playback::advance(double dt, bool current_drawn) {
  if (!playing_ || solver_.frame_count() <= 1) return;
  if (lockstep_) {
    if (current_drawn) advance_one();
    return;
  }
  acc_ += std::min(dt, 0.25) * speed * rate_;
  while (acc_ >= 1 && playing_) {
    if (!advance_one()) {
      acc_ = std::min(acc_, 1.0);
      break;
    }
    acc_ -= 1;
  }
}

double Playback::frames_per_second() {
  const auto now = Clock::now();
  while (!advance_times_.empty() && now - advance_times_.front() > std::chrono::seconds(1))
    advance_times_.erase(advance_times_.begin());
  return playing_ ? static_cast<double>(advance_times_.size()) : 0;
}

}  // namespace hsi::viewer
