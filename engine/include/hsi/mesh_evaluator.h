// f of many maps at one fixed set of points (a mesh's vertices), from cached basis
// rows (issue #23): the rows C (and D) at the points are evaluated once, then each map
// costs one dense product, f = C φ + conj(C ψ) (harmonic_map.h), instead of the basis
// evaluated again at every point for every frame. The CPU evaluator here is the
// readable reference; the CUDA one (hsi/cuda/mesh_evaluator.h) keeps the rows on the
// GPU. runtime/'s factory (hsi/runtime/backend.h) picks one by backend name.
#pragma once

#include <cstddef>
#include <memory>
#include <span>

#include "hsi/harmonic_map.h"

namespace hsi {

struct MeshEvaluatorOptions {
  bool derivatives = false;  // also f_z and conj f_zbar (the rows D are cached too)
};

class MeshEvaluator {
 public:
  virtual ~MeshEvaluator() = default;
  virtual const char* name() const = 0;  // "cpu", "cuda"
  virtual std::size_t size() const = 0;  // the number of points
  virtual bool derivatives() const = 0;
  // f at every point (and f_z, fzbar_conj where set up with derivatives; f_zz stays
  // empty), into `out`, reusing its storage. InputError if the map is not of the cage
  // the evaluator was made for.
  virtual void evaluate(const HarmonicMap& map, MapValues& out) = 0;
  MapValues evaluate(const HarmonicMap& map) {
    MapValues v;
    evaluate(map, v);
    return v;
  }
  // The cached rows of the points [p0, p0 + count) as evaluate_basis gives them: C into
  // `C`, resized to count × (m + N) (count 0 gives the columns), and, where `D` is not null, D into it (the evaluator must keep
  // them: derivatives()). For an evaluator of another backend made from rows already
  // evaluated (hsi/cuda/mesh_evaluator.h) instead of evaluating the basis again. False,
  // nothing written, where this evaluator does not keep them on the host; InputError for
  // a range past size() or D asked of an evaluator without derivatives.
  virtual bool rows(std::size_t /*p0*/, std::size_t /*count*/, MatrixXcd& /*C*/, MatrixXcd* /*D*/) const { return false; }
};

// The rows at `points` (none may lie on the cage or at a hole point) are evaluated
// here, multi-threaded; per map, OpenMP over blocks of points. Same values as
// evaluate_map(cage, map, points) up to the order of summation. InputError for a cage
// of no vertex.
std::unique_ptr<MeshEvaluator> make_cpu_mesh_evaluator(const Cage& cage, std::span<const cd> points,
                                                       const MeshEvaluatorOptions& options = {});

// An evaluator that forwards every call to `evaluator`, which must outlive it: lends one
// evaluator to owners that each want their own (a batch worker's Interpolators, one after
// another), so that its rows are evaluated once.
std::unique_ptr<MeshEvaluator> borrow_evaluator(MeshEvaluator& evaluator);

// Bytes of cached basis rows an evaluator holds for this many points (per backend copy).
double mesh_evaluator_bytes(const Cage& cage, std::size_t points, const MeshEvaluatorOptions& options = {});

}  // namespace hsi
