// Certified Newton iteration over the reduced coefficients (paper Algorithm 1,
// math.md §5) for energies "mean over samples G of the isometric energy of
// (f_z, conj f_zbar) against a target metric per sample", plus an optional
// quadratic term (positional constraints when authoring keyframes).
//
// One loop, newton_solve, makes every decision (which Hessian, ridge retries, the
// descent test, Armijo backtracking, certificate rejections, convergence and
// stagnation) for every backend. The arithmetic sits behind two interfaces:
//   NewtonCore     per-sample work (energy and gradient over G, the PSD Hessian over
//                  H, line-search evaluations): the CPU core here, the readable
//                  reference, and its CUDA twin (the CUDA backend, made by runtime's factory);
//   NewtonStepper  one solve's reduced-space work (the system, its factorisation, the
//                  trial points, the certificate): a host stepper over any NewtonCore
//                  (newton.cpp), or a core's own (the CUDA core keeps x, the system
//                  and the certificate on the GPU and answers with scalars).
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "hsi/certificate.h"
#include "hsi/energy.h"
#include "hsi/map_space.h"

namespace hsi {

struct QuadraticTerm;
struct NewtonOptions;
struct NewtonResult;
class NewtonStepper;

// The samples an exact Newton system sums its Hessian over. The energy and gradient
// always sum over all of G; the paper builds Hessians over the subset H (r|G|) for speed.
// Near the solution the subset's exact Hessian is not the energy's: at the minimiser of
// the energy over G it can be indefinite (bench_stress, issue #20: links/bend at |G|
// 2,000, one eigenvalue of −2e-7 against a largest of 16 at every PartProj solution,
// while over G it is definite), so the loop falls back to the projection and needs a
// step more, and where it is definite its Newton decrement is not the energy's, so the
// decrement test ends fewer solves.
enum class ExactSamples {
  Subset,          // over H, as every other Hessian (the paper's speed-up)
  SubsetThenAll,   // over H; where that is not positive definite, over G before the projection
  All,             // over G (|G|/|H| times the Hessian's work; on the GPU that work is small)
  Auto             // the core's own choice (NewtonCore::preferred_exact_samples); newton_run alone: Subset
};
const char* to_string(ExactSamples e);
ExactSamples parse_exact_samples(const std::string& name);  // one of exact_samples_names()
// "subset", "subset-then-all", "all", "auto": every ExactSamples by its to_string name, in
// declaration order (for an option's check, e.g. CLI::IsMember(exact_samples_names())).
const std::vector<std::string>& exact_samples_names();

// Per-iteration sample work. Coefficients are the active real vector
// v = (Re φ_a, Im φ_a, Re ψ_a, Im ψ_a) ∈ R^{4n} of MapSpace.
class NewtonCore {
 public:
  virtual ~NewtonCore() = default;
  virtual int n() const = 0;
  virtual const char* name() const = 0;
  // Reference metric at every sample of G (identity for plain symmetric Dirichlet).
  virtual void set_targets(const std::vector<Metric>& g) = 0;
  virtual void set_coefficients(const Eigen::VectorXd& v) = 0;
  virtual double energy() = 0;                     // mean over G; +inf if a sample folds
  virtual Eigen::VectorXd gradient() = 0;          // ∂E/∂v, mean over G
  // PSD Hessian (mean over H; with all_samples, over all of G), or with exact = true the
  // unprojected one.
  virtual Eigen::MatrixXd hessian(HessianProjection projection, bool exact = false, bool all_samples = false) = 0;
  // H p for the Hessian hessian(projection, exact, all_samples) returns, without forming
  // it: each sample's 4×4 Hessian applied to the sample's part of p, then summed back
  // through the basis rows as the gradient is, O(|G| n) work against the matrix's
  // O(|G| n²) (a Krylov solve's product: a preconditioned conjugate gradient with a kept
  // factor reaches the exact system's Newton decrement in 2-4 such products where that
  // factor is one frame old, bench/results/pcg_decrement_2026-12-07.md). Equal to
  // hessian(...) · p up to round-off. The default forms the matrix.
  virtual Eigen::VectorXd hessian_times(HessianProjection projection, bool exact, bool all_samples, const Eigen::VectorXd& p) {
    return hessian(projection, exact, all_samples) * p;
  }
  virtual void set_direction(const Eigen::VectorXd& dv) = 0;
  virtual double max_safe_step() = 0;              // first s > 0 with |a + s da| = |b + s db| at a sample
  virtual double energy_at(double s) = 0;          // energy at v + s dv
  // ExactSamples::Auto resolved (newton_solve): the samples this core's exact systems
  // should sum over. The CPU core: Subset (over all of G its Hessian costs |G|/|H| times
  // the work, 1.8-2.2x a warm frame on the bundled scenes, bench_cuda); the CUDA core:
  // All (that work is small next to its latencies, and the exact system over G is the
  // energy's: fewer iterations, decisions that do not hinge on round-off).
  virtual ExactSamples preferred_exact_samples() const { return ExactSamples::Subset; }

  // Targets as a blend of metric sets the core keeps (an interpolator's keyframes, set
  // once): blend_targets(token, w, false) sets Σ_j w_j keys_j per sample, with
  // `exponential` metric_exp(Σ_j w_j log_keys_j) (log_keys may be empty otherwise). The
  // token names the sets; blend_targets returns false, setting nothing, when the core
  // has been given other sets since (a core lent to several interpolators in turn). The
  // default blends on the host and calls set_targets; the CUDA core blends on the device
  // instead of uploading |G| metrics per frame.
  virtual std::uint64_t set_target_keys(std::vector<std::vector<Metric>> keys, std::vector<std::vector<Metric>> log_keys);
  virtual bool blend_targets(std::uint64_t token, std::span<const double> w, bool exponential);

  // A stepper of the core's own for one solve in `space` (certifier and quad may be
  // null), or null: newton_solve then drives this core through the host stepper. The
  // CUDA core made from a ShapeSetup answers for that setup's spaces and certifier.
  virtual std::unique_ptr<NewtonStepper> make_stepper(const MapSpace& /*space*/, const Certifier* /*certifier*/,
                                                      const QuadraticTerm* /*quad*/) {
    return nullptr;
  }

  // The full certificate of `map` (CertificateOptions' defaults) by `certifier` on the
  // core's backend, where the core can: the CUDA core made from a ShapeSetup answers for
  // that setup's certifier with its device certifier (the certificate its frames get).
  // nullopt: the caller certifies on the host. An Interpolator certifies its keyframes
  // so at set-up (issue #23: on the host it was 6-8 ms of a keyframe's ~13 ms there at
  // |G| = 10,000, one thread).
  virtual std::optional<CertificateResult> certify_map(const Certifier& /*certifier*/, const HarmonicMap& /*map*/) {
    return std::nullopt;
  }

  // A token no other set_target_keys call of any core gets.
  static std::uint64_t next_target_token();

 private:
  std::vector<std::vector<Metric>> keys_, log_keys_;  // the default blend's sets
  std::uint64_t token_ = 0;
};

// Which Hessian a Newton system is built from.
struct HessianChoice {
  bool exact = false;  // the unprojected Hessian (mean over H); else the projection below
  HessianProjection projection = HessianProjection::PartProj;
  // Solve with the global rotation of the image free: the system gets one more unknown,
  // θ, along MapSpace::rotation_generator, and a step is taken along T d + θ u and then
  // turned back into the rotation gauge exactly (MapSpace::regauge). The energy and the
  // certificate do not change under that rotation. Only for the ModuloRigid space
  // without a quadratic term (newton_solve decides).
  // With exact: the exact Hessian on the shapes modulo rotation. The step T d + θ u is
  // kept orthogonal to u (θ = −(Tᵀu)ᵀd / |u|²), so the system in d is
  // Eᵀ K E with K the system in (d, θ) and E = [I; −(Tᵀu)ᵀ/|u|²]: a rank-2 change of
  // the gauged exact system, which is the energy's Hessian along the gauge slice, not
  // across the orbits of the rotation; the step is then taken and regauged as above.
  bool free_rotation = false;
  // The Hessian over all of G instead of the subset H (a Hessian |G|/|H| times dearer;
  // newton_solve escalates to it when the subset's model fails, NewtonOptions::
  // escalate_after_cuts).
  bool all_samples = false;
};

// A factored exact Newton system kept past the solve that made it, for chord steps in
// later solves (NewtonOptions::kept_system): in the form its stepper keeps it (the host
// stepper: the factor, here; the CUDA stepper: on the device, where `generation` tells
// whether another solve has replaced it since). Only a stepper of the same owner (the
// same space, and for the CUDA core the same device workspace) solves with it.
struct KeptSystem {
  const void* owner = nullptr;    // null: nothing kept
  std::uint64_t generation = 0;   // the owner's count of systems kept when this one was
  std::shared_ptr<void> data;     // the owner's own form (the host stepper's factor)
  int order = 0;                  // the system's order, and what it was made as:
  bool free_rotation = false, modulo_rotation = false;
  // Carried beside the system (NewtonOptions::carry_all_samples): a solve of this
  // sequence found the subset H's model wrong and built its Hessians over all of G; the
  // solves after it start there. Set by newton_run, independent of the system above.
  bool all_samples = false;
  bool empty() const { return owner == nullptr; }
};

// Whether a sequence's solves carry a move of the Hessians to all of G to the next solve
// (NewtonOptions::carry_all_samples, KeptSystem::all_samples).
enum class AllSamplesCarry : std::uint8_t {
  Off,
  On,
  Auto  // On where the exact systems sum over all of G (ExactSamples::All, resolved: the
        // core's Hessians over G are cheap, the GPU's), Off otherwise; newton_run alone: Off
};

// What a stepper reports about the system it solved: (H + ridge I) d = −g.
struct NewtonSystem {
  bool factored = false;       // Cholesky succeeded and d is finite
  double slope = 0;            // gᵀd (< 0 for a descent direction; −slope is the squared Newton decrement)
  double gradient_norm = 0;    // |g| in the reduced variables
  double diagonal_max = 0;     // max |diagonal of H|: the scale of a ridge
  double max_safe_step = 0;    // first s > 0 at which a sample reaches |a| = |b| along d
  // false: from decrement(), which factored and found the decrement but made no d yet:
  // slope is −‖L⁻¹g‖² (gᵀd in exact arithmetic), max_safe_step unknown; direction() makes d.
  bool has_direction = true;
};

// One solve's work in the reduced space. Vectors stay where the stepper keeps them;
// newton_solve sees scalars, certificates and, at the end, x. "x ⊕ s·d" is x + s d, or
// with free_rotation the regauged T x + s (T d + θ u).
class NewtonStepper {
 public:
  virtual ~NewtonStepper() = default;
  // x ← x0; the total energy there (mean over G plus the quadratic term), +inf if it folds.
  virtual double start(const Eigen::VectorXd& x0) = 0;
  // start() whose energy may come later: start_energy() gives it, and the GPU stepper
  // waits for the device only at its next call that waits anyway (newton_run begins a
  // chord step with it: the chord's solve brings the energy along). Default: start().
  virtual void start_deferred(const Eigen::VectorXd& x0) { deferred_energy_ = start(x0); }
  virtual double start_energy() { return deferred_energy_; }
  // The gradient and the chosen Hessian at x (the quadratic term's added). A stepper
  // may return before they are made (the GPU's: solve() waits for them).
  virtual void linearize(const HessianChoice& choice) = 0;
  // d from (H + ridge · max|diag H| · I) d = −g of the last linearize() (the ridge
  // relative to the system's scale, NewtonSystem::diagonal_max; max|diag H| taken as at
  // least 1e-300), and the safe step along it. Relative, so that the loop needs no
  // number from linearize() before it asks for the factor: the GPU stepper runs both
  // without waiting between them.
  virtual NewtonSystem solve(double ridge) = 0;
  // The factor and the Newton decrement alone, for a solve that may stop on it (the exact
  // system near the solution): solve()'s system with slope = −‖L⁻¹g‖² (the forward
  // substitution only; has_direction false), or, where the stepper does not split the
  // solve, solve() itself. direction() then makes d, the slope gᵀd and the safe step
  // along it, as solve() gives them (only after a decrement() that factored; keep() may
  // come between). The GPU stepper saves the back substitution, the direction's
  // products and the safe step on a solve that stops.
  virtual NewtonSystem decrement(double ridge) { return solve(ridge); }
  virtual NewtonSystem direction() { throw std::logic_error("NewtonStepper::direction without a split decrement()"); }
  // Total energies at x ⊕ steps[j]·d.
  virtual void trial_energies(std::span<const double> steps, std::span<double> energies) = 0;
  // The certificate of x ⊕ step·d (step 0: of x). Full: every segment, with bounds;
  // otherwise it may stop at the first failure (a pass has looked at every segment).
  virtual CertificateResult certify(double step, bool full) = 0;
  // A certify(step, false) the loop will likely ask for next, asked ahead: a stepper may
  // start it now and hand its result to that call (the GPU stepper enqueues it before the
  // trial energies the loop asks for first, so one wait brings both). Any other call of
  // certify() or accept() drops it. Default: nothing.
  virtual void certify_ahead(double /*step*/) {}
  // x ← x ⊕ step·d: exactly the point certify(step, ·) looked at.
  virtual void accept(double step) = 0;
  virtual Eigen::VectorXd x() = 0;
  // Chord steps (NewtonOptions::kept_system). keep: the system the last solve() factored
  // (an exact one, successfully) into `slot`, replacing what it held; false where this
  // stepper keeps none (the slot is then left as it was). linearize_kept: linearize() for
  // the kept system: the gradient at x, and the next solve() solves with the slot's
  // factor (its ridge ignored); false, nothing done, where the slot is not this
  // stepper's to solve with.
  virtual bool keep(KeptSystem& /*slot*/) { return false; }
  virtual bool linearize_kept(const KeptSystem& /*slot*/) { return false; }

 private:
  double deferred_energy_ = 0;  // start_deferred's, by default
};

// The host stepper: reduced-space algebra with Eigen over the core's per-call interface.
std::unique_ptr<NewtonStepper> make_host_stepper(NewtonCore& core, const MapSpace& space, const Certifier* certifier,
                                                 const QuadraticTerm* quad);

// D: the active basis rows D(w) at the samples G (|G| × n); H: indices into G.
std::unique_ptr<NewtonCore> make_cpu_newton_core(MatrixXcd D, std::vector<int> H);

// A core that forwards every call to `core`, which must outlive it: lends one core to
// owners that each want their own (an Interpolator, authoring's make_core, a batch
// worker's sequences), so that its set-up is paid once.
std::unique_ptr<NewtonCore> borrow_core(NewtonCore& core);

// ½ xᵀ Q x + cᵀ x + k over the reduced variables.
struct QuadraticTerm {
  Eigen::MatrixXd Q;
  Eigen::VectorXd c;
  double k = 0;
  double value(const Eigen::VectorXd& x) const { return 0.5 * x.dot(Q * x) + c.dot(x) + k; }
};

// Every threshold newton_solve decides by. Energies are compared relative to |E|, so a
// test means the same whatever the energy's scale (the interpolation energy is ≥ 2; an
// authoring energy adds a positional term).
struct NewtonOptions {
  int max_iterations = 100;
  // Converged when a step the line search took as first offered (min(1, safe_fraction ·
  // s_max), or longer: not cut by Armijo or the certificate) lowers the energy by less
  // than tolerance·|E| and the decrease is not a slow linear crawl: with
  // ρ = ΔE_k / ΔE_{k−1} (0 for the first step), the decrease still to come, ΔE ρ/(1 − ρ),
  // counts too. 5e-8 is the paper's absolute 1e-7 at E = 2, the
  // isometric energy's minimum. Also converged: an exact system whose Newton decrement
  // (the decrease of a full step, −gᵀd/2, taken as ‖L⁻¹g‖²/2 before d is made:
  // NewtonStepper::decrement) is below it. A cut step's small decrease
  // says nothing about what is left (issue #20: a first Delete step cut to 1/2048
  // lowered the energy by 4e-8 with a decrement of 3e-4 left, and the frame was called
  // converged).
  double tolerance = 5e-8;
  // Also converged: a projected system (not a chord one) whose decrement −gᵀd/2 is below
  // this fraction of tolerance·|E| (0: never). A projection clamps curvature up, so its
  // decrement can understate what is left by the factor it overstates curvature along
  // the gradient; the fraction is the margin for that. Where the exact system does not
  // factor near a solution (issue #20: at near-rigid maps the exact Hessian over G has an
  // eigenvalue of −2e-7 against a largest of 16, PartProj's accurate first step lands
  // there, blob/spin), the frame otherwise takes one more projected step whose decrease
  // (in the traces: what its model predicted, ~1e-9 at E = 2) stops it. Interpolation
  // sets 0.01 (InterpolationOptions::projected_decrement_stop, measured there); authoring 0.
  // The same share ends a solve at its start where a chord step's system (the kept one,
  // kept_system) has a decrement below it: a kept factor may be stiffer than the energy
  // as a projection is, and a frame that does not move the metric (a rigid motion between
  // keyframes, with the slot seeded at the keyframe: newton_seed_kept_system) has nothing
  // to step.
  double projected_decrement_stop = 0;
  // Also converged: a projected system (not a chord one) whose decrement −gᵀd/2, scaled
  // by how far the previous step's model understated its own decrease, is below
  // tolerance·|E|. The previous step must be a full one (step 1, no backtrack) of this
  // solve; with r its decrease over its model's −gᵀd/2, a quadratic model of curvature
  // κ_m along its direction against the energy's κ gives r = 2 − κ/κ_m, so along it the
  // energy offers 1/(2 − r) times what the model says (r ≤ 1, a model no stiffer than the
  // energy: the decrement as it is; r ≥ 2: no stop). The 1 % of projected_decrement_stop
  // is a margin for a stiffness not yet seen; this rule uses the one the solve has seen.
  // Near-rigid frames (issue #20, bench_stress --trace, arm/drag with PartProj, CPU core,
  // exact systems over G): the exact system over G never factors, every frame's first
  // projected step lowers the energy by what its model said (r ≈ 1) and a second one by
  // 3e-9 at a tolerance·|E| of 1e-7, a step the decrement below the tolerance already
  // said was not worth taking. Interpolation turns it on
  // (InterpolationOptions::checked_decrement_stop); authoring leaves it off.
  bool checked_decrement_stop = false;
  // Also converged, after a full chord step (the solve's first step, with the factor kept
  // by an earlier solve, kept_system; step 1, no backtrack): the kept system's decrement
  // at the new x, scaled by that step's model error as in checked_decrement_stop, below
  // this share of tolerance·|E|. For a quadratic energy the scaled number is the
  // decrement along the step's direction exactly; the share is the margin for the other
  // directions, where the kept factor (made at an earlier frame's solution) may be
  // stiffer than the energy. The solve then ends without a system of its own: no exact
  // Hessian and no factor, the bulk of a warm frame's work on either core, and the next
  // solve's chord step reuses the same older factor (where it overshoots, that solve
  // builds its systems at its own points, as without a kept one). Where the test fails
  // the iteration goes on as without it. Measured (issue #23, 2026-12-07, CPU core with
  // exact systems over G, chromium_superbomb/bend_steps, hinge and u_to_s at |G| = 3,000,
  // Delete and PartProj): at 500 frames per interval 22.8–26.2 → 13.9–14.5 ms per frame for
  // 1.00 → 1.02–1.03 iterations per frame with a share of 0.01; at 100 the same iterations
  // (1.28 / 1.30), the test seldom passing. Larger shares fire where frames are further
  // apart, and the factor they leave kept overshoots in the next frame: at 100, 1.34–1.36
  // iterations with 0.03 and 1.52–1.54 with 0.1 (bend_steps at |G| = 40,000 with 0.1:
  // 1.01 → 1.49), and even 0.01 costs steps on some sequences at |G| = 40,000 (drag, 100
  // frames per interval: Delete 199 → 222 iterations over 198 frames, PartProj 202 → 210).
  // On the CUDA core (one H100, bench_cuda, bar_holes, 500 frames) it does not pay: a warm
  // frame 0.80 against 0.71 ms (the test seldom passes there, and its kept solve and wait
  // add to the exact system's), and over the stress corpus at 100 frames per interval the
  // iterations rise 1.2–2.6 %. Off by default (InterpolationOptions::chord_decrement_stop);
  // authoring 0 (never).
  double chord_decrement_stop = 0;
  HessianProjection projection = HessianProjection::PartProj;
  // Once a full step was taken (or, with exact_after_cut, a projected step that Armijo
  // cut), use the unprojected Hessian whenever its reduced system is positive definite
  // (quadratic convergence near the solution), and the projection above otherwise (and
  // always in a solve's first iteration).
  bool exact_hessian_when_definite = true;
  // Also try the exact system after a projected step that Armijo cut (backtracks beyond
  // the certificate's rejections), not after full steps only: a projection can be too
  // soft along cage modes that barely change the metric (Delete's), every projected step
  // then overshoots, Armijo cuts it to 1/64–1/1024 and the energy crawls into stagnation
  // while the exact system, gated on a full step, is never tried (bench_stress --trace,
  // issue #20: grid_2/scale with Delete, 7 of 99 frames stagnated, 37 iterations at
  // t = 0.31; with this rule none, at most 6). After an exact step that Armijo cut the
  // next system is the projection again: each model is tried after the other failed.
  // (The same rule on an older loop, with the exact system over the subset H and a ridge
  // of 1e-12, crawled on exact steps cut to 1/4–1/2 for 100 iterations in the cli_authoring
  // test's posed scene; escalate_after_cuts and exact_ridge = 1e-15 end that frame in 3.)
  bool exact_after_cut = true;
  // Step expansion: when a full step lowered the energy by more than expand_ratio times
  // what the system's quadratic model predicts (−gᵀd/2), the model is too stiff along d
  // (a projection clamps negative or near-zero curvature to a positive one): the steps
  // 2, 4, …, 2^expand_steps (up to safe_fraction · s_max) are tried too and the lowest
  // energy that passes Armijo and the certificate is taken (else the full step). Near a
  // saddle the projected Newton otherwise takes full steps, each ~2× what its model
  // predicts, at a linear rate of 0.9–1 (bench_stress --trace, issue #20: chain/spin with
  // PartProj, t = 0.59 at the iteration cap, the safe step 200–700). 0: never.
  double expand_ratio = 1.5;
  int expand_steps = 4;
  // The exact system is factored with this ridge (relative to max |diag H|): its
  // smallest eigenvalues lie near 0 (cage modes that barely move the boundary), where
  // round-off alone would decide whether a bare Cholesky succeeds; with the ridge only
  // a clearly indefinite system falls back to the projection. The ridge damps every mode
  // softer than itself: Newton then converges along it only linearly, at the rate
  // ridge / (ridge + eigenvalue). Soft modes reach ~1e-14 of the largest eigenvalue
  // (bench_stress --trace, issue #20: grid_2/halves_180, full exact steps lowering the
  // energy at a rate of 0.93 per step to the iteration cap with 1e-12; 5 frames: 51.3
  // iterations per frame with 1e-12, 28.5 with 1e-13, 12.0 with 1e-14, 11.0 with 1e-15
  // and with 0), so the ridge sits at round-off level.
  double exact_ridge = 1e-15;
  // Solve the exact system modulo the global rotation (HessianChoice::free_rotation with
  // exact) where the energy is rotation invariant. The gauged exact system (the energy
  // restricted to the slice Re φ_r = 0) is indefinite over many more iterations of a
  // frame than the one modulo rotation (bench_stress --trace, issue #20: annulus/
  // hinge_posed, one negative eigenvalue in iterations 2-8 of a frame), so the loop fell
  // back to the projection there and converged only linearly.
  bool exact_modulo_rotation = true;
  // Which samples the exact system's Hessian sums over (ExactSamples). Projected systems
  // use the subset H until a rule above moves them to all of G.
  ExactSamples exact_samples = ExactSamples::Subset;
  // Free the global rotation in projected systems (HessianChoice::free_rotation): a PSD
  // projection gives the rotation, along which the energy is flat, a curvature that the
  // rotation gauge Re φ_r = 0 otherwise spreads over every other direction, and Newton
  // then crawls (issue #20).
  bool free_rotation = true;
  double armijo = 0.2;            // sufficient-decrease factor
  double shrink = 0.5;            // backtracking factor
  double safe_fraction = 0.8;     // first trial step: min(1, 0.8 s_max)
  int max_backtracks = 60;
  int max_ridge_attempts = 12;    // ridges 1e-12·max|diag H|, ×10 each, when Cholesky fails
  double descent_slope = 1e-14;   // no descent left when gᵀd ≥ −descent_slope·max(1, |E|)
  // Stagnation: this many accepted steps in a row, each lowering the energy by less than
  // 10·tolerance·|E| at a linear rate ρ ≥ stagnation_rate, stop the solve as not converged.
  int stagnation_steps = 12;
  double stagnation_rate = 0.9;
  // The Hessian comes from the subset H of the samples (r|G|, the paper's speed-up); the
  // gradient and the energy from all of G. Where a few samples carry most of the
  // curvature (thin parts, a cage close to the boundary, few samples for many unknowns)
  // the subset's model is wrong: its Newton step overshoots and Armijo cuts it again and
  // again though the certificate allows a full step (bench_stress --trace, issue #20:
  // ceferino_levels at |G| 2,000, n = 85, steps of 1/32 for 100 iterations; with H = G
  // 2 iterations). After an iteration whose step Armijo cut this many times (the
  // certificate's rejections not counted), the rest of the solve builds its Hessians
  // over all of G (HessianChoice::all_samples). 0: never.
  int escalate_after_cuts = 2;
  // The subset's model can be wrong by less than that rule sees: Armijo cuts every step
  // once, to 1/2, the exact system over H is indefinite (so exact_after_cut falls back to
  // the projection), and the energy crawls (bench_stress --trace, issue #20:
  // grid_6/hinge_posed at 500 frames per interval with FullProj, t = 0.770: 16 steps cut
  // to 1/2, then one cut twice moved the Hessians to all of G, whose exact system was
  // definite and ended the frame in one step; t = 0.772: 40 steps cut to 1/2, stagnated).
  // After this many iterations of a solve whose steps Armijo cut (the certificate's
  // rejections not counted), the rest of the solve builds its Hessians over all of G
  // too. 0: never.
  int escalate_after_cut_iterations = 3;
  // Once the Hessians are built over all of G (above), a projected step that Armijo again
  // cut escalate_after_cuts times switches the rest of the solve to this projection, the
  // one nearest the exact Hessian (each sample's own Hessian with its negative eigenvalues
  // clamped). Delete (H2 alone) drops curvature along directions where the exact Hessian
  // is large but indefinite elsewhere, so the exact system cannot stand in: every Delete
  // step overshot ~10^4 times, Armijo cut it to 1/4096-1/8192 and the energy crawled to
  // stagnation (bench_stress --trace, issue #20: fork/hinge_steps, 10 of 198 frames
  // stopped after 17-33 iterations; FullProj 2 at most). Set it to the solve's own
  // projection to never switch.
  HessianProjection escalate_projection = HessianProjection::FullProj;
  // A solve still running after this many iterations switches to escalate_projection too
  // (0: never): a projection stiffer than the energy (PartProj: H2 plus H1's positive
  // part, where H1's negative part softens the energy) takes full steps that fall short,
  // never cut, so the rule above never fires (issue #20: grid_3/hinge_posed with PartProj
  // at t = 0.70, a basin change, at the cap where FullProj ends in 79 iterations; with
  // the switch after 20: 77 iterations, no frame of the sequence at the cap). Off here
  // (keyframe authoring, whose long solves were not measured with it); interpolation
  // turns it on (InterpolationOptions::escalate_after_iterations).
  int escalate_after_iterations = 0;
  // From this iteration of a solve on (0: never), an exact system that is indefinite is
  // shifted instead of replaced by the projection: factored with ridges μ = 1e-9, 1e-8,
  // …, 1e-1 · max|diag H| until it is positive definite, then solved with 2μ, so its
  // lowest eigenvalue λ gets a curvature 2μ + λ ≥ |λ| and every other mode keeps its own
  // (a Levenberg–Marquardt step on the true curvature). Near a saddle of the energy a
  // projection gives the negative-curvature direction a positive curvature, each step
  // moves the map only a little along it and Newton crawls (bench_stress --trace, issue
  // #20: grid_3/hinge_posed with PartProj at t = 0.70, 100 full steps lowering the energy
  // by 3-8e-6 each, the exact system indefinite in every one). Its decrement is not the
  // Newton decrement: a shifted system never ends a solve as converged.
  // Off by default: measured on that frame (CPU core, 100 frames per interval), it did not
  // end it (PartProj still at the cap with shift_after = 6) and it put FullProj's frame
  // there too (79 iterations without it): the decade-coarse shift, doubled, damps every
  // mode by up to 20× the negative eigenvalue, and the shifted steps, taken in full,
  // crawl along the valley that the projection's expanded steps (step expansion above)
  // cross faster. Kept as an option (newton_run's tests drive it).
  int shift_after = 0;
  bool certify = true;            // accept a step only if the certificate passes
  // A start the certificate refuses (finite energy: no sample folds) is solved from all
  // the same: the line search accepts certified steps only, so the first step taken
  // leaves the solve on a certified map; only a solve that takes none stops as
  // StartNotCertified (the final map is then the start, flagged not certified). A
  // keyframe authored at the fold limit is certified with a margin at round-off level,
  // and its coefficients in the interpolation's reduced space (MapSpace::reduce, then
  // expand) differ from it by round-off, which the certificate, counting its own
  // rounding, refuses: the first frame after it then stopped at once, not certified
  // (the stress corpus' grid_6/bend_steps, 1 to 3 frames per run). false: stop at once.
  bool from_uncertified_start = true;
  // A step is accepted only where the certificate proves a margin: min over ∂Ω of
  // |f_z| − |f_zbar| (CertificateResult::min_margin, the certified lower bound of σ2) at
  // least min_margin times the certified upper bound of σ1 (so κ ≤ 1/min_margin), or the
  // start's own share where that is smaller (a certified start nearer the fold may move,
  // never nearer to it; the start itself is not held to it). 0: any certified map. Keyframe authoring asks for 1e-6 (KeyframeOptions): a drag that
  // would fold otherwise stops at a map whose margin is at round-off level, and that
  // map's coefficients in the interpolation's reduced space, equal to it up to
  // round-off, are not certified (the stress corpus' grid_6/bend_steps: the frames after
  // its keyframe 0 could not be certified, 59 of 60 with FullProj).
  double min_margin = 0;
  // The certificate of x0's map when the caller has it already (a warm start from the
  // previous frame's solution), certified or not: not computed again. Must be of
  // space.expand(x0) exactly.
  const CertificateResult* start_certificate = nullptr;
  // Chord steps (issue #23: a warm-started frame built and factored two systems, the first
  // step's projected one and the exact one whose decrement ends the solve: ~0.7 of a CUDA
  // frame's ~1 ms, most of a CPU frame). With a slot here (the caller keeps it between
  // solves: an interpolation sequence's frames), every exact system the loop factors is
  // kept in it (the last one replaces the others), and a solve's first step is a chord
  // step: the gradient at x solved with the kept factor (the previous frame's last exact
  // Hessian, built at this frame's start), in that system's own rotation frame; no
  // Hessian is built and nothing is factored. Its full step must pass Armijo, else the
  // iteration builds its system at x as without a slot; the iterations after it are the
  // loop's own. (Chord steps after the first were tried, on the tests' twist scene: every
  // second one overshot, |d| 3x the exact step's, and failed Armijo; the kept Hessian is
  // off along some direction once the map has moved by a step, cause not established;
  // with this point's rotation frame instead of the kept one's, |d| was 1000x. Measured
  // again on bar_holes, 60 frames: after the chord step, gᵀK⁻¹g is 100 to 26,000 times
  // the exact decrement there, with the rotation freed or gauged, while at the start
  // the two agree within 1 to 5 %; so neither a second chord step nor a stopping test
  // on the kept system, Deuflhard's simplified Newton, can replace the exact system.)
  // null: no chord step.
  KeptSystem* kept_system = nullptr;
  // A solve's first step may be a chord step from the kept system (above). false: the
  // start is not the point the kept system was built at (a continuation predictor's
  // start, InterpolationOptions::predict_start), and the first iteration builds its
  // system at x as without a slot; the exact systems it factors are kept as usual. A
  // chord step from such a start overshoots: the kept system is the Hessian modulo the
  // rotation at the point it was built, and the gradient here has a part along the
  // difference of the two points' rotation generators, which that system barely
  // stiffens (chromium_superbomb/hinge, issue #20: the energy up by 0.1 to 3e4 in 95 of
  // 99 chord trials from predicted starts, every one refused by Armijo, with or without
  // the increment's soft modes damped).
  bool chord_from_start = true;
  // With a slot above: a solve whose Hessians moved to all of G (escalate_after_cuts,
  // escalate_after_cut_iterations) marks the slot (KeptSystem::all_samples), and a solve
  // that finds it marked builds its Hessians over all of G from its first iteration. The
  // next frame of a sequence is a map next to this one, where the subset's model is as
  // wrong (bench_stress --trace, issue #20: comb/hole_turn, |G| 2,000, PartProj, 100
  // frames per interval: every fifth frame's steps on H were cut to 1/2 three times, then
  // one step over G ended the frame; 1.79 iterations per frame against Delete's 1.04, and
  // with H = G 1.00, every frame at or below the energy it reached before). On the CPU
  // core a Hessian over G costs |G|/|H| times one over H, so Auto carries only where the
  // exact systems are over G already (the CUDA core).
  AllSamplesCarry carry_all_samples = AllSamplesCarry::Off;
};

struct NewtonIteration {
  double energy = 0, gradient_norm = 0, step = 0, max_safe_step = 0;
  double decrement2 = 0;          // −gᵀd: the squared Newton decrement (predicted decrease of a full step ×2)
  bool exact_hessian = false;     // the system used the unprojected Hessian
  bool chord = false;             // … kept from an earlier solve (NewtonOptions::kept_system), not built at x
  bool shifted = false;           // … shifted to be definite (NewtonOptions::shift_after)
  bool all_samples = false;       // the Hessian was built over all of G (escalated, or an exact system by
                                  // NewtonOptions::exact_samples), not the subset H
  // The projection a projected system used (NewtonOptions::escalate_projection once the
  // solve's own failed).
  HessianProjection projection = HessianProjection::PartProj;
  int backtracks = 0, certificate_rejections = 0;
  double ms = 0;
};

// Why a Newton solve stopped (NewtonResult::stop): set by the loop where it decides, so
// callers count and report reasons without reading the message's wording.
enum class NewtonStop : std::uint8_t {
  Converged,           // the decrement, the decrease or the slope fell below its tolerance
  IterationLimit,      // NewtonOptions::max_iterations steps taken, still decreasing
  Stagnated,           // the energy decreased only linearly and slowly (stagnation_steps in a row)
  CertificateRefused,  // every step that lowered the energy enough was refused by the certificate
  NoDecrease,          // Armijo refused every step (the certificate refused none)
  NotFactored,         // no system could be factored, ridges included
  StartFolds,          // the starting map folds or degenerates at a sample
  StartNotCertified,   // the starting map is not certified
};
inline constexpr int kNewtonStopCount = 8;
// "converged", "iteration limit", "stagnated", "certificate refused", "no decrease",
// "not factored", "start folds", "start not certified".
const char* to_string(NewtonStop stop);

struct NewtonResult {
  Eigen::VectorXd x;
  double energy = 0;
  int iterations = 0;
  bool converged = false;         // stop == NewtonStop::Converged
  NewtonStop stop = NewtonStop::IterationLimit;
  bool certified = false;         // the final map passed the certificate
  CertificateResult certificate;  // of the final map (when certify)
  std::vector<NewtonIteration> log;
  std::string message;            // why it stopped
  double ms = 0;
  // Host time per part: energy_gradient the start and each accepted step (the samples
  // at the new x), hessian the gradient and Hessian (linearize), solve the
  // factorisation, direction and safe step, line_search the trial energies,
  // certificate every certificate.
  struct Timing {
    double energy_gradient = 0, hessian = 0, solve = 0, line_search = 0, certificate = 0;
    Timing& operator+=(const Timing& o) {
      energy_gradient += o.energy_gradient;
      hessian += o.hessian;
      solve += o.solve;
      line_search += o.line_search;
      certificate += o.certificate;
      return *this;
    }
  } timing;
};

// Minimises mean_G E_iso + quad(x) from x0 (a certified map, or see
// NewtonOptions::from_uncertified_start): the core's own stepper where it has one for
// these arguments, else the host stepper.
NewtonResult newton_solve(NewtonCore& core, const MapSpace& space, const Certifier* certifier, const QuadraticTerm* quad,
                          const Eigen::VectorXd& x0, const NewtonOptions& options);

// Seeds a sequence's chord slot at a solution: the exact system at x (the minimiser of
// the core's present energy: a keyframe, whose blended metric is its own), built and
// factored as newton_solve's exact systems are (options' projection, exact_samples,
// exact_modulo_rotation, exact_ridge) and kept in `slot` for the next solve's chord step
// (NewtonOptions::kept_system). Where it does not factor, or x's energy is not finite,
// the slot is left empty. Returns whether it factored. (Issue #20: the first frame
// after a keyframe had no chord step, and where its own end point's exact system did not
// factor, PartProj's case on chromium_superbomb/hinge, neither had the frames after it.)
bool newton_seed_kept_system(NewtonCore& core, const MapSpace& space, const Eigen::VectorXd& x, const NewtonOptions& options,
                             KeptSystem& slot);

// The loop itself over any stepper (newton_solve's body; tests drive it with a fake).
// certify: the stepper's certificates decide steps; rotation_invariant: the energy is
// invariant under the global rotation of the image, so projected systems may free it.
NewtonResult newton_run(NewtonStepper& stepper, bool certify, bool rotation_invariant, const Eigen::VectorXd& x0,
                        const NewtonOptions& options);

}  // namespace hsi
