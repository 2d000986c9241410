// Keyframe authoring by handles (CW17) and import of coefficient keyframes.
#include "hsi/keyframes.h"

#include <algorithm>
#include <chrono>
#include <sstream>

namespace hsi {

namespace {
std::string fmt_point(cd p) {
  std::ostringstream s;
  s.precision(6);
  s << "(" << p.real() << ", " << p.imag() << ")";
  return s.str();
}
}  // namespace

std::vector<cd> map_points(const Cage& cage, const HarmonicMap& map, std::span<const cd> points) {
  const VectorXcd f = evaluate_map(evaluate_basis(cage, points, kBasisC), map).f;
  return std::vector<cd>(f.data(), f.data() + f.size());
}

namespace {
// Identity target metric: the symmetric Dirichlet energy.
std::unique_ptr<NewtonCore> authoring_core(const ShapeSetup& setup, const KeyframeOptions& o) {
  return o.make_core ? o.make_core(setup) : make_cpu_newton_core(setup.D_G, setup.H);
}

// author_keyframe on a given core (a scene's keyframes share one).
KeyframeResult author_on(NewtonCore& core, const ShapeSetup& setup, std::span<const cd> handles, std::span<const cd> targets,
                         const HarmonicMap& start, const KeyframeOptions& o, const std::function<void(int, int)>& progress) {
  const auto t0 = std::chrono::steady_clock::now();
  if (handles.size() != targets.size())
    throw InputError("keyframe: " + std::to_string(targets.size()) + " targets for " + std::to_string(handles.size()) + " handles");
  for (size_t k = 0; k < targets.size(); ++k)
    if (!std::isfinite(targets[k].real()) || !std::isfinite(targets[k].imag()))
      throw InputError("keyframe: target " + std::to_string(k) + " is not finite");
  // A handle must lie on the shape: inside a hole the basis is not the map (and is
  // singular at the hole point).
  for (size_t k = 0; k < handles.size(); ++k)
    if (const std::string why = off_shape_reason(setup.shape, handles[k]); !why.empty())
      throw InputError("keyframe: handle " + std::to_string(k) + " at " + fmt_point(handles[k]) + " " + why);
  const MapSpace& space = setup.map_space;
  Eigen::VectorXd x = space.reduce(import_keyframe(setup, start, "the start map")).x;

  // f(handles) = A x: the positional term λ' Σ |f(p_k) − q_k|², λ' = λ / size².
  const BasisRows rows = evaluate_basis(setup.cage, handles, kBasisC);
  const Eigen::MatrixXd A = reduced_evaluation_matrix(space, rows);
  const double lam = o.lambda / (setup.size * setup.size);
  const std::vector<cd> from = map_points(setup.cage, start, handles);

  KeyframeResult r;
  const int stages = std::max(1, o.stages);
  NewtonResult last;
  for (int st = 1; st <= stages; ++st) {
    if (progress) progress(st, stages);
    const double w = static_cast<double>(st) / stages;
    Eigen::VectorXd q(2 * static_cast<Eigen::Index>(handles.size()));
    for (size_t k = 0; k < handles.size(); ++k) {
      const cd t = from[k] + w * (targets[k] - from[k]);
      q(2 * static_cast<Eigen::Index>(k)) = t.real();
      q(2 * static_cast<Eigen::Index>(k) + 1) = t.imag();
    }
    QuadraticTerm quad{2 * lam * A.transpose() * A, -2 * lam * A.transpose() * q, lam * q.squaredNorm()};
    NewtonOptions no = o.newton;
    if (st < stages) {
      no.max_iterations = o.stage_iterations;
      no.tolerance = 1e-6;
    }
    last = newton_solve(core, space, &setup.certifier, &quad, x, no);
    r.iterations += last.iterations;
    r.log.insert(r.log.end(), last.log.begin(), last.log.end());
    x = last.x;
  }
  r.map = space.expand(x);
  r.certificate = last.certificate;
  r.certified = last.certified;
  r.energy = core.energy();
  const std::vector<cd> got = map_points(setup.cage, r.map, handles);
  for (size_t k = 0; k < handles.size(); ++k) {
    const double e = std::abs(got[k] - targets[k]);
    if (e > r.max_target_error) {
      r.max_target_error = e;
      r.worst_handle = static_cast<int>(k);
    }
  }
  r.reached = r.max_target_error <= o.reach_tolerance * setup.size;
  std::ostringstream m;
  m.precision(3);
  if (!r.certified)
    m << "not certified: " << r.certificate.reason;
  else if (!r.reached)
    m << "targets not reached without folding: handle " << r.worst_handle << " stops " << r.max_target_error
      << " from its target; this is the closest certified map (" << last.message << ")";
  else
    m << "reached all targets (max error " << r.max_target_error << "), certified";
  r.message = m.str();
  r.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return r;
}
}  // namespace

KeyframeResult author_keyframe(const ShapeSetup& setup, std::span<const cd> handles, std::span<const cd> targets,
                               const HarmonicMap& start, const KeyframeOptions& o,
                               const std::function<void(int, int)>& progress) {
  const std::unique_ptr<NewtonCore> core = authoring_core(setup, o);
  return author_on(*core, setup, handles, targets, start, o, progress);
}

HarmonicMap import_keyframe(const ShapeSetup& setup, const HarmonicMap& map, const std::string& what) {
  const int full = setup.map_space.full_size();
  if (map.phi.size() != full || map.psi.size() != full)
    throw InputError(what + ": has " + std::to_string(map.phi.size()) + " coefficients; the cage needs " + std::to_string(full));
  if (!map.phi.allFinite() || !map.psi.allFinite()) throw InputError(what + ": coefficients are not finite");
  try {
    (void)setup.map_space.reduce(map);  // checks ψ_log = conj φ_log
  } catch (const InputError& e) {
    throw InputError(what + ": " + e.what());
  }
  const CertificateResult c = setup.certifier.certify(map);
  if (!c.certified) throw InputError(what + " is not locally injective: " + c.reason);
  return map;
}

}  // namespace hsi

namespace hsi {

std::vector<SceneKeyframe> solve_scene_keyframes(Scene& scene, const ShapeSetup& setup, const KeyframeOptions& options,
                                                 bool force, const std::function<void(const SceneKeyframe&)>& on_keyframe) {
  std::vector<SceneKeyframe> out;
  const HarmonicMap rest = identity_map(setup.cage);
  HarmonicMap previous = rest;
  std::unique_ptr<NewtonCore> core;
  try {
  for (size_t k = 0; k < scene.keyframes.size(); ++k) {
    Keyframe& key = scene.keyframes[k];
    const std::string label = "keyframe " + std::to_string(k);
    SceneKeyframe rep;
    rep.index = static_cast<int>(k);
    if (key.coefficients && !(force && !key.targets.empty())) {
      key.coefficients = import_keyframe(setup, *key.coefficients, label);
    } else {
      if (key.targets.empty()) throw InputError(label + ": has neither targets nor coefficients");
      rep.solved = true;
      if (!core) core = authoring_core(setup, options);  // one core for the scene's keyframes, made when first needed
      rep.from_rest = key.start == Keyframe::Start::Rest;
      rep.result = author_on(*core, setup, scene.handles, key.targets, rep.from_rest ? rest : previous, options, {});
      if (!rep.result.certified) throw InputError(label + ": " + rep.result.message);
      key.coefficients = rep.result.map;
    }
    previous = *key.coefficients;
    rep.overlap = setup.overlap.check(*key.coefficients);
    if (on_keyframe) on_keyframe(rep);
    out.push_back(std::move(rep));
  }
  } catch (const InputError& e) {
    rethrow_in_scene(scene, e);
  }
  return out;
}

}  // namespace hsi

namespace hsi {


std::string off_shape_reason(const Shape& shape, cd p) {
  const BoundingBox bb = bounding_box(shape);
  const double size = bb.diagonal();
  if (point_in_shape(shape, p)) return "";
  const double d = boundary_distance(shape, p);
  if (d <= 1e-9 * size) return "";
  std::string where = "beyond the outer loop";
  for (int l = 1; l < shape.loop_count(); ++l)
    if (point_in_loop(shape.loop(l), p)) where = "in " + loop_name(l);
  std::ostringstream s;
  s.precision(4);
  s << "lies outside the shape, " << where << ", " << d << " from the shape (" << 100 * d / size
    << "% of its size); a handle must be on the shape (its bounding box is " << fmt_point(bb.lo) << " to " << fmt_point(bb.hi)
    << ")";
  return s.str();
}

void add_handle(Scene& scene, cd rest) {
  const std::string what = "handle " + std::to_string(scene.handles.size()) + " at " + fmt_point(rest);
  if (!std::isfinite(rest.real()) || !std::isfinite(rest.imag())) throw InputError(what + ": is not finite");
  if (const std::string why = off_shape_reason(scene.shape, rest); !why.empty()) throw InputError(what + ": " + why);
  for (size_t k = 0; k < scene.keyframes.size(); ++k)
    if (!scene.keyframes[k].coefficients)
      throw InputError(what + ": keyframe " + std::to_string(k) +
                       " is given by targets only, so the new handle's target there is not known; solve the keyframes "
                       "first (hsi keyframes SCENE -o SOLVED.json) and add handles to the solved scene");
  if (!scene.keyframes.empty() && !scene.cage) throw InputError(what + ": the scene's keyframe coefficients have no cage");
  std::vector<cd> all = scene.handles;
  all.push_back(rest);
  for (Keyframe& k : scene.keyframes)  // each keyframe keeps its pose: the target is where the handle is
    k.targets = k.targets.size() == scene.handles.size() && !k.targets.empty()
                    ? [&] {
                        std::vector<cd> t = k.targets;
                        t.push_back(map_points(*scene.cage, *k.coefficients, std::span<const cd>(&rest, 1))[0]);
                        return t;
                      }()
                    : map_points(*scene.cage, *k.coefficients, all);
  scene.handles = std::move(all);
}

int add_keyframe(Scene& scene, double time, std::vector<cd> targets) {
  const std::string what = "keyframe at t = " + std::to_string(time);
  if (!std::isfinite(time)) throw InputError("a keyframe's time must be finite");
  if (targets.empty()) targets = scene.handles;
  if (scene.handles.empty()) throw InputError(what + ": the scene has no handles; add handles first (they are what a keyframe poses)");
  if (targets.size() != scene.handles.size())
    throw InputError(what + ": has " + std::to_string(targets.size()) + " targets; the scene has " + std::to_string(scene.handles.size()) +
                     " handles (give one target per handle, in handle order, or none for the rest pose)");
  for (size_t i = 0; i < targets.size(); ++i)
    if (!std::isfinite(targets[i].real()) || !std::isfinite(targets[i].imag()))
      throw InputError(what + ": target " + std::to_string(i) + " is not finite");
  for (size_t k = 0; k < scene.keyframes.size(); ++k)
    if (scene.keyframes[k].time == time)
      throw InputError(what + ": keyframe " + std::to_string(k) + " is at that time already");
  const auto at = std::upper_bound(scene.keyframes.begin(), scene.keyframes.end(), time,
                                   [](double t, const Keyframe& x) { return t < x.time; });
  const int index = static_cast<int>(at - scene.keyframes.begin());
  scene.keyframes.insert(at, Keyframe{time, std::move(targets), std::nullopt});
  return index;
}

}  // namespace hsi
