// The viewer's script mode: the parser and the runner.
#include "script.h"

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "app.h"

namespace hsi::viewer {

namespace {

double number(const ScriptStep& s, size_t i) {
  try {
    size_t used = 0;
    const double v = std::stod(s.args[i], &used);
    if (used == s.args[i].size() && std::isfinite(v)) return v;
  } catch (const std::exception&) {
  }
  throw InputError("script line " + std::to_string(s.line) + ": '" + s.args[i] + "' is not a number");
}

}  // namespace

std::vector<ScriptStep> parse_script(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError("--script: cannot read " + path);
  std::vector<ScriptStep> steps;
  std::string line;
  int n = 0;
  static const std::vector<std::pair<std::string, size_t>> known = {
      {"play", 0},   {"pause", 0}, {"frames", 1}, {"seek", 1},       {"key", 1},        {"drag", 3},  {"add-handle", 2},
      {"remove-handle", 1}, {"undo", 0}, {"redo", 0}, {"save", 1}, {"screenshot", 1}, {"exit", 0}, {"expect-certified", 0}, {"timing", 2}};
  while (std::getline(in, line)) {
    ++n;
    if (const size_t c = line.find('#'); c != std::string::npos) line.resize(c);
    std::istringstream ss(line);
    ScriptStep s;
    s.line = n;
    if (!(ss >> s.op)) continue;
    for (std::string a; ss >> a;) s.args.push_back(a);
    const auto it = std::find_if(known.begin(), known.end(), [&](const auto& k) { return k.first == s.op; });
    if (it == known.end()) throw InputError(path + ":" + std::to_string(n) + ": unknown script command '" + s.op + "'");
    if (s.args.size() != it->second)
      throw InputError(path + ":" + std::to_string(n) + ": '" + s.op + "' takes " + std::to_string(it->second) + " argument(s)");
    steps.push_back(std::move(s));
  }
  return steps;
}

std::vector<ScriptStep> script_from_options(const Options& o) {
  std::vector<ScriptStep> script;
  if (!o.script.empty()) script = parse_script(o.script);
  if (o.screenshot_after >= 0) {
    script.push_back({"play", {}, 0});
    script.push_back({"frames", {std::to_string(o.screenshot_after)}, 0});
    script.push_back({"pause", {}, 0});
    if (!o.screenshot.empty()) script.push_back({"screenshot", {o.screenshot}, 0});
    if (o.exit_after) script.push_back({"exit", {}, 0});
  } else if (!o.screenshot.empty()) {
    script.push_back({"screenshot", {o.screenshot}, 0});
    if (o.exit_after) script.push_back({"exit", {}, 0});
  } else if (o.exit_after) {
    script.push_back({"exit", {}, 0});
  }
  return script;
}

void ScriptRunner::captured() {
  capture_ = false;
  ++pc_;
}

void ScriptRunner::run(ScriptHost& host) {
  while (pc_ < steps_.size() && !quit_) {
    const ScriptStep& s = steps_[pc_];
    auto fail = [&](const std::string& why) {
      std::fprintf(stderr, "hsi-viewer: script step %zu (%s%s): %s\n", pc_ + 1, s.op.c_str(),
                   s.line ? (", line " + std::to_string(s.line)).c_str() : "", why.c_str());
      failed_ = true;
      quit_ = true;
    };
    if (s.op == "play") {
      if (!host.playing()) host.toggle_play();
    } else if (s.op == "pause") {
      host.pause();
    } else if (s.op == "frames") {
      if (wait_ == 0) {
        wait_ = std::max(1, static_cast<int>(number(s, 0)));
        wait_start_ = host.played_frames();
        return;
      }
      if (host.played_frames() - wait_start_ < wait_ && host.playing()) return;
      wait_ = 0;
    } else if (s.op == "seek") {
      host.seek(static_cast<int>(number(s, 0)));
    } else if (s.op == "key") {
      static const std::vector<std::pair<std::string, int>> names = {
          {"d", GLFW_KEY_D}, {"b", GLFW_KEY_B}, {"c", GLFW_KEY_C}, {"p", GLFW_KEY_P}, {"g", GLFW_KEY_G}, {"h", GLFW_KEY_H}, {"n", GLFW_KEY_N},
          {"l", GLFW_KEY_L}, {"k", GLFW_KEY_K}, {"x", GLFW_KEY_X}, {"space", GLFW_KEY_SPACE}, {"right", GLFW_KEY_RIGHT},
          {"left", GLFW_KEY_LEFT}, {"home", GLFW_KEY_HOME}, {"end", GLFW_KEY_END}, {"f", GLFW_KEY_F}};
      const auto it = std::find_if(names.begin(), names.end(), [&](const auto& k) { return k.first == s.args[0]; });
      if (it == names.end()) return fail("unknown key '" + s.args[0] + "'");
      host.press_key(it->second);
    } else if (s.op == "add-handle") {
      host.add_handle_at({number(s, 0), number(s, 1)});
    } else if (s.op == "remove-handle") {
      host.remove_handle(static_cast<int>(number(s, 0)));
    } else if (s.op == "drag") {
      if (wait_ == 0) {
        const std::string refused = host.drag(static_cast<int>(number(s, 0)), {number(s, 1), number(s, 2)});
        if (!refused.empty()) return fail(refused);
        wait_ = 1;
        return;
      }
      if (host.dragging()) return;  // until the final pose is committed
      wait_ = 0;
    } else if (s.op == "timing") {  // timing K MODE: the interval leaving keyframe K
      const auto mode = parse_key_timing(s.args[1]);
      if (!mode) return fail("unknown timing '" + s.args[1] + "' (expected one of: " + kKeyTimingNames + ")");
      const std::string refused = host.set_timing(static_cast<int>(number(s, 0)), *mode);
      if (!refused.empty()) return fail(refused);
    } else if (s.op == "undo" || s.op == "redo") {
      const std::string refused = host.undo_redo(s.op == "undo");
      if (!refused.empty()) return fail(refused);
    } else if (s.op == "save") {
      if (!host.save(s.args[0])) return fail("save failed");
    } else if (s.op == "expect-certified") {
      std::string reason;
      if (!host.shown_certified(&reason))
        return fail("frame " + std::to_string(host.current_frame()) + " is not certified: " + reason);
    } else if (s.op == "screenshot") {
      // Once the frame shown is the current one, solved and drawn.
      if (!host.current_frame_drawn()) return;
      // Two more frames first: ImGui windows that just opened are sized on their first frame.
      if (wait_ == 0 && !capture_) {
        wait_ = 3;
        return;
      }
      if (wait_ > 1) {
        --wait_;
        return;
      }
      if (!capture_) {
        wait_ = 0;
        capture_ = true;
        capture_path_ = s.args[0];
      }
      return;  // the viewer calls captured() once it is written, then the script moves on
    } else if (s.op == "exit") {
      quit_ = true;
    }
    ++pc_;
  }
}

}  // namespace hsi::viewer
