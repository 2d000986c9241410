// The CUDA mesh evaluator (hsi/cuda/mesh_evaluator.h): the rows at the points live on
// the device, column-major P × M as Eigen would store them; per map one coefficient
// upload through pinned memory, one kernel (mesh_kernels.cu) and, for evaluate(), one
// download.
#include "hsi/cuda/mesh_evaluator.h"

#include <algorithm>
#include <functional>
#include <string>

#include "device.h"
#include "hsi/domain.h"
#include "mesh_kernels.h"

namespace hsi::cuda {

namespace {
size_t sz(long long v) { return static_cast<size_t>(v); }
}  // namespace

struct MeshEvaluator::Impl {
  long long P = 0;
  int M = 0;
  bool derivatives = false;
  Stream stream;  // first: everything below is used on it
  DeviceArray<double2> C, D, coef, values;
  Upload<double2> coef_up;
  PinnedArray<double2> values_down;

  // fill(p0, np, C, D): the rows of points [p0, p0 + np) into the host blocks (D: null
  // without derivatives).
  using Fill = std::function<void(long long, long long, MatrixXcd&, MatrixXcd*)>;
  Impl(long long points, int columns, const MeshEvaluatorOptions& o, const Fill& fill)
      : P(points),
        M(columns),
        derivatives(o.derivatives),
        C(sz(P) * sz(M)),
        D(o.derivatives ? sz(P) * sz(M) : 0),
        coef(2 * sz(M)),
        values((o.derivatives ? 3 : 1) * sz(P)),
        coef_up(2 * sz(M)),
        values_down((o.derivatives ? 3 : 1) * sz(P)) {
    static_assert(sizeof(cd) == sizeof(double2), "std::complex<double> and double2 share a layout");
    // The rows a chunk of points at a time (bounded host memory), each chunk's np × M
    // block copied into the P × M device matrix at its rows.
    constexpr long long kChunk = 16384;
    MatrixXcd rc, rd;
    for (long long p0 = 0; p0 < P; p0 += kChunk) {
      const long long np = std::min(kChunk, P - p0);
      fill(p0, np, rc, derivatives ? &rd : nullptr);
      auto put = [&](const MatrixXcd& block, DeviceArray<double2>& dst) {
        HSI_CUDA_CHECK(cudaMemcpy2DAsync(dst.get() + p0, sz(P) * sizeof(double2), block.data(), sz(np) * sizeof(double2),
                                         sz(np) * sizeof(double2), sz(M), cudaMemcpyHostToDevice, stream));
      };
      put(rc, C);
      if (derivatives) put(rd, D);
      // The host blocks are pageable and are overwritten by the next chunk.
      HSI_CUDA_CHECK(cudaStreamSynchronize(stream));
    }
  }

  void enqueue(const HarmonicMap& map) {
    if (map.phi.size() != M || map.psi.size() != M)
      throw InputError("mesh evaluator: the map has " + std::to_string(map.phi.size()) + " (phi) and " +
                       std::to_string(map.psi.size()) + " (psi) coefficients; the cage needs " + std::to_string(M));
    double2* c = coef_up.begin_fill();
    std::copy(map.phi.data(), map.phi.data() + M, reinterpret_cast<cd*>(c));
    std::copy(map.psi.data(), map.psi.data() + M, reinterpret_cast<cd*>(c) + M);
    coef_up.send(coef.get(), coef.size(), stream);
    HSI_CUDA_CHECK(kernels::mesh_values(P, M, C.get(), derivatives ? D.get() : nullptr, coef.get(), values.get(), stream));
  }
};

MeshEvaluator::MeshEvaluator(const Cage& cage, std::span<const cd> points, const MeshEvaluatorOptions& options) {
  if (cage.vertex_count() < 1) throw InputError("mesh evaluator: the cage has no vertex");
  const unsigned parts = kBasisC | (options.derivatives ? kBasisD : 0u);
  impl_ = std::make_unique<Impl>(static_cast<long long>(points.size()), basis_size(cage), options,
                                 [&](long long p0, long long np, MatrixXcd& C, MatrixXcd* D) {
                                   BasisRows rows = evaluate_basis(cage, points.subspan(sz(p0), sz(np)), parts);
                                   C = std::move(rows.C);
                                   if (D) *D = std::move(rows.D);
                                 });
}

MeshEvaluator::MeshEvaluator(const hsi::MeshEvaluator& source, const MeshEvaluatorOptions& options) {
  if (options.derivatives && !source.derivatives())
    throw InputError("mesh evaluator: derivatives asked of rows made without them");
  MatrixXcd probe;  // no rows: 0 × (m + N), the columns
  if (!source.rows(0, 0, probe, nullptr))
    throw InputError(std::string("mesh evaluator: the ") + source.name() + " evaluator keeps no rows on the host to copy");
  const long long P = static_cast<long long>(source.size());
  impl_ = std::make_unique<Impl>(P, static_cast<int>(probe.cols()), options, [&](long long p0, long long np, MatrixXcd& C, MatrixXcd* D) {
    source.rows(sz(p0), sz(np), C, D);
  });
}

MeshEvaluator::~MeshEvaluator() {
  if (impl_) cudaStreamSynchronize(impl_->stream);  // nothing in flight while the members free their memory
}

std::size_t MeshEvaluator::size() const { return sz(impl_->P); }
bool MeshEvaluator::derivatives() const { return impl_->derivatives; }
void MeshEvaluator::enqueue(const HarmonicMap& map) { impl_->enqueue(map); }
void MeshEvaluator::synchronize() { HSI_CUDA_CHECK(cudaStreamSynchronize(impl_->stream)); }
const cd* MeshEvaluator::device_values() const { return reinterpret_cast<const cd*>(impl_->values.get()); }

void MeshEvaluator::evaluate(const HarmonicMap& map, MapValues& out) {
  Impl& I = *impl_;
  I.enqueue(map);
  if (I.values.size())
    HSI_CUDA_CHECK(cudaMemcpyAsync(I.values_down.get(), I.values.get(), I.values.bytes(), cudaMemcpyDeviceToHost, I.stream));
  HSI_CUDA_CHECK(cudaStreamSynchronize(I.stream));
  const Eigen::Index P = static_cast<Eigen::Index>(I.P);
  const cd* v = reinterpret_cast<const cd*>(I.values_down.get());
  out.f = Eigen::Map<const VectorXcd>(v, P);
  out.f_zz.resize(0);
  if (I.derivatives) {
    out.f_z = Eigen::Map<const VectorXcd>(v + P, P);
    out.fzbar_conj = Eigen::Map<const VectorXcd>(v + 2 * P, P);
  } else {
    out.f_z.resize(0);
    out.fzbar_conj.resize(0);
  }
}

}  // namespace hsi::cuda
