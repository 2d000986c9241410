// The CPU evaluator of f at fixed points from cached basis rows (hsi/mesh_evaluator.h).
// The rows are kept in blocks of kBlock points, each block column-major and contiguous,
// so that a block's products stream through memory once and stay in cache for the
// second product. f takes two real products instead of two complex ones: with
// C = A + iB, s = φ + ψ and d = φ − ψ,
//   Re f = Re(C φ) + Re(C ψ) = A Re s − B Im s,   Im f = Im(C φ) − Im(C ψ) = A Im d + B Re d,
// so [Re f, Im f] = [A | B] · [[Re s, Im d], [−Im s, Re d]]: half the arithmetic.
#include "hsi/mesh_evaluator.h"

#include <algorithm>
#include <string>
#include <vector>

#include "hsi/domain.h"

namespace hsi {

namespace {

constexpr Eigen::Index kBlock = 128;  // points per block: 128 × 2(m + N) doubles (~170 KB at m + N = 84), L2-sized

class CpuMeshEvaluator final : public MeshEvaluator {
 public:
  CpuMeshEvaluator(const Cage& cage, std::span<const cd> points, const MeshEvaluatorOptions& options)
      : points_(static_cast<Eigen::Index>(points.size())), columns_(basis_size(cage)), derivatives_(options.derivatives) {
    if (cage.vertex_count() < 1) throw InputError("mesh evaluator: the cage has no vertex");
    const unsigned parts = kBasisC | (derivatives_ ? kBasisD : 0u);
    const Eigen::Index blocks = (points_ + kBlock - 1) / kBlock;
    AB_.resize(static_cast<size_t>(blocks));
    if (derivatives_) D_.resize(static_cast<size_t>(blocks));
    // Evaluated a chunk of blocks at a time (evaluate_basis is multi-threaded over
    // points), so that set-up never holds the rows twice.
    constexpr Eigen::Index kChunkBlocks = 64;
    for (Eigen::Index b0 = 0; b0 < blocks; b0 += kChunkBlocks) {
      const Eigen::Index p0 = b0 * kBlock, np = std::min(kChunkBlocks * kBlock, points_ - p0);
      const BasisRows rows = evaluate_basis(cage, points.subspan(static_cast<size_t>(p0), static_cast<size_t>(np)), parts);
      for (Eigen::Index b = b0; b < std::min(blocks, b0 + kChunkBlocks); ++b) {
        const Eigen::Index q0 = b * kBlock - p0, nq = std::min(kBlock, points_ - b * kBlock);
        Eigen::MatrixXd& AB = AB_[static_cast<size_t>(b)];
        AB.resize(nq, 2 * columns_);
        AB.leftCols(columns_) = rows.C.middleRows(q0, nq).real();
        AB.rightCols(columns_) = rows.C.middleRows(q0, nq).imag();
        if (derivatives_) D_[static_cast<size_t>(b)] = rows.D.middleRows(q0, nq);
      }
    }
  }

  const char* name() const override { return "cpu"; }
  std::size_t size() const override { return static_cast<std::size_t>(points_); }
  bool derivatives() const override { return derivatives_; }

  void evaluate(const HarmonicMap& map, MapValues& out) override {
    if (map.phi.size() != columns_ || map.psi.size() != columns_)
      throw InputError("mesh evaluator: the map has " + std::to_string(map.phi.size()) + " (phi) and " +
                       std::to_string(map.psi.size()) + " (psi) coefficients; the cage needs " + std::to_string(columns_));
    out.f.resize(points_);
    out.f_zz.resize(0);
    if (derivatives_) {
      out.f_z.resize(points_);
      out.fzbar_conj.resize(points_);
    } else {
      out.f_z.resize(0);
      out.fzbar_conj.resize(0);
    }
    // f = C φ + conj(C ψ) (harmonic_map.h) as two real products (see the top of this file).
    const Eigen::Index blocks = static_cast<Eigen::Index>(AB_.size()), M = columns_;
    const VectorXcd s = map.phi + map.psi, d = map.phi - map.psi;
    Eigen::VectorXd w_re(2 * M), w_im(2 * M);
    w_re << s.real(), -s.imag();
    w_im << d.imag(), d.real();
#pragma omp parallel
    {
      Eigen::VectorXd re(kBlock), im(kBlock);  // per thread
      // Dynamic: a thread the OS holds back (a busy machine) does not hold back the frame.
#pragma omp for schedule(dynamic, 2)
      for (Eigen::Index b = 0; b < blocks; ++b) {
        const Eigen::MatrixXd& AB = AB_[static_cast<size_t>(b)];
        const Eigen::Index p0 = b * kBlock, np = AB.rows();
        re.head(np).noalias() = AB * w_re;
        im.head(np).noalias() = AB * w_im;
        for (Eigen::Index q = 0; q < np; ++q) out.f(p0 + q) = cd(re(q), im(q));
        if (derivatives_) {
          const MatrixXcd& D = D_[static_cast<size_t>(b)];
          out.f_z.segment(p0, np).noalias() = D * map.phi;         // f_z = D φ
          out.fzbar_conj.segment(p0, np).noalias() = D * map.psi;  // conj f_zbar = D ψ
        }
      }
    }
  }

  bool rows(std::size_t p0, std::size_t count, MatrixXcd& C, MatrixXcd* D) const override {
    if (p0 > static_cast<std::size_t>(points_) || count > static_cast<std::size_t>(points_) - p0)
      throw InputError("mesh evaluator: rows " + std::to_string(p0) + " to " + std::to_string(p0 + count) + " asked of " +
                       std::to_string(points_) + " points");
    if (D && !derivatives_) throw InputError("mesh evaluator: the rows D asked of an evaluator made without derivatives");
    const Eigen::Index first = static_cast<Eigen::Index>(p0), n = static_cast<Eigen::Index>(count), M = columns_;
    C.resize(n, M);
    if (D) D->resize(n, M);
    for (Eigen::Index q = 0; q < n;) {  // block by block: the rows [first + q, …) within block b
      const Eigen::Index p = first + q, b = p / kBlock, in = p - b * kBlock;
      const Eigen::MatrixXd& AB = AB_[static_cast<size_t>(b)];
      const Eigen::Index take = std::min(AB.rows() - in, n - q);
      C.middleRows(q, take).real() = AB.block(in, 0, take, M);
      C.middleRows(q, take).imag() = AB.block(in, M, take, M);
      if (D) D->middleRows(q, take) = D_[static_cast<size_t>(b)].middleRows(in, take);
      q += take;
    }
    return true;
  }

 private:
  Eigen::Index points_ = 0, columns_ = 0;
  bool derivatives_ = false;
  std::vector<Eigen::MatrixXd> AB_;  // per block of kBlock points: [Re C | Im C], kBlock × 2(m + N)
  std::vector<MatrixXcd> D_;         // per block: the rows D, kBlock × (m + N)
};

}  // namespace

std::unique_ptr<MeshEvaluator> make_cpu_mesh_evaluator(const Cage& cage, std::span<const cd> points,
                                                       const MeshEvaluatorOptions& options) {
  return std::make_unique<CpuMeshEvaluator>(cage, points, options);
}

namespace {
class BorrowedEvaluator final : public MeshEvaluator {
 public:
  explicit BorrowedEvaluator(MeshEvaluator& e) : e_(e) {}
  const char* name() const override { return e_.name(); }
  std::size_t size() const override { return e_.size(); }
  bool derivatives() const override { return e_.derivatives(); }
  void evaluate(const HarmonicMap& map, MapValues& out) override { e_.evaluate(map, out); }
  bool rows(std::size_t p0, std::size_t count, MatrixXcd& C, MatrixXcd* D) const override { return e_.rows(p0, count, C, D); }

 private:
  MeshEvaluator& e_;
};
}  // namespace

std::unique_ptr<MeshEvaluator> borrow_evaluator(MeshEvaluator& evaluator) { return std::make_unique<BorrowedEvaluator>(evaluator); }

double mesh_evaluator_bytes(const Cage& cage, std::size_t points, const MeshEvaluatorOptions& options) {
  return static_cast<double>(points) * basis_size(cage) * sizeof(cd) * (options.derivatives ? 2.0 : 1.0);
}

}  // namespace hsi
