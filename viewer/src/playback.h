// The viewer's playback: the current timeline frame, play / pause, speed, loop,
// stepping and jumping between keyframes, and advancing in real time or in lockstep
// with the solver (one solved frame per drawn frame).
#pragma once

#include <chrono>
#include <vector>

#include "hsi/scene_io.h"
#include "solver.h"

namespace hsi::viewer {

class Playback {
 public:
  using Clock = std::chrono::steady_clock;

  // The solver gives the timeline; `keyframes` are the scene's (read at each call).
  Playback(const Solver& solver, const std::vector<Keyframe>& keyframes, double rate, bool lockstep);

  bool loop = true;
  double speed = 1;  // playback speed, ×

  int current() const { return cur_; }
  bool playing() const { return playing_; }
  int played_frames() const { return played_; }  // frames advanced by playback so far
  // The keyframe whose frame `frame` is (−1: none).
  int keyframe_at(int frame) const;

  void toggle_play();  // (needs two frames or more)
  void pause() { playing_ = false; }
  void step(int delta);  // pauses; wraps when looping
  void seek(int frame);  // pauses; clamped to the timeline
  void to_keyframe(bool next);  // previous / next keyframe's frame (the ends when none)
  void clamp_to_timeline();     // after the keyframes (so the timeline) changed

  // One drawn frame, dt seconds after the last: advances while playing, in real time
  // (frames wait until solved) or, in lockstep, once the current frame has been drawn.
  void advance(double dt, bool current_drawn);
  // Frames advanced in the last second (while playing).
  double frames_per_second();

 private:
  bool advance_one();

  const Solver& solver_;
  const std::vector<Keyframe>& keyframes_;
  double rate_;
  bool lockstep_;
  int cur_ = 0;
  bool playing_ = false;
  double acc_ = 0;
  int played_ = 0;
  std::vector<Clock::time_point> advance_times_;  // for the playback rate
};

}  // namespace hsi::viewer
