// The viewer's script mode (tests, recordings): a file of commands, one a line (play,
// pause, frames N, seek F, key K, add-handle X Y, remove-handle H, drag H X Y, undo,
// redo, save PATH, screenshot PATH, expect-certified, exit), run one step per drawn
// frame through the same actions as the keyboard and mouse.
#pragma once

#include <string>
#include <vector>

#include "hsi/domain.h"
#include "hsi/timing.h"

namespace hsi::viewer {

struct Options;

struct ScriptStep {
  std::string op;
  std::vector<std::string> args;
  int line = 0;  // in the script file (0: from the command line's shortcuts)
};

// Reads a script; InputError naming the file and line for an unknown command or a
// wrong number of arguments.
std::vector<ScriptStep> parse_script(const std::string& path);
// --script's steps, or the ones --screenshot-after N --screenshot PATH --exit stand for.
std::vector<ScriptStep> script_from_options(const Options& options);

// What a script drives: the viewer's own actions.
class ScriptHost {
 public:
  virtual ~ScriptHost() = default;
  virtual bool playing() const = 0;
  virtual void toggle_play() = 0;
  virtual void pause() = 0;
  virtual int played_frames() const = 0;
  virtual int current_frame() const = 0;
  virtual void seek(int frame) = 0;
  virtual void press_key(int glfw_key) = 0;  // as if pressed, through the keyboard's handler
  virtual void add_handle_at(cd world) = 0;
  virtual void remove_handle(int h) = 0;
  // Drags handle h to `target` and releases it; the refusal's message, or "" once started.
  virtual std::string drag(int h, cd target) = 0;
  virtual bool dragging() const = 0;  // until the final pose is committed
  // Undo (or redo); the refusal's message, or "" when done.
  virtual std::string undo_redo(bool undo) = 0;
  // Sets the timing of the interval leaving keyframe k; the refusal's message, or "".
  virtual std::string set_timing(int k, KeyTiming timing) = 0;
  virtual bool save(const std::string& path) = 0;
  virtual bool shown_certified(std::string* reason) = 0;
  // Whether the frame shown is the current one, solved and drawn.
  virtual bool current_frame_drawn() = 0;
};

class ScriptRunner {
 public:
  explicit ScriptRunner(std::vector<ScriptStep> steps) : steps_(std::move(steps)) {}
  bool empty() const { return steps_.empty(); }

  // Runs steps until one waits for later frames (or the script ends, fails or exits).
  void run(ScriptHost& host);
  // Non-null when the next presented frame is to be written to this PNG; captured()
  // once it is, and the script moves on.
  const std::string* capture_path() const { return capture_ ? &capture_path_ : nullptr; }
  void captured();

  bool quit() const { return quit_; }      // exit, or a step failed
  bool failed() const { return failed_; }  // a step failed (the exit code is 4)

 private:
  std::vector<ScriptStep> steps_;
  size_t pc_ = 0;
  int wait_ = 0, wait_start_ = 0;
  bool failed_ = false, quit_ = false;
  bool capture_ = false;
  std::string capture_path_;
};

}  // namespace hsi::viewer
