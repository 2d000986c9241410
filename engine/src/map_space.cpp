// Reduced variables of the harmonic map space (math.md §3, paper §5.3).
#include "hsi/map_space.h"

#include <cmath>
#include <string>

namespace hsi {

MapSpace::MapSpace(const Cage& cage, Gauge gauge) : gauge_(gauge) {
  const int m = cage.vertex_count();
  const int N = cage.hole_count();
  full_size_ = m + N;
  outer_vertices_ = static_cast<int>(cage.loops.front().size());
  if (outer_vertices_ < 3) throw InputError("the cage's outer loop needs at least 3 vertices");
  for (const Loop& l : cage.loops)
    for (const cd& z : l) cage_vertices_.push_back(z);
  for (int j = 0; j < outer_vertices_; ++j) {
    active_.push_back(j);
    if (std::abs(cage_vertices_[static_cast<size_t>(j)] - cage_vertices_[0]) >
        std::abs(cage_vertices_[static_cast<size_t>(rotation_vertex_)] - cage_vertices_[0]))
      rotation_vertex_ = j;
  }
  for (int k = 1; k < static_cast<int>(cage.loops.size()); ++k) {
    const int off = cage.loop_offset(k);
    const int size = static_cast<int>(cage.loops[static_cast<size_t>(k)].size());
    if (size < 3) throw InputError("cage loop of " + loop_name(k) + " needs at least 3 vertices");
    hole_loops_.emplace_back();
    for (int j = 0; j < size; ++j) {
      hole_loops_.back().push_back(off + j);
      if (j >= 2) active_.push_back(off + j);  // the first two carry the null directions a + b w
    }
  }
  for (int h = 0; h < N; ++h) {
    log_columns_.push_back(static_cast<int>(active_.size()));
    active_.push_back(m + h);
  }
  const int n = static_cast<int>(active_.size());
  auto is_log = [&](int a) { return a >= n - N; };

  // Columns of T: one free real variable each; its primary row gets +1.
  std::vector<Eigen::Triplet<double>> t;
  int col = 0;
  for (int a = 0; a < n; ++a) {  // Re φ_a
    if (gauge_ == Gauge::ModuloRigid && (a == 0 || a == rotation_vertex_)) continue;
    t.emplace_back(a, col, 1.0);
    if (is_log(a)) t.emplace_back(2 * n + a, col, 1.0);  // Re ψ_log = Re φ_log
    ++col;
  }
  for (int a = 0; a < n; ++a) {  // Im φ_a
    if (gauge_ == Gauge::ModuloRigid && a == 0) continue;
    t.emplace_back(n + a, col, 1.0);
    if (is_log(a)) t.emplace_back(3 * n + a, col, -1.0);  // Im ψ_log = −Im φ_log
    ++col;
  }
  for (int part = 2; part <= 3; ++part)  // Re ψ_a, Im ψ_a: not at outer vertex 0, not the log columns
    for (int a = 1; a < n - N; ++a) t.emplace_back(part * n + a, col++, 1.0);
  T_.resize(4 * n, col);
  T_.setFromTriplets(t.begin(), t.end());
  primary_rows_.resize(static_cast<size_t>(col));
  for (int c = 0; c < col; ++c) primary_rows_[static_cast<size_t>(c)] = static_cast<int>(Eigen::SparseMatrix<double>::InnerIterator(T_, c).row());
}

Eigen::VectorXd MapSpace::rotation_generator(const Eigen::VectorXd& v) const {
  const Eigen::Index n = this->n();
  if (v.size() != 4 * n) throw InputError("rotation_generator: expected " + std::to_string(4 * n) + " active coefficients");
  Eigen::VectorXd u(4 * n);
  u << -v.segment(n, n), v.segment(0, n), v.segment(3 * n, n), -v.segment(2 * n, n);
  return u;
}

Eigen::VectorXd MapSpace::regauge(const Eigen::VectorXd& v) const {
  const Eigen::Index n = this->n();
  if (gauge_ != Gauge::ModuloRigid) throw InputError("regauge: only the ModuloRigid space has a rotation gauge");
  if (v.size() != 4 * n) throw InputError("regauge: expected " + std::to_string(4 * n) + " active coefficients");
  // φ_r ↦ r φ_r ∈ i R+ with |r| = 1: r = i conj(φ_r) / |φ_r| (as reduce() does).
  const cd p(v(rotation_vertex_), v(n + rotation_vertex_));
  const cd r = std::abs(p) > 0 ? cd(0, 1) * std::conj(p) / std::abs(p) : cd(1);
  Eigen::VectorXd x(dim());
  for (int c = 0; c < dim(); ++c) {
    const Eigen::Index row = primary_rows_[static_cast<size_t>(c)], a = row % n, part = row / n;
    const cd z = part < 2 ? r * cd(v(a), v(n + a)) : std::conj(r) * cd(v(2 * n + a), v(3 * n + a));
    x(c) = part % 2 == 0 ? z.real() : z.imag();
  }
  return x;
}

MatrixXcd MapSpace::restrict_columns(const MatrixXcd& full_rows) const {
  MatrixXcd out(full_rows.rows(), n());
  for (int a = 0; a < n(); ++a) out.col(a) = full_rows.col(active_[static_cast<size_t>(a)]);
  return out;
}

HarmonicMap MapSpace::expand(const Eigen::VectorXd& x) const {
  if (x.size() != dim())
    throw InputError("reduced vector has " + std::to_string(x.size()) + " entries; the map space has " +
                     std::to_string(dim()));
  const Eigen::VectorXd v = T_ * x;
  const int N = static_cast<int>(log_columns_.size());
  const int n = this->n();
  HarmonicMap map{VectorXcd::Zero(full_size_), VectorXcd::Zero(full_size_)};
  for (int a = 0; a < n; ++a) {
    const int j = active_[static_cast<size_t>(a)];
    map.phi(j) = cd(v(a), v(n + a));
    map.psi(j) = cd(v(2 * n + a), v(3 * n + a));
  }
  (void)N;
  return map;
}

MapSpace::Canonical MapSpace::reduce(const HarmonicMap& input) const {
  if (input.phi.size() != full_size_ || input.psi.size() != full_size_)
    throw InputError("coefficient vectors have " + std::to_string(input.phi.size()) + " (phi) and " +
                     std::to_string(input.psi.size()) + " (psi) entries; the cage needs " +
                     std::to_string(full_size_) + " each");
  const int m = full_size_ - static_cast<int>(log_columns_.size());
  const double scale = std::max(1.0, input.phi.cwiseAbs().maxCoeff());
  for (int h = 0; h < static_cast<int>(log_columns_.size()); ++h) {
    const cd p = input.phi(m + h), q = input.psi(m + h);
    if (std::abs(q - std::conj(p)) > 1e-9 * scale)
      throw InputError("hole " + std::to_string(h + 1) + " column: psi must equal conj(phi) (paper Eq. 3), got phi = (" +
                       std::to_string(p.real()) + ", " + std::to_string(p.imag()) + "), psi = (" +
                       std::to_string(q.real()) + ", " + std::to_string(q.imag()) + ")");
  }
  HarmonicMap map = input;
  // Remove each hole loop's null component a + b z (its Cauchy integral vanishes on Ω).
  for (const auto& loop : hole_loops_)
    for (VectorXcd* c : {&map.phi, &map.psi}) {
      const int j0 = loop[0], j1 = loop[1];
      const cd z0 = cage_vertices_[static_cast<size_t>(j0)], z1 = cage_vertices_[static_cast<size_t>(j1)];
      const cd b = ((*c)(j1) - (*c)(j0)) / (z1 - z0);
      const cd a = (*c)(j0) - b * z0;
      for (int j : loop) (*c)(j) -= a + b * cage_vertices_[static_cast<size_t>(j)];
      (*c)(j0) = (*c)(j1) = 0.0;
    }
  // Ψ's constant moves into Φ: f = Φ + conj Ψ is unchanged.
  const cd psi0 = map.psi(0);
  for (int j = 0; j < outer_vertices_; ++j) {
    map.psi(j) -= psi0;
    map.phi(j) += std::conj(psi0);
  }
  Canonical out;
  if (gauge_ == Gauge::ModuloRigid) {
    out.translation = map.phi(0);
    for (int j = 0; j < outer_vertices_; ++j) map.phi(j) -= out.translation;
    const cd p1 = map.phi(rotation_vertex_);
    const cd r = std::abs(p1) > 0 ? cd(0, 1) * std::conj(p1) / std::abs(p1) : cd(1);  // r φ_r ∈ i R+
    map.phi *= r;
    map.psi *= std::conj(r);
    out.rotation = std::conj(r);
  }
  const int n = this->n();
  Eigen::VectorXd v(4 * n);
  for (int a = 0; a < n; ++a) {
    const int j = active_[static_cast<size_t>(a)];
    v(a) = map.phi(j).real();
    v(n + a) = map.phi(j).imag();
    v(2 * n + a) = map.psi(j).real();
    v(3 * n + a) = map.psi(j).imag();
  }
  // x is read off each column's primary row (its first, +1 entry).
  out.x.resize(dim());
  for (int c = 0; c < dim(); ++c) out.x(c) = v(primary_rows_[static_cast<size_t>(c)]);
  return out;
}

}  // namespace hsi

#include <Eigen/SVD>

namespace hsi {

Eigen::MatrixXd reduced_evaluation_matrix(const MapSpace& space, const BasisRows& rows) {
  const int n = space.n();
  const cd I(0, 1);
  Eigen::MatrixXd Mv;
  if (space.gauge() == Gauge::Map) {
    const MatrixXcd C = space.restrict_columns(rows.C);
    const Eigen::Index P = C.rows();
    Mv.setZero(2 * P, 4 * n);
    for (int a = 0; a < n; ++a)
      for (Eigen::Index p = 0; p < P; ++p) {
        const cd c = C(p, a);
        const cd d[4] = {c, I * c, std::conj(c), -I * std::conj(c)};  // ∂f/∂(Re φ, Im φ, Re ψ, Im ψ)
        for (int k = 0; k < 4; ++k) {
          Mv(2 * p, k * n + a) = d[k].real();
          Mv(2 * p + 1, k * n + a) = d[k].imag();
        }
      }
  } else {
    const MatrixXcd D = space.restrict_columns(rows.D);
    const Eigen::Index P = D.rows();
    Mv.setZero(4 * P, 4 * n);
    for (int a = 0; a < n; ++a)
      for (Eigen::Index p = 0; p < P; ++p) {
        const cd d = D(p, a);
        // a = D φ: rows (Re a, Im a); b = D ψ: rows (Re b, Im b). Paper Eq. 13.
        Mv(4 * p, a) = d.real();
        Mv(4 * p, n + a) = -d.imag();
        Mv(4 * p + 1, a) = d.imag();
        Mv(4 * p + 1, n + a) = d.real();
        Mv(4 * p + 2, 2 * n + a) = d.real();
        Mv(4 * p + 2, 3 * n + a) = -d.imag();
        Mv(4 * p + 3, 2 * n + a) = d.imag();
        Mv(4 * p + 3, 3 * n + a) = d.real();
      }
  }
  return Mv * space.T();
}

Conditioning conditioning(const MapSpace& space, const BasisRows& rows) {
  const Eigen::MatrixXd M = reduced_evaluation_matrix(space, rows);
  Eigen::BDCSVD<Eigen::MatrixXd> svd(M);
  const auto& s = svd.singularValues();
  return {s.minCoeff(), s.maxCoeff(), static_cast<int>(M.rows()), static_cast<int>(M.cols())};
}

}  // namespace hsi
