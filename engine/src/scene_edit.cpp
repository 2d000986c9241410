// Editing a scene's handles and keyframes: the rules, their messages, undo and redo.
#include "hsi/scene_edit.h"

#include <algorithm>
#include <cstdio>

namespace hsi {

namespace {

EditOutcome refused(std::string message, bool error) { return {false, std::move(message), error, -1}; }
EditOutcome accepted(std::string message, int index) { return {true, std::move(message), false, index}; }

std::string no_handle(int h, size_t count) {
  return "no handle " + std::to_string(h) + " (the scene has " + std::to_string(count) + ")";
}

}  // namespace

SceneEditor::SceneEditor(Scene scene, const SceneEditOptions& options) : scene_(std::move(scene)), options_(options) {
  const std::string where = scene_.source.empty() ? "scene" : scene_.source;
  if (!scene_.cage) throw InputError(where + ": editing needs the scene's cage (scene_setup gives it one)");
  const Eigen::Index n = basis_size(*scene_.cage);
  for (size_t k = 0; k < scene_.keyframes.size(); ++k) {
    const auto& c = scene_.keyframes[k].coefficients;
    if (!c || c->phi.size() != n || c->psi.size() != n)
      throw InputError(where + ": keyframe " + std::to_string(k) +
                       " has no coefficients over the scene's cage: solve the keyframes first (solve_scene_keyframes)");
  }
  if (options_.max_undo < 0) throw InputError("SceneEditOptions::max_undo must be ≥ 0");
}

void SceneEditor::push_undo(SceneEditState before) {
  undo_.push_back(std::move(before));
  while (undo_.size() > static_cast<size_t>(options_.max_undo)) undo_.erase(undo_.begin());
  redo_.clear();
  modified_ = true;
}

EditOutcome SceneEditor::add_keyframe(const EditFrame& at) {
  if (pose_) return {};
  auto& keys = scene_.keyframes;
  const int key = at.keyframe;
  const std::string frame = "frame " + std::to_string(at.index);
  if (key >= 0 && key + 1 < static_cast<int>(keys.size()))
    return refused(frame + " is keyframe " + std::to_string(key) +
                       " already: drag its handles to pose it, or add a keyframe between keyframes",
                   false);
  Keyframe k;
  if (key >= 0) {  // at the last keyframe: a new keyframe one time unit later, posed like it
    k = keys.back();
    k.time = keys.back().time + 1.0;
  } else {
    if (!at.solved) return refused(frame + " is still being solved: add the keyframe when it is shown", true);
    if (!at.certified) return refused(frame + " is not certified: it cannot become a keyframe", true);
    k.time = at.time;
    k.coefficients = *at.solved;
    k.targets = map_points(*scene_.cage, *at.solved, scene_.handles);
  }
  push_undo(snapshot());
  const auto pos = std::upper_bound(keys.begin(), keys.end(), k.time, [](double t, const Keyframe& x) { return t < x.time; });
  const int index = static_cast<int>(pos - keys.begin());
  const double time = k.time;
  keys.insert(pos, std::move(k));
  return accepted("added keyframe " + std::to_string(index) + " at t = " + std::to_string(time), index);
}

EditOutcome SceneEditor::remove_keyframe(const EditFrame& at) {
  auto& keys = scene_.keyframes;
  if (at.keyframe < 0 || at.keyframe >= static_cast<int>(keys.size()) || pose_)
    return refused("the current frame is not a keyframe: step to one (the timeline's marks) to remove it", false);
  if (keys.size() <= 1) return refused("the last keyframe cannot be removed", true);
  push_undo(snapshot());
  keys.erase(keys.begin() + at.keyframe);
  return accepted("removed keyframe " + std::to_string(at.keyframe), at.keyframe);
}

EditOutcome SceneEditor::add_handle(const std::optional<cd>& rest) {
  if (pose_) return {};
  if (!rest) return refused("no handle added: click on the shape", false);
  push_undo(snapshot());
  scene_.handles.push_back(*rest);
  for (Keyframe& k : scene_.keyframes) {  // every keyframe keeps its pose: the handle's target is where it is
    if (k.targets.size() + 1 == scene_.handles.size())
      k.targets.push_back(map_points(*scene_.cage, *k.coefficients, std::span<const cd>(&*rest, 1))[0]);
    else
      k.targets = map_points(*scene_.cage, *k.coefficients, scene_.handles);
  }
  char where[96];
  std::snprintf(where, sizeof where, " at rest point (%.3f, %.3f)", rest->real(), rest->imag());
  const int index = static_cast<int>(scene_.handles.size()) - 1;
  return accepted("added handle " + std::to_string(index) + where, index);
}

EditOutcome SceneEditor::remove_handle(int h) {
  if (pose_) return {};
  if (h < 0 || h >= static_cast<int>(scene_.handles.size())) return refused(no_handle(h, scene_.handles.size()), true);
  push_undo(snapshot());
  scene_.handles.erase(scene_.handles.begin() + h);
  for (Keyframe& k : scene_.keyframes)
    if (k.targets.size() == scene_.handles.size() + 1) k.targets.erase(k.targets.begin() + h);
  return accepted("removed handle " + std::to_string(h), h);
}

EditOutcome SceneEditor::set_timing(int k, KeyTiming timing) {
  if (pose_) return {};
  auto& keys = scene_.keyframes;
  const int count = static_cast<int>(keys.size());
  if (k < 0 || k >= count)
    return refused("no keyframe " + std::to_string(k) + " (the scene has " + std::to_string(count) + ")", true);
  if (k + 1 == count)
    return refused("keyframe " + std::to_string(k) + " is the last: no interval leaves it, so it has no timing", false);
  const std::string interval = "keyframe " + std::to_string(k) + " to " + std::to_string(k + 1);
  if (keys[static_cast<size_t>(k)].timing == timing)
    return refused(interval + " is " + std::string(to_string(timing)) + " already", false);
  push_undo(snapshot());
  keys[static_cast<size_t>(k)].timing = timing;
  return accepted(interval + ": " + std::string(to_string(timing)) + " timing", k);
}

EditOutcome SceneEditor::begin_pose(int h, const EditFrame& at) {
  if (pose_) return {};
  if (at.keyframe < 0 || at.keyframe >= static_cast<int>(scene_.keyframes.size()))
    return refused("handles are posed at keyframes: pause and step to a keyframe (Page Up / Page Down), or add one here (K)",
                   false);
  if (h < 0 || h >= static_cast<int>(scene_.handles.size())) return refused(no_handle(h, scene_.handles.size()), true);
  HandlePose p;
  p.handle = h;
  p.keyframe = at.keyframe;
  p.latest = *scene_.keyframes[static_cast<size_t>(at.keyframe)].coefficients;
  p.targets = map_points(*scene_.cage, p.latest, scene_.handles);  // every other handle stays where it is
  pose_before_ = snapshot();
  pose_ = std::move(p);
  return accepted("", h);
}

bool SceneEditor::move_pose_target(cd target) {
  if (!pose_) return false;
  cd& t = pose_->targets[static_cast<size_t>(pose_->handle)];
  if (std::abs(target - t) < 1e-12) return false;
  t = target;
  return true;
}

void SceneEditor::pose_solved(const KeyframeResult& result) {
  if (!pose_) return;
  if (result.certified) pose_->latest = result.map;  // always, unless the start was not: never a folding map
  pose_->status = result.message;
}

EditOutcome SceneEditor::commit_pose(const KeyframeResult& final, std::vector<cd> targets) {
  if (!pose_) return {};
  pose_solved(final);
  push_undo(std::move(*pose_before_));
  const int key = pose_->keyframe;
  Keyframe& k = scene_.keyframes[static_cast<size_t>(key)];
  k.coefficients = std::move(pose_->latest);
  k.targets = std::move(targets);
  cancel_pose();
  EditOutcome out = accepted("keyframe " + std::to_string(key) + ": " + final.message, key);
  out.error = !final.reached;
  return out;
}

void SceneEditor::cancel_pose() {
  pose_.reset();
  pose_before_.reset();
}

EditOutcome SceneEditor::step_history(std::vector<SceneEditState>& from, std::vector<SceneEditState>& to, const char* what) {
  if (pose_) return {};
  if (from.empty()) return refused(std::string("nothing to ") + what, true);
  to.push_back(snapshot());
  scene_.handles = std::move(from.back().handles);
  scene_.keyframes = std::move(from.back().keyframes);
  from.pop_back();
  modified_ = true;
  return accepted(what, -1);
}

EditOutcome SceneEditor::undo() { return step_history(undo_, redo_, "undo"); }
EditOutcome SceneEditor::redo() { return step_history(redo_, undo_, "redo"); }

}  // namespace hsi
