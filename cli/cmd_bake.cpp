// hsi bake SCENE -o seq.hsib: interpolates a scene (or takes the frames of an earlier
// hsi interpolate) and bakes it for playback by the dependency-free runtime
// (engine/include/hsi/baked_runtime.h documents the format). hsi bake A.json B.json ...
// -o DIR/: the scenes' sequences solved together by a pool of workers (hsi/batch.h),
// one .hsib per scene.
#include <unistd.h>

#include <cstdio>
#include <map>
#include <mutex>
#include <thread>

#include "hsi/sample_limits.h"
#include "commands.h"
#include "hsi/baked.h"
#include "hsi/baked_runtime.h"
#include "hsi/batch.h"
#include "hsi/keyframes.h"
#include "hsi/runtime/backend.h"
#include "hsi/scene_sequence.h"
#include "sequence_source.h"

namespace hsi::cli {

// Frames from FROM (a .hsif file or a folder holding frames.hsif), checked against the scene's cage.
FrameFile frames_from(const std::string& from, Scene& scene) {
  std::filesystem::path p(from);
  if (std::filesystem::is_directory(p)) p /= "frames.hsif";
  FrameFile ff = read_frames(p);
  const Cage cage = scene_cage(scene);
  if (ff.cage.loops != cage.loops || ff.cage.hole_points != cage.hole_points)
    throw InputError(p.string() + ": its cage is not the scene's (were these frames computed for another scene?)");
  return ff;
}

// Interpolates with a progress line on stderr; returns the sequence.
// A frame's flags on stderr, as every bake and export progress reports them.
void print_flags(const FrameResult& f, int i, const std::string& tag, bool tty) {
  if (!f.certified)
    std::fprintf(stderr, "%s[%s] frame %d (t = %.6f) NOT CERTIFIED: %s\n", tty ? "\n" : "", tag.c_str(), i, f.t, f.certificate.reason.c_str());
  else if (!f.converged)
    std::fprintf(stderr, "%s[%s] frame %d (t = %.6f) NOT CONVERGED after %d iterations: %s\n", tty ? "\n" : "", tag.c_str(), i, f.t,
                 f.iterations, f.message.c_str());
}

SceneSequence interpolate_with_progress(Scene& scene, const SceneSequenceOptions& o, const char* tag, std::unique_ptr<NewtonCore> core,
                                        std::shared_ptr<const ShapeSetup> setup) {
  const bool tty = isatty(fileno(stderr));
  SceneSequence seq = interpolate_scene(scene, o, [&](const FrameResult& f, int i, int n) {
    if (tty)
      std::fprintf(stderr, "\r[%s] frame %d/%d  t = %.4f  %s%s   ", tag, i + 1, n, f.t, f.certified ? "certified" : "NOT CERTIFIED",
                   f.converged ? "" : ", NOT CONVERGED");
    else if ((i + 1) % std::max(1, n / 10) == 0 || i + 1 == n)
      std::fprintf(stderr, "[%s] frame %d/%d\n", tag, i + 1, n);
    print_flags(f, i, tag, tty);
  }, std::move(core), std::move(setup));
  if (tty) std::fprintf(stderr, "\n");
  return seq;
}

namespace {

struct BakeOpts {
  std::vector<std::string> scenes;
  std::string out = "sequence.hsib", from, backend = "cpu";
  std::string predict_start = to_string(InterpolationOptions{}.predict_start);
  int frames = 120, samples = 0, per_interval = 0, jobs = 0;
  double ratio = 0;
  bool f64 = false, allow_unconverged = false;
  int max_iterations = 100;
  int blend_substeps = 4, mesh_vertices = 2000;
};

struct Flagged {
  int uncertified = 0, not_converged = 0;
};

// Encodes the frames, writes the file atomically (a temporary name, then renamed) and
// prints what was written: the one output step of both forms.
Flagged write_baked(const Scene& scene, const FrameFile& ff, const std::string& out, const BakeOpts& o) {
  BakeOptions bo;
  bo.single_precision = !o.f64;
  bo.blend_substeps = o.blend_substeps;
  bo.mesh_vertices = o.mesh_vertices;
  bo.certificate_samples = o.samples > 0 ? o.samples : scene.samples;
  bo.texture_rect = scene.texture_rect_or_bounds();
  const std::string bytes = encode_baked(scene.shape, ff, bo);
  write_file_atomic(out, bytes);
  Flagged flagged;
  int overlapping = 0;
  for (const StoredFrame& f : ff.frames) {
    flagged.uncertified += !f.certified;
    flagged.not_converged += !f.converged;
    overlapping += f.overlaps;
  }
  // Why the frames that did not converge stopped, as the file stores it (hsib_frame_stop).
  const std::string why = stop_counts(ff.frames);
  std::printf("wrote %s: %zu frames, %zu bytes (%.1f KB per frame), %d uncertified, %d not converged%s\n", out.c_str(),
              ff.frames.size(), bytes.size(),
              static_cast<double>(bytes.size()) / 1024.0 / static_cast<double>(std::max<size_t>(1, ff.frames.size())),
              flagged.uncertified, flagged.not_converged, why.empty() ? "" : (" (" + why + ")").c_str());
  // What the runtime will blend, read back from the file as a game reads it.
  if (o.blend_substeps >= 2 && ff.frames.size() >= 2) {
    int blendable = 0;
    hsib_sequence* seq = nullptr;
    if (hsib_open_memory(bytes.data(), bytes.size(), &seq, nullptr, 0) == HSIB_OK) {
      for (uint32_t i = 0; i + 1 < ff.frames.size(); ++i) {
        uint32_t flags = 0;
        hsib_frame_info(seq, i, nullptr, &flags);
        blendable += (flags & HSIB_FRAME_BLEND_CERTIFIED) != 0;
      }
      hsib_close(seq);
    }
    std::printf("blends certified at %d sub-steps in %d of %zu intervals (the runtime plays the nearest frame in the others)\n",
                o.blend_substeps, blendable, ff.frames.size() - 1);
  }
  if (overlapping > 0)
    std::printf("WARNING: %d frame(s) overlap themselves (the image of the boundary crosses itself); flagged "
                "HSIB_FRAME_OVERLAPS in the baked file\n",
                overlapping);
  return flagged;
}

SceneSequenceOptions sequence_options(const BakeOpts& o) {
  SceneSequenceOptions so;
  so.frames = o.frames;
  so.frames_per_interval = o.per_interval;
  so.samples = o.samples;
  so.hessian_ratio = o.ratio;
  so.interpolation.max_iterations = o.max_iterations;
  so.interpolation.predict_start = parse_predict_start(o.predict_start);
  return so;
}

// hsi bake SCENE -o FILE: one scene, one sequence, as before.
void bake_one(const BakeOpts& o) {
  Scene scene = load_scene(o.scenes.front());
  FrameFile ff;
  if (!o.from.empty()) {
    ff = frames_from(o.from, scene);
  } else {
    const std::shared_ptr<const ShapeSetup> setup = scene_setup(scene, o.samples, o.ratio);
    runtime::NewtonCoreChoice core = runtime::make_newton_core(*setup, runtime::parse_backend(o.backend));
    if (core.choice.used != runtime::Backend::Cpu || !core.choice.fallback.empty())
      std::printf("Newton core: %s\n", runtime::describe(core.choice).c_str());
    ff = interpolate_with_progress(scene, sequence_options(o), "bake", std::move(core.core), setup).frame_file();
  }
  const Flagged f = write_baked(scene, ff, o.out, o);
  exit_for_flagged_frames(f.uncertified, f.not_converged, o.allow_unconverged, "they are flagged in the baked file");
}

// hsi bake A.json B.json ... -o DIR: every scene's sequence solved together, one file each.
void bake_many(const BakeOpts& o) {
  if (!o.from.empty()) throw InputError("--from bakes the frames of one scene; give one scene with it (got " + std::to_string(o.scenes.size()) + ")");
  // Output names from the scene files' names; two scenes may not write one file.
  const std::filesystem::path dir(o.out);
  std::vector<std::filesystem::path> outs;
  std::map<std::string, std::string> by_name;
  for (const std::string& s : o.scenes) {
    const std::string name = std::filesystem::path(s).stem().string() + ".hsib";
    if (const auto [it, added] = by_name.emplace(name, s); !added)
      throw InputError("scenes " + it->second + " and " + s + " would both be baked to " + (dir / name).string() +
                       " (output names come from the scene file names: rename one)");
    outs.push_back(dir / name);
  }
  if (std::filesystem::exists(dir) && !std::filesystem::is_directory(dir))
    throw InputError(o.out + ": with several scenes -o names a folder, and this is a file");
  std::filesystem::create_directories(dir);

  // Scenes made ready one by one (setup, keyframes certified or solved); one that cannot
  // be is named and left out, the others are still baked.
  const size_t N = o.scenes.size();
  std::vector<Scene> scenes(N);
  std::vector<std::shared_ptr<const ShapeSetup>> setups(N);
  std::vector<std::string> errors(N);
  std::vector<BatchSequence> batch;
  std::vector<size_t> scene_of;  // batch index → scene index
  const SceneSequenceOptions so = sequence_options(o);
  for (size_t k = 0; k < N; ++k) {
    try {
      scenes[k] = load_scene(o.scenes[k]);
      Scene& scene = scenes[k];
      if (scene.keyframes.size() < 2)
        throw InputError(o.scenes[k] + ": interpolation needs at least two keyframes (it has " + std::to_string(scene.keyframes.size()) +
                         "); " + kHowToAddKeyframes);
      setups[k] = scene_setup(scene, o.samples, o.ratio);
      solve_scene_keyframes(scene, *setups[k]);
      BatchSequence q;
      q.name = o.scenes[k];
      q.setup = setups[k].get();
      for (const Keyframe& kf : scene.keyframes) {
        q.key_times.push_back(kf.time);
        q.keyframes.push_back(*kf.coefficients);
      }
      q.options = so.interpolation;
      q.options.timing = scene_timings(scene);
      q.times = sequence_times(q.key_times, so.frames, so.frames_per_interval);
      batch.push_back(std::move(q));
      scene_of.push_back(k);
    } catch (const InputError& e) {
      errors[k] = e.what();
      std::fprintf(stderr, "[bake] %s: not baked: %s\n", o.scenes[k].c_str(), e.what());
    }
  }

  // One backend for every worker: auto decided here once, so no worker falls back alone.
  const runtime::Backend requested = runtime::parse_backend(o.backend);
  const runtime::CudaStatus cuda = requested == runtime::Backend::Cpu ? runtime::CudaStatus{} : runtime::cuda_status();
  const runtime::BackendChoice choice = runtime::choose_backend(requested, cuda);
  BatchOptions bo;
  const int hw = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  bo.workers = o.jobs > 0 ? o.jobs : hw;
  // One OpenMP thread each: W workers use W cores, and the frames (whose CPU energy sums
  // follow the OpenMP thread count) are the same for any --jobs.
  bo.threads_per_worker = 1;
  runtime::set_batch_backend(bo, choice.used, cuda);
  size_t total = 0;
  for (const BatchSequence& q : batch) total += q.times.size();
  std::printf("baking %zu scene(s), %zu frames: %d worker(s) x %d OpenMP thread(s), Newton core: %s\n", batch.size(), total,
              bo.workers, bo.threads_per_worker, runtime::describe(choice).c_str());

  const bool tty = isatty(fileno(stderr));
  std::vector<size_t> left(batch.size());
  for (size_t b = 0; b < batch.size(); ++b) left[b] = batch[b].times.size();
  const BatchResult result = solve_batch(batch, bo, [&](const FrameResult& f, int b, int i, size_t done, size_t all) {
    const std::string& name = batch[static_cast<size_t>(b)].name;
    print_flags(f, i, "bake " + name, tty);
    if (tty)
      std::fprintf(stderr, "\r[bake] %zu/%zu frames   ", done, all);
    else if (done % std::max<size_t>(1, all / 10) == 0 || done == all)
      std::fprintf(stderr, "[bake] %zu/%zu frames\n", done, all);
    if (--left[static_cast<size_t>(b)] == 0) std::fprintf(stderr, "%s[bake] %s: solved\n", tty ? "\n" : "", name.c_str());
    return true;
  });
  if (tty) std::fprintf(stderr, "\n");
  std::printf("solved %zu frames in %.2f s (%.0f frames/s, %d runs, %d cores made)\n", total, result.stats.seconds,
              static_cast<double>(total) / std::max(result.stats.seconds, 1e-9), result.stats.runs, result.stats.cores_made);

  Flagged all;
  for (size_t b = 0; b < batch.size(); ++b) {
    const size_t k = scene_of[b];
    const BatchSequenceResult& r = result.sequences[b];
    if (!r.error.empty()) {
      errors[k] = r.error;
      std::fprintf(stderr, "[bake] %s: not baked: %s\n", o.scenes[k].c_str(), r.error.c_str());
      continue;
    }
    const SceneSequence seq{setups[k], r.frames, 0.0, batch[b].options};
    try {
      const Flagged f = write_baked(scenes[k], seq.frame_file(), outs[k].string(), o);
      all.uncertified += f.uncertified;
      all.not_converged += f.not_converged;
    } catch (const InputError& e) {
      errors[k] = e.what();
      std::fprintf(stderr, "[bake] %s: not baked: %s\n", o.scenes[k].c_str(), e.what());
    }
  }
  std::string failed;
  int failures = 0;
  for (size_t k = 0; k < N; ++k)
    if (!errors[k].empty()) failed += (failures++ ? ", " : "") + o.scenes[k];
  if (failures)
    throw InputError(std::to_string(failures) + " of " + std::to_string(N) + " scene(s) not baked (" + failed +
                     "; each named above with why); the others were written");
  exit_for_flagged_frames(all.uncertified, all.not_converged, o.allow_unconverged, "they are flagged in the baked files");
}

}  // namespace

void register_bake(CLI::App& app) {
  auto o = std::make_shared<BakeOpts>();
  CLI::App* cmd = app.add_subcommand(
      "bake",
      "Bake a scene's interpolation for playback in a game: a compact .hsib file (the cage once, then per frame the\n"
      "reduced coefficients and pose, a few KB) that the dependency-free runtime hsi/baked_runtime.h plays back on\n"
      "any mesh's vertices with one small matrix product per frame. Each frame's flags (certified, keyframe,\n"
      "converged) and why its Newton solve stopped are stored in the file. Several scenes (hsi bake a.json b.json\n"
      "-o DIR) are solved together by --jobs workers, one DIR/NAME.hsib per scene NAME.json.\n" +
          std::string(kFlaggedFramesHelp));
  cmd->add_option("scenes", o->scenes, "Scene file(s) (.json) with two or more keyframes")->required()->check(CLI::ExistingFile);
  cmd->add_option("-o,--output", o->out, "Baked file to write; with several scenes, the folder for their NAME.hsib")->capture_default_str();
  add_frame_options(cmd, o->frames, o->per_interval);
  cmd->add_option("--samples", o->samples, "Boundary samples |G| (default: the scene's)")->check(CLI::Range(kMinSamples, kMaxSamples));
  cmd->add_option("--ratio", o->ratio, "Hessian sample ratio r (default: the scene's)")->check(CLI::Range(1e-6, 1.0));
  cmd->add_option("--from", o->from, "Bake the frames of an earlier hsi interpolate (its folder or frames.hsif) instead");
  cmd->add_option("--max-iterations", o->max_iterations, "Newton iterations per frame at most")->capture_default_str()->check(CLI::Range(1, 1000000));
  add_predict_start_option(cmd, o->predict_start);
  cmd->add_option("--backend", o->backend, runtime::kBackendHelp)->capture_default_str()->check(CLI::IsMember(runtime::backend_names()));
  cmd->add_option("--jobs", o->jobs,
                  "With several scenes: workers solving them together, each with its own Newton core and one OpenMP thread\n"
                  "(default: the machine's hardware threads); the frames do not depend on it")
      ->check(CLI::Range(1, 4096));
  cmd->add_flag("--allow-unconverged", o->allow_unconverged, "Exit 0 when certified frames did not converge (still flagged in the file)");
  cmd->add_option("--blend-substeps", o->blend_substeps,
                  "k: certify the blends of every two neighbouring certified frames at k-1 sub-steps, so the runtime may blend\n"
                  "there (0: nearest-frame playback only)")
      ->capture_default_str()
      ->check(CLI::Range(0, 1000));
  cmd->add_option("--mesh-vertices", o->mesh_vertices, "The shape's triangulation stored in the file, about this many vertices")
      ->capture_default_str()
      ->check(CLI::Range(16, 10000000));
  cmd->add_flag("--f64", o->f64, "Store per-frame coefficients as f64 (default f32, about 1e-7 of the shape's size)");
  cmd->callback([o, cmd] {
    if (o->scenes.size() == 1) return bake_one(*o);
    if (cmd->get_option("--output")->count() == 0)
      throw InputError("several scenes: give -o DIR, the folder for their .hsib files");
    bake_many(*o);
  });
}

}  // namespace hsi::cli
