// Editing a scene's handles and keyframes, with undo and redo: the rules a user can
// break (a keyframe where there is one already, a frame still being solved or not
// certified, the last keyframe, a click off the shape) and the message each refusal
// gives. The viewer calls these; any front-end that edits a scene would.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "hsi/keyframes.h"
#include "hsi/scene_io.h"

namespace hsi {

// What an undo step restores: everything editing changes.
struct SceneEditState {
  std::vector<cd> handles;
  std::vector<Keyframe> keyframes;
};

// The outcome of an edit. Refused edits change nothing; `message` is what the user is
// told either way (empty: nothing to say, e.g. an edit asked for during a pose).
struct EditOutcome {
  bool done = false;
  std::string message;
  bool error = false;  // shown as an error rather than a note
  int index = -1;      // the keyframe or handle added, removed or posed
};

// The timeline frame an edit is asked at, as the front-end shows it.
struct EditFrame {
  int index = 0;                        // the frame's number (named in messages)
  double time = 0;                      // its scene time
  int keyframe = -1;                    // the keyframe shown at this frame; −1: none
  const HarmonicMap* solved = nullptr;  // the frame's solved map; null while it is solved
  bool certified = false;               // whether `solved` is certified locally injective
};

// A handle being dragged at a keyframe: the point-to-point solves (author_keyframe)
// run outside, and report back through SceneEditor::pose_solved / commit_pose.
struct HandlePose {
  int handle = -1, keyframe = -1;
  std::vector<cd> targets;  // one per handle: the dragged one follows the mouse, the others stay
  HarmonicMap latest;       // the latest certified pose (starts as the keyframe's map)
  std::string status;       // the latest solve's message
};

struct SceneEditOptions {
  int max_undo = 200;  // undo steps kept (the oldest are dropped)
};

class SceneEditor {
 public:
  // Every keyframe needs coefficients (solve_scene_keyframes) and the scene a cage:
  // InputError naming the keyframe otherwise.
  explicit SceneEditor(Scene scene, const SceneEditOptions& options = {});

  const Scene& scene() const { return scene_; }

  // At `at.keyframe` if it is not the last keyframe: refused. At the last keyframe: a
  // copy of it one time unit later. Elsewhere: the frame's solved map becomes a
  // keyframe at its time (refused while it is being solved or if it is not certified),
  // with targets where it sends the handles. `index` is the new keyframe's.
  EditOutcome add_keyframe(const EditFrame& at);
  // Removes the keyframe at `at.keyframe`; refused off a keyframe and for the last one.
  EditOutcome remove_keyframe(const EditFrame& at);
  // A handle at a rest point (InverseMap::rest_point of the click); nullopt: the click
  // missed the shape, refused. Every keyframe keeps its pose: the new handle's target
  // is where the keyframe's map sends it.
  EditOutcome add_handle(const std::optional<cd>& rest_point);
  // Removes handle h and its target in every keyframe.
  EditOutcome remove_handle(int h);

  // Dragging handle h at `at.keyframe` (refused off a keyframe and for a handle that is
  // not there). Other edits and undo/redo are refused until the pose is committed or
  // cancelled.
  EditOutcome begin_pose(int h, const EditFrame& at);
  // Moves the dragged handle's target; false if it did not move (no solve needed).
  bool move_pose_target(cd target);
  // A solve of the pose: its map is kept only if certified (never a folding map).
  void pose_solved(const KeyframeResult& result);
  // The final solve: the keyframe becomes the latest certified pose with these
  // targets, one undo step; the message is the solve's (an error if not reached).
  EditOutcome commit_pose(const KeyframeResult& final, std::vector<cd> targets);
  void cancel_pose();
  const HandlePose* pose() const { return pose_ ? &*pose_ : nullptr; }

  // How the interval leaving keyframe k is travelled (timing.h). Refused for a keyframe
  // that does not exist, for the last one (no interval leaves it) and during a pose;
  // not done (no undo step) when it is the timing already.
  EditOutcome set_timing(int k, KeyTiming timing);

  EditOutcome undo();
  EditOutcome redo();
  bool can_undo() const { return !undo_.empty() && !pose_; }
  bool can_redo() const { return !redo_.empty() && !pose_; }

  // Whether the scene changed since it was loaded or mark_saved() was called.
  bool modified() const { return modified_; }
  void mark_saved() { modified_ = false; }

 private:
  SceneEditState snapshot() const { return {scene_.handles, scene_.keyframes}; }
  void push_undo(SceneEditState before);
  EditOutcome step_history(std::vector<SceneEditState>& from, std::vector<SceneEditState>& to, const char* what);

  Scene scene_;
  SceneEditOptions options_;
  std::vector<SceneEditState> undo_, redo_;
  std::optional<HandlePose> pose_;
  std::optional<SceneEditState> pose_before_;
  bool modified_ = false;
};

}  // namespace hsi
