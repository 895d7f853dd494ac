#include "fem/block_amg.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <numeric>
#include <stdexcept>

#include <Eigen/Dense>

#include "fem/cholmod_factor.h"

namespace spec2fab::fem {
// Named, not anonymous: BlockAmgSolver::Impl holds these types.
namespace block_amg_detail {

constexpr int kModes = 6;  // the rigid-body modes: the coarse levels' block size
// Strong coupling on the finest level (halved on each coarser one): a
// soft node next to a 1e3 times stiffer one is weak (√1e-3 ≈ 0.03), so
// aggregates do not straddle a material interface.
constexpr double kStrongFinest = 0.08;
// The finest level's aggregates reach two strong steps from their root
// (PETSc's GAMG aggregates on A²'s graph for the same reason): on the 321k-tet
// cantilever one step gave 23,604 coarse rows whose next coarsening was
// poor (97 CG iterations), two steps 5,298 rows solved directly (38).
constexpr int kFinestRadius = 2;
// A coarse level of up to this many scalar rows is solved by a sparse
// Cholesky factor (CHOLMOD) rather than coarsened again; the finest level is
// coarsened at least once unless it has no more than kDirectRows.
constexpr int kCoarsestRows = 20000;
constexpr int kDirectRows = 600;
constexpr int kMaxLevels = 12;
constexpr int kLanczosSteps = 12;
// Chebyshev over [0.1 λ, 1.1 λ] of D⁻¹A, degree 2 (PETSc's GAMG defaults).
constexpr int kChebyshevDegree = 2;
constexpr double kChebyshevLow = 0.1, kChebyshevHigh = 1.1;
constexpr double kProlongatorDamping = 4.0 / 3.0;  // ω λ (Vaněk et al.)

using Vector = Eigen::VectorXd;

// B × B blocks in compressed rows, each row's columns sorted; a block's
// values row-major.
struct BlockMatrix {
  int block = 3;
  std::vector<int> start{0};
  std::vector<int> column;
  std::vector<double> values;
  // The values rounded to float, for the multigrid's own products: they
  // read half the memory (the products are bound by it), and CG keeps the
  // exact operator in `values`. Rounding keeps the matrix symmetric, so the
  // multigrid stays a symmetric preconditioner.
  std::vector<float> single;
  int rows() const { return static_cast<int>(start.size()) - 1; }
  size_t block_size() const { return static_cast<size_t>(block * block); }
  double* at(size_t k) { return values.data() + k * block_size(); }
  const double* at(size_t k) const { return values.data() + k * block_size(); }
  // Row i's diagonal block (every row has one).
  size_t diagonal(int i) const {
    const auto row = column.begin() + start[static_cast<size_t>(i)];
    return static_cast<size_t>(
        std::lower_bound(row, column.begin() + start[static_cast<size_t>(i) + 1], i) -
        column.begin());
  }
};

// The prolongator: rows of B × 6 blocks (row-major), columns unsorted.
struct Prolongator {
  int block = 3;
  std::vector<int> start{0};
  std::vector<int> column;
  std::vector<double> values;
  size_t block_size() const { return static_cast<size_t>(block * kModes); }
  const double* at(size_t k) const { return values.data() + k * block_size(); }
};

template <int B, class Value>
void multiply(const BlockMatrix& a, const Value* v, const double* x, double* y) {
  const int n = a.rows();
  const int* start = a.start.data();
  const int* column = a.column.data();
  for (int i = 0; i < n; ++i) {
    double sum[B] = {};
    for (int k = start[i]; k < start[i + 1]; ++k) {
      const Value* block = v + static_cast<size_t>(k) * B * B;
      const double* xj = x + static_cast<size_t>(column[k]) * B;
      for (int r = 0; r < B; ++r)
        for (int c = 0; c < B; ++c) sum[r] += block[r * B + c] * xj[c];
    }
    for (int r = 0; r < B; ++r) y[static_cast<size_t>(i) * B + r] = sum[r];
  }
}

void multiply(const BlockMatrix& a, const Vector& x, Vector& y) {
  if (a.block == 3)
    multiply<3>(a, a.values.data(), x.data(), y.data());
  else
    multiply<kModes>(a, a.values.data(), x.data(), y.data());
}

// y = A x with the float values (the multigrid's smoothing and residuals).
void multiply_single(const BlockMatrix& a, const Vector& x, Vector& y) {
  if (a.block == 3)
    multiply<3>(a, a.single.data(), x.data(), y.data());
  else
    multiply<kModes>(a, a.single.data(), x.data(), y.data());
}

// x += P xc
template <int B>
void prolong_add(const Prolongator& p, const double* coarse, double* x) {
  const int n = static_cast<int>(p.start.size()) - 1;
  for (int i = 0; i < n; ++i) {
    double sum[B] = {};
    for (int k = p.start[i]; k < p.start[i + 1]; ++k) {
      const double* block = p.values.data() + static_cast<size_t>(k) * B * kModes;
      const double* xc = coarse + static_cast<size_t>(p.column[k]) * kModes;
      for (int r = 0; r < B; ++r)
        for (int c = 0; c < kModes; ++c) sum[r] += block[r * kModes + c] * xc[c];
    }
    for (int r = 0; r < B; ++r) x[static_cast<size_t>(i) * B + r] += sum[r];
  }
}

// coarse = Pᵀ r
template <int B>
void restrict_to(const Prolongator& p, const double* r, double* coarse, size_t coarse_size) {
  std::fill(coarse, coarse + coarse_size, 0.0);
  const int n = static_cast<int>(p.start.size()) - 1;
  for (int i = 0; i < n; ++i) {
    const double* ri = r + static_cast<size_t>(i) * B;
    for (int k = p.start[i]; k < p.start[i + 1]; ++k) {
      const double* block = p.values.data() + static_cast<size_t>(k) * B * kModes;
      double* to = coarse + static_cast<size_t>(p.column[k]) * kModes;
      for (int r2 = 0; r2 < B; ++r2)
        for (int c = 0; c < kModes; ++c) to[c] += block[r2 * kModes + c] * ri[r2];
    }
  }
}

// One level of the hierarchy and its work vectors.
struct Level {
  BlockMatrix a;
  Vector inverse_diagonal;
  double lambda = 1;          // largest eigenvalue of D⁻¹A (Lanczos, from below)
  std::vector<double> modes;  // near-nullspace: block × 6 per node, row-major
  Prolongator p;              // to the next level (none on the coarsest)
  Vector b, x, r, d, t;
  size_t size() const { return static_cast<size_t>(a.rows()) * static_cast<size_t>(a.block); }
};

// The largest eigenvalue of D⁻¹A: the Lanczos matrix of a few steps of
// Jacobi-preconditioned CG (its extreme Ritz value converges first), from a
// fixed pseudo-random start.
double largest_eigenvalue(const Level& level) {
  const auto n = static_cast<long>(level.size());
  Vector r(n), z(n), p(n), q(n);
  std::uint64_t state = 0x9E3779B97F4A7C15ull;
  for (long i = 0; i < n; ++i) {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    r[i] = static_cast<double>(state >> 11) * 0x1.0p-53 - 0.5;
  }
  z = level.inverse_diagonal.cwiseProduct(r);
  p = z;
  double rz = r.dot(z);
  std::vector<double> alpha, beta;
  for (int step = 0; step < kLanczosSteps && step < n; ++step) {
    multiply(level.a, p, q);
    const double pq = p.dot(q);
    if (!(pq > 0) || !(rz > 0)) break;
    alpha.push_back(rz / pq);
    r -= alpha.back() * q;
    z = level.inverse_diagonal.cwiseProduct(r);
    const double rz_next = r.dot(z);
    beta.push_back(rz_next / rz);
    if (!(rz_next > 1e-30 * rz)) break;
    p = z + beta.back() * p;
    rz = rz_next;
  }
  const auto m = static_cast<long>(alpha.size());
  if (m == 0) return 1.0;
  Eigen::MatrixXd t = Eigen::MatrixXd::Zero(m, m);
  for (long k = 0; k < m; ++k) {
    const auto ku = static_cast<size_t>(k);
    t(k, k) = 1 / alpha[ku] + (k > 0 ? beta[ku - 1] / alpha[ku - 1] : 0.0);
    if (k + 1 < m) t(k, k + 1) = t(k + 1, k) = std::sqrt(beta[ku]) / alpha[ku];
  }
  return Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(t, Eigen::EigenvaluesOnly)
      .eigenvalues()
      .maxCoeff();
}

}  // namespace block_amg_detail
using namespace block_amg_detail;

struct BlockAmgSolver::Impl {
  double tolerance = 1e-10;
  int max_iterations = 1000;
  // The finest level's node rows.
  std::vector<int> row_of_free;    // free DOF -> scalar row (3·node + axis)
  std::vector<int> diagonal_slot;  // per node: its diagonal block
  std::vector<char> prescribed;    // per scalar row: an identity row
  std::vector<Vec3> positions;     // per node
  std::vector<Level> levels;
  CholmodFactor coarsest;
  Vector cg_x, cg_r, cg_p, cg_q;  // CG's solution, residual, direction, A·direction
  int iterations = 0;
  double relative_residual = 0;
  bool ready = false;  // the last setup built a hierarchy

  void fine_pattern(const Matrix& lower);
  void fine_values(const Matrix& lower);
  bool build_hierarchy();
  // The steps of one coarsening.
  int aggregate(const Level& level, double strong, std::vector<int>& aggregate_of) const;
  void tentative(Level& level, Level& next, const std::vector<int>& aggregate_of, int aggregates,
                 std::vector<double>& tentative_blocks) const;
  template <int B>
  void smooth_prolongator(Level& level, const std::vector<int>& aggregate_of,
                          const std::vector<double>& t, int aggregates) const;
  template <int B>
  void galerkin(const Level& level, BlockMatrix& coarse, int aggregates) const;
  bool factor_coarsest();
  void vcycle(size_t l);
  void chebyshev(Level& level, bool zero_start);
};

BlockAmgSolver::BlockAmgSolver(const Matrix& lower, const std::vector<int>& dof_of_free,
                               std::span<const Vec3> nodes, double tolerance, int max_iterations)
    : impl_(std::make_unique<Impl>()) {
  if (!lower.isCompressed())
    throw std::logic_error("BlockAmgSolver: the matrix must be compressed");
  if (dof_of_free.size() != static_cast<size_t>(lower.cols()))
    throw std::logic_error("BlockAmgSolver: one DOF per free row");
  Impl& m = *impl_;
  m.tolerance = tolerance;
  m.max_iterations = max_iterations;
  // Node rows in the order of the free DOFs.
  m.row_of_free.resize(dof_of_free.size());
  int last_node = -1, node_rows = 0;
  std::vector<char> seen(nodes.size(), 0);
  for (size_t i = 0; i < dof_of_free.size(); ++i) {
    const int node = dof_of_free[i] / 3;
    if (node != last_node) {
      if (seen[static_cast<size_t>(node)])
        throw std::logic_error("BlockAmgSolver: a node's free DOFs must be consecutive");
      seen[static_cast<size_t>(node)] = 1;
      last_node = node;
      ++node_rows;
      m.positions.push_back(nodes[static_cast<size_t>(node)]);
    }
    m.row_of_free[i] = 3 * (node_rows - 1) + dof_of_free[i] % 3;
  }
  m.prescribed.assign(3 * static_cast<size_t>(node_rows), 1);
  for (int row : m.row_of_free) m.prescribed[static_cast<size_t>(row)] = 0;
  m.fine_pattern(lower);
}

BlockAmgSolver::~BlockAmgSolver() = default;

// The node graph of the lower triangle, mirrored: row i's columns ascending
// (the lower triangle's columns are visited in order, and a node's own
// columns give its diagonal and upper neighbours, ascending).
void BlockAmgSolver::Impl::fine_pattern(const Matrix& lower) {
  const int n = static_cast<int>(positions.size());
  const int* outer = lower.outerIndexPtr();
  const int* inner = lower.innerIndexPtr();
  // Per node, the nodes at or after it that its columns reach.
  std::vector<int> first_column(static_cast<size_t>(n) + 1, 0);
  for (size_t c = lower.cols(); c-- > 0;)
    first_column[static_cast<size_t>(row_of_free[c] / 3)] = static_cast<int>(c);
  first_column[static_cast<size_t>(n)] = static_cast<int>(lower.cols());
  std::vector<int> seen(static_cast<size_t>(n), -1);
  std::vector<int> upper_start(static_cast<size_t>(n) + 1, 0), upper;
  std::vector<int> count(static_cast<size_t>(n), 0);
  for (int node = 0; node < n; ++node) {
    const size_t begin = upper.size();
    for (int c = first_column[static_cast<size_t>(node)];
         c < first_column[static_cast<size_t>(node) + 1]; ++c) {
      for (int k = outer[c]; k < outer[c + 1]; ++k) {
        const int other = row_of_free[static_cast<size_t>(inner[k])] / 3;
        if (seen[static_cast<size_t>(other)] == node) continue;
        seen[static_cast<size_t>(other)] = node;
        upper.push_back(other);
      }
    }
    std::sort(upper.begin() + static_cast<long>(begin), upper.end());
    if (begin == upper.size() || upper[begin] != node)
      throw std::logic_error("BlockAmgSolver: a node without its diagonal");
    upper_start[static_cast<size_t>(node) + 1] = static_cast<int>(upper.size());
    for (size_t k = begin; k < upper.size(); ++k) {
      ++count[static_cast<size_t>(node)];
      if (upper[k] != node) ++count[static_cast<size_t>(upper[k])];
    }
  }
  Level& fine = levels.emplace_back();
  BlockMatrix& a = fine.a;
  a.block = 3;
  a.start.assign(static_cast<size_t>(n) + 1, 0);
  for (int i = 0; i < n; ++i)
    a.start[static_cast<size_t>(i) + 1] =
        a.start[static_cast<size_t>(i)] + count[static_cast<size_t>(i)];
  a.column.resize(static_cast<size_t>(a.start.back()));
  std::vector<int> cursor(a.start.begin(), a.start.end() - 1);
  diagonal_slot.resize(static_cast<size_t>(n));
  for (int node = 0; node < n; ++node) {
    for (int k = upper_start[static_cast<size_t>(node)];
         k < upper_start[static_cast<size_t>(node) + 1]; ++k) {
      const int other = upper[static_cast<size_t>(k)];
      if (other == node)
        diagonal_slot[static_cast<size_t>(node)] = cursor[static_cast<size_t>(node)];
      a.column[static_cast<size_t>(cursor[static_cast<size_t>(node)]++)] = other;
      if (other != node) a.column[static_cast<size_t>(cursor[static_cast<size_t>(other)]++)] = node;
    }
  }
  a.values.assign(a.column.size() * a.block_size(), 0.0);
}

// The lower triangle's values into the node blocks: each entry (r, c),
// r ≥ c, is block (node r, node c)'s and, mirrored, block (node c, node r)'s.
void BlockAmgSolver::Impl::fine_values(const Matrix& lower) {
  BlockMatrix& a = levels.front().a;
  std::fill(a.values.begin(), a.values.end(), 0.0);
  const int n = a.rows();
  std::vector<int> lower_cursor(a.start.begin(), a.start.end() - 1);
  const int* outer = lower.outerIndexPtr();
  const int* inner = lower.innerIndexPtr();
  const double* value = lower.valuePtr();
  for (int c = 0; c < static_cast<int>(lower.cols()); ++c) {
    const int cj = row_of_free[static_cast<size_t>(c)];
    const int node = cj / 3, dj = cj % 3;
    int upper = diagonal_slot[static_cast<size_t>(node)];
    for (int k = outer[c]; k < outer[c + 1]; ++k) {
      const int ri = row_of_free[static_cast<size_t>(inner[k])];
      const int other = ri / 3, di = ri % 3;
      while (a.column[static_cast<size_t>(upper)] < other) ++upper;
      a.at(static_cast<size_t>(upper))[dj * 3 + di] = value[k];
      if (other != node) {
        int& at = lower_cursor[static_cast<size_t>(other)];
        while (a.column[static_cast<size_t>(at)] < node) ++at;
        a.at(static_cast<size_t>(at))[di * 3 + dj] = value[k];
      } else if (di != dj) {
        a.at(static_cast<size_t>(upper))[di * 3 + dj] = value[k];
      }
    }
  }
  for (int i = 0; i < n; ++i)
    for (int d = 0; d < 3; ++d)
      if (prescribed[3 * static_cast<size_t>(i) + static_cast<size_t>(d)])
        a.at(static_cast<size_t>(diagonal_slot[static_cast<size_t>(i)]))[d * 4] = 1.0;
}

/// Aggregates on the strong graph (Vaněk et al.): a node whose strong
/// neighbourhood (one step, or kFinestRadius steps on the finest level) is
/// all free starts an aggregate with it; a node left over joins the
/// aggregate of its strongest aggregated neighbour, sweep after sweep; a
/// node with no strong neighbour stays out (the smoother alone handles it).
int BlockAmgSolver::Impl::aggregate(const Level& level, double strong,
                                    std::vector<int>& aggregate_of) const {
  const BlockMatrix& a = level.a;
  const int n = a.rows();
  const size_t bb = a.block_size();
  std::vector<double> diagonal_norm(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) {
    const double* block = a.at(a.diagonal(i));
    double sum = 0;
    for (size_t e = 0; e < bb; ++e) sum += block[e] * block[e];
    diagonal_norm[static_cast<size_t>(i)] = std::sqrt(sum);
  }
  // The strength of each off-diagonal block (0: weak).
  std::vector<float> strength(a.column.size(), 0.0f);
  std::vector<char> has_strong(static_cast<size_t>(n), 0);
  for (int i = 0; i < n; ++i) {
    for (int k = a.start[static_cast<size_t>(i)]; k < a.start[static_cast<size_t>(i) + 1]; ++k) {
      const int j = a.column[static_cast<size_t>(k)];
      if (j == i) continue;
      const double* block = a.at(static_cast<size_t>(k));
      double sum = 0;
      for (size_t e = 0; e < bb; ++e) sum += block[e] * block[e];
      const double scale =
          diagonal_norm[static_cast<size_t>(i)] * diagonal_norm[static_cast<size_t>(j)];
      if (sum > strong * strong * scale && sum > 0) {
        strength[static_cast<size_t>(k)] = static_cast<float>(sum / scale);
        has_strong[static_cast<size_t>(i)] = 1;
      }
    }
  }
  aggregate_of.assign(static_cast<size_t>(n), -1);
  int aggregates = 0;
  const int radius = &level == &levels.front() ? kFinestRadius : 1;
  std::vector<int> reach;
  for (int i = 0; i < n; ++i) {
    if (!has_strong[static_cast<size_t>(i)] || aggregate_of[static_cast<size_t>(i)] >= 0) continue;
    // The strong neighbourhood of radius `radius`, all free, or no aggregate here.
    reach.assign(1, i);
    aggregate_of[static_cast<size_t>(i)] = aggregates;  // reached
    bool free = true;
    size_t from = 0;
    for (int step = 0; step < radius && free; ++step) {
      const size_t to = reach.size();
      for (size_t e = from; e < to && free; ++e) {
        const int v = reach[e];
        for (int k = a.start[static_cast<size_t>(v)]; k < a.start[static_cast<size_t>(v) + 1];
             ++k) {
          if (!(strength[static_cast<size_t>(k)] > 0)) continue;
          const int j = a.column[static_cast<size_t>(k)];
          if (aggregate_of[static_cast<size_t>(j)] >= 0) {
            if (aggregate_of[static_cast<size_t>(j)] == aggregates) continue;
            free = false;
            break;
          }
          aggregate_of[static_cast<size_t>(j)] = aggregates;  // reached
          reach.push_back(j);
        }
      }
      from = to;
    }
    if (!free) {
      for (int v : reach) aggregate_of[static_cast<size_t>(v)] = -1;
      continue;
    }
    ++aggregates;
  }
  // Left-over nodes join their strongest aggregated neighbour's aggregate,
  // sweep after sweep (a node may be two steps from an aggregate).
  for (bool changed = true; changed;) {
    changed = false;
    const std::vector<int> before = aggregate_of;
    for (int i = 0; i < n; ++i) {
      if (aggregate_of[static_cast<size_t>(i)] >= 0 || !has_strong[static_cast<size_t>(i)])
        continue;
      float best = 0;
      for (int k = a.start[static_cast<size_t>(i)]; k < a.start[static_cast<size_t>(i) + 1]; ++k) {
        const int j = a.column[static_cast<size_t>(k)];
        if (strength[static_cast<size_t>(k)] > best && before[static_cast<size_t>(j)] >= 0) {
          best = strength[static_cast<size_t>(k)];
          aggregate_of[static_cast<size_t>(i)] = before[static_cast<size_t>(j)];
          changed = true;
        }
      }
    }
  }
  return aggregates;
}

/// The tentative prolongator: each aggregate's rows of the near-nullspace,
/// orthonormalised (Gram–Schmidt, twice), are its block of T; the factor R
/// is the aggregate's near-nullspace on the next level. A mode the aggregate
/// cannot carry (a single node's rotations) gives a zero column.
void BlockAmgSolver::Impl::tentative(Level& level, Level& next,
                                     const std::vector<int>& aggregate_of, int aggregates,
                                     std::vector<double>& t) const {
  const int n = level.a.rows();
  const int b = level.a.block;
  // Nodes of each aggregate.
  std::vector<int> start(static_cast<size_t>(aggregates) + 1, 0), member(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i)
    if (aggregate_of[static_cast<size_t>(i)] >= 0)
      ++start[static_cast<size_t>(aggregate_of[static_cast<size_t>(i)]) + 1];
  std::partial_sum(start.begin(), start.end(), start.begin());
  std::vector<int> fill(start.begin(), start.end() - 1);
  for (int i = 0; i < n; ++i)
    if (const int g = aggregate_of[static_cast<size_t>(i)]; g >= 0)
      member[static_cast<size_t>(fill[static_cast<size_t>(g)]++)] = i;

  t.assign(static_cast<size_t>(n) * static_cast<size_t>(b) * kModes, 0.0);
  next.modes.assign(static_cast<size_t>(aggregates) * kModes * kModes, 0.0);
  const bool finest = &level == &levels.front();
  Eigen::MatrixXd q;
  for (int g = 0; g < aggregates; ++g) {
    const int first = start[static_cast<size_t>(g)], end = start[static_cast<size_t>(g) + 1];
    const int rows = (end - first) * b;
    q.resize(rows, kModes);
    if (finest) {
      // Rigid-body modes about the aggregate's centre (better conditioned).
      Vec3 centre = Vec3::Zero();
      for (int k = first; k < end; ++k)
        centre += positions[static_cast<size_t>(member[static_cast<size_t>(k)])];
      centre /= end - first;
      for (int k = first; k < end; ++k) {
        const int i = member[static_cast<size_t>(k)];
        const Vec3 x = positions[static_cast<size_t>(i)] - centre;
        const long r = 3L * (k - first);
        q.block(r, 0, 3, kModes) << 1, 0, 0, 0, x.z(), -x.y(),  //
            0, 1, 0, -x.z(), 0, x.x(),                          //
            0, 0, 1, x.y(), -x.x(), 0;
        for (int d = 0; d < 3; ++d)
          if (prescribed[3 * static_cast<size_t>(i) + static_cast<size_t>(d)])
            q.row(r + d).setZero();
      }
    } else {
      for (int k = first; k < end; ++k) {
        const double* modes =
            level.modes.data() + static_cast<size_t>(member[static_cast<size_t>(k)]) * b * kModes;
        for (int r = 0; r < b; ++r)
          for (int c = 0; c < kModes; ++c) q((k - first) * b + r, c) = modes[r * kModes + c];
      }
    }
    double* r_factor = next.modes.data() + static_cast<size_t>(g) * kModes * kModes;
    for (int c = 0; c < kModes; ++c) {
      const double original = q.col(c).norm();
      for (int pass = 0; pass < 2; ++pass) {
        for (int e = 0; e < c; ++e) {
          const double dot = q.col(e).dot(q.col(c));
          q.col(c) -= dot * q.col(e);
          r_factor[e * kModes + c] += dot;
        }
      }
      const double norm = q.col(c).norm();
      if (norm > 1e-10 * original && norm > 0) {
        q.col(c) /= norm;
        r_factor[c * kModes + c] = norm;
      } else {
        q.col(c).setZero();
      }
    }
    for (int k = first; k < end; ++k) {
      double* block = t.data() + static_cast<size_t>(member[static_cast<size_t>(k)]) * b * kModes;
      for (int r = 0; r < b; ++r)
        for (int c = 0; c < kModes; ++c) block[r * kModes + c] = q((k - first) * b + r, c);
    }
  }
}

/// P = (I − ω D⁻¹A) T, ω = 4 / (3 λ): row i's blocks at the aggregates of i
/// and its neighbours.
template <int B>
void BlockAmgSolver::Impl::smooth_prolongator(Level& level, const std::vector<int>& aggregate_of,
                                              const std::vector<double>& t, int aggregates) const {
  const BlockMatrix& a = level.a;
  const int n = a.rows();
  const double omega = kProlongatorDamping / level.lambda;
  Prolongator& p = level.p;
  p.block = B;
  p.start.assign(static_cast<size_t>(n) + 1, 0);
  p.column.clear();
  p.values.clear();
  std::vector<int> slot(static_cast<size_t>(aggregates), -1);
  using BlockB = Eigen::Matrix<double, B, B, Eigen::RowMajor>;
  using BlockP = Eigen::Matrix<double, B, kModes, Eigen::RowMajor>;
  std::vector<BlockP, Eigen::aligned_allocator<BlockP>> row;
  std::vector<int> row_columns;
  for (int i = 0; i < n; ++i) {
    row.clear();
    row_columns.clear();
    for (int k = a.start[static_cast<size_t>(i)]; k < a.start[static_cast<size_t>(i) + 1]; ++k) {
      const int j = a.column[static_cast<size_t>(k)];
      const int g = aggregate_of[static_cast<size_t>(j)];
      if (g < 0) continue;
      int& s = slot[static_cast<size_t>(g)];
      if (s < 0) {
        s = static_cast<int>(row.size());
        row.push_back(BlockP::Zero());
        row_columns.push_back(g);
      }
      row[static_cast<size_t>(s)].noalias() +=
          Eigen::Map<const BlockB>(a.at(static_cast<size_t>(k))) *
          Eigen::Map<const BlockP>(t.data() + static_cast<size_t>(j) * B * kModes);
    }
    for (size_t s = 0; s < row.size(); ++s) {
      BlockP block =
          -omega *
          (level.inverse_diagonal.template segment<B>(static_cast<long>(i) * B).asDiagonal() *
           row[s]);
      if (row_columns[s] == aggregate_of[static_cast<size_t>(i)])
        block += Eigen::Map<const BlockP>(t.data() + static_cast<size_t>(i) * B * kModes);
      p.column.push_back(row_columns[s]);
      p.values.insert(p.values.end(), block.data(), block.data() + B * kModes);
      slot[static_cast<size_t>(row_columns[s])] = -1;
    }
    p.start[static_cast<size_t>(i) + 1] = static_cast<int>(p.column.size());
  }
}

/// The coarse operator PᵀAP in 6 × 6 blocks: its pattern first (the
/// aggregates P's transpose reaches through A and P), then fine row by fine
/// row, (AP)ᵢ formed once and Pᵢᵀ(AP)ᵢ added to the coarse rows of Pᵢ.
template <int B>
void BlockAmgSolver::Impl::galerkin(const Level& level, BlockMatrix& coarse, int aggregates) const {
  const BlockMatrix& a = level.a;
  const Prolongator& p = level.p;
  const int n = a.rows();
  // Pᵀ's rows: the fine rows whose P row has the aggregate.
  std::vector<int> t_start(static_cast<size_t>(aggregates) + 1, 0), t_row(p.column.size());
  for (int g : p.column) ++t_start[static_cast<size_t>(g) + 1];
  std::partial_sum(t_start.begin(), t_start.end(), t_start.begin());
  {
    std::vector<int> fill(t_start.begin(), t_start.end() - 1);
    for (int i = 0; i < n; ++i)
      for (int k = p.start[static_cast<size_t>(i)]; k < p.start[static_cast<size_t>(i) + 1]; ++k)
        t_row[static_cast<size_t>(fill[static_cast<size_t>(p.column[static_cast<size_t>(k)])]++)] =
            i;
  }
  coarse.block = kModes;
  coarse.start.assign(static_cast<size_t>(aggregates) + 1, 0);
  coarse.column.clear();
  std::vector<int> mark(static_cast<size_t>(aggregates), -1);
  for (int g = 0; g < aggregates; ++g) {
    const size_t begin = coarse.column.size();
    for (int k = t_start[static_cast<size_t>(g)]; k < t_start[static_cast<size_t>(g) + 1]; ++k) {
      const int i = t_row[static_cast<size_t>(k)];
      for (int ka = a.start[static_cast<size_t>(i)]; ka < a.start[static_cast<size_t>(i) + 1];
           ++ka) {
        const int j = a.column[static_cast<size_t>(ka)];
        for (int kp = p.start[static_cast<size_t>(j)]; kp < p.start[static_cast<size_t>(j) + 1];
             ++kp) {
          const int h = p.column[static_cast<size_t>(kp)];
          if (mark[static_cast<size_t>(h)] == g) continue;
          mark[static_cast<size_t>(h)] = g;
          coarse.column.push_back(h);
        }
      }
    }
    std::sort(coarse.column.begin() + static_cast<long>(begin), coarse.column.end());
    coarse.start[static_cast<size_t>(g) + 1] = static_cast<int>(coarse.column.size());
  }
  coarse.values.assign(coarse.column.size() * coarse.block_size(), 0.0);

  using BlockB = Eigen::Matrix<double, B, B, Eigen::RowMajor>;
  using BlockP = Eigen::Matrix<double, B, kModes, Eigen::RowMajor>;
  using Block6 = Eigen::Matrix<double, kModes, kModes, Eigen::RowMajor>;
  Eigen::Matrix<double, B, Eigen::Dynamic> ap;  // (AP)ᵢ, 6 columns per aggregate
  Eigen::Matrix<double, B, Eigen::Dynamic> pi;  // Pᵢ, 6 columns per aggregate
  Eigen::MatrixXd product;
  std::vector<int> ap_columns;
  std::vector<int> local(static_cast<size_t>(aggregates), -1);
  for (int i = 0; i < n; ++i) {
    ap_columns.clear();
    int count = 0;
    for (int ka = a.start[static_cast<size_t>(i)]; ka < a.start[static_cast<size_t>(i) + 1]; ++ka) {
      const int j = a.column[static_cast<size_t>(ka)];
      for (int kp = p.start[static_cast<size_t>(j)]; kp < p.start[static_cast<size_t>(j) + 1];
           ++kp) {
        const int h = p.column[static_cast<size_t>(kp)];
        if (local[static_cast<size_t>(h)] < 0) {
          local[static_cast<size_t>(h)] = count++;
          ap_columns.push_back(h);
        }
      }
    }
    if (ap.cols() < kModes * count) ap.resize(B, kModes * count);
    ap.leftCols(kModes * count).setZero();
    for (int ka = a.start[static_cast<size_t>(i)]; ka < a.start[static_cast<size_t>(i) + 1]; ++ka) {
      const int j = a.column[static_cast<size_t>(ka)];
      const Eigen::Map<const BlockB> aij(a.at(static_cast<size_t>(ka)));
      for (int kp = p.start[static_cast<size_t>(j)]; kp < p.start[static_cast<size_t>(j) + 1];
           ++kp) {
        const int h = p.column[static_cast<size_t>(kp)];
        ap.template middleCols<kModes>(kModes * local[static_cast<size_t>(h)]).noalias() +=
            aij * Eigen::Map<const BlockP>(p.at(static_cast<size_t>(kp)));
      }
    }
    const int pi_count = p.start[static_cast<size_t>(i) + 1] - p.start[static_cast<size_t>(i)];
    if (pi.cols() < kModes * pi_count) pi.resize(B, kModes * pi_count);
    for (int s = 0; s < pi_count; ++s)
      pi.template middleCols<kModes>(kModes * s) =
          Eigen::Map<const BlockP>(p.at(static_cast<size_t>(p.start[static_cast<size_t>(i)] + s)));
    product.noalias() = pi.leftCols(kModes * pi_count).transpose() * ap.leftCols(kModes * count);
    for (int s = 0; s < pi_count; ++s) {
      const int g = p.column[static_cast<size_t>(p.start[static_cast<size_t>(i)] + s)];
      const int* row_begin = coarse.column.data() + coarse.start[static_cast<size_t>(g)];
      const int* row_end = coarse.column.data() + coarse.start[static_cast<size_t>(g) + 1];
      for (int w = 0; w < count; ++w) {
        const int h = ap_columns[static_cast<size_t>(w)];
        const auto at =
            static_cast<size_t>(std::lower_bound(row_begin, row_end, h) - coarse.column.data());
        Eigen::Map<Block6>(coarse.at(at)) += product.block<kModes, kModes>(kModes * s, kModes * w);
      }
    }
    for (int h : ap_columns) local[static_cast<size_t>(h)] = -1;
  }
  // A mode no aggregate carries leaves a zero row: an identity row instead.
  double largest = 0;
  for (int g = 0; g < aggregates; ++g) {
    const double* block = coarse.at(coarse.diagonal(g));
    for (int d = 0; d < kModes; ++d) largest = std::max(largest, block[d * (kModes + 1)]);
  }
  for (int g = 0; g < aggregates; ++g) {
    double* block = coarse.at(coarse.diagonal(g));
    for (int d = 0; d < kModes; ++d)
      if (!(block[d * (kModes + 1)] > 1e-12 * largest))
        block[d * (kModes + 1)] = largest > 0 ? largest : 1.0;
  }
}

bool BlockAmgSolver::Impl::build_hierarchy() {
  levels.resize(1);
  double strong = kStrongFinest;
  std::vector<int> aggregate_of;
  std::vector<double> t;
  for (;;) {
    const size_t l = levels.size() - 1;
    {
      Level& level = levels[l];
      const auto size = static_cast<long>(level.size());
      level.b.resize(size);
      level.x.resize(size);
      level.r.resize(size);
      level.d.resize(size);
      level.t.resize(size);
      level.inverse_diagonal.resize(size);
      const int b = level.a.block;
      for (int i = 0; i < level.a.rows(); ++i) {
        const double* block = level.a.at(level.a.diagonal(i));
        for (int d = 0; d < b; ++d) {
          const double diagonal = block[d * (b + 1)];
          if (!(diagonal > 0)) return false;  // not positive definite
          level.inverse_diagonal[static_cast<long>(i) * b + d] = 1 / diagonal;
        }
      }
      const int direct_rows = l == 0 ? kDirectRows : kCoarsestRows;
      if (level.size() <= static_cast<size_t>(direct_rows) ||
          levels.size() == static_cast<size_t>(kMaxLevels))
        break;
      level.lambda = largest_eigenvalue(level);
    }
    const int aggregates = aggregate(levels[l], strong, aggregate_of);
    // No coarsening to be had (no strong couplings left): solve here.
    if (aggregates == 0 || static_cast<size_t>(aggregates) * kModes >= levels[l].size()) break;
    Level next;
    tentative(levels[l], next, aggregate_of, aggregates, t);
    if (levels[l].a.block == 3) {
      smooth_prolongator<3>(levels[l], aggregate_of, t, aggregates);
      galerkin<3>(levels[l], next.a, aggregates);
    } else {
      smooth_prolongator<kModes>(levels[l], aggregate_of, t, aggregates);
      galerkin<kModes>(levels[l], next.a, aggregates);
    }
    levels.push_back(std::move(next));
    strong *= 0.5;
  }
  levels.back().p = Prolongator{};
  for (size_t l = 0; l + 1 < levels.size(); ++l) {
    BlockMatrix& a = levels[l].a;
    a.single.assign(a.values.begin(), a.values.end());
  }
  return factor_coarsest();
}

bool BlockAmgSolver::Impl::factor_coarsest() {
  const Level& level = levels.back();
  const BlockMatrix& a = level.a;
  const int b = a.block;
  std::vector<Eigen::Triplet<double>> entries;
  entries.reserve(a.values.size() / 2 + level.size());
  for (int i = 0; i < a.rows(); ++i)
    for (int k = a.start[static_cast<size_t>(i)]; k < a.start[static_cast<size_t>(i) + 1]; ++k) {
      const int j = a.column[static_cast<size_t>(k)];
      if (j > i) continue;
      const double* block = a.at(static_cast<size_t>(k));
      for (int r = 0; r < b; ++r)
        for (int c = 0; c < b; ++c)
          if (j < i || c <= r) entries.emplace_back(i * b + r, j * b + c, block[r * b + c]);
    }
  Matrix lower(static_cast<long>(level.size()), static_cast<long>(level.size()));
  lower.setFromTriplets(entries.begin(), entries.end());
  lower.makeCompressed();
  coarsest.analyze(lower);
  return coarsest.factorize(lower);
}

void BlockAmgSolver::Impl::chebyshev(Level& level, bool zero_start) {
  const double low = kChebyshevLow * level.lambda, high = kChebyshevHigh * level.lambda;
  const double theta = (high + low) / 2, delta = (high - low) / 2, sigma = theta / delta;
  double rho = 1 / sigma;
  if (zero_start) {
    level.x.setZero();
    level.r = level.b;
  } else {
    multiply_single(level.a, level.x, level.t);
    level.r = level.b - level.t;
  }
  level.d = level.inverse_diagonal.cwiseProduct(level.r) / theta;
  for (int k = 1;; ++k) {
    level.x += level.d;
    if (k == kChebyshevDegree) break;
    multiply_single(level.a, level.d, level.t);
    level.r -= level.t;
    const double rho_next = 1 / (2 * sigma - rho);
    level.d = rho_next * rho * level.d +
              (2 * rho_next / delta) * level.inverse_diagonal.cwiseProduct(level.r);
    rho = rho_next;
  }
}

// x = M⁻¹ b on level l (levels[l].b in, levels[l].x out), one V-cycle.
void BlockAmgSolver::Impl::vcycle(size_t l) {
  Level& level = levels[l];
  if (l + 1 == levels.size()) {
    coarsest.solve(level.b, level.x);
    return;
  }
  Level& next = levels[l + 1];
  chebyshev(level, true);
  multiply_single(level.a, level.x, level.t);
  level.r = level.b - level.t;
  if (level.a.block == 3)
    restrict_to<3>(level.p, level.r.data(), next.b.data(), next.size());
  else
    restrict_to<kModes>(level.p, level.r.data(), next.b.data(), next.size());
  vcycle(l + 1);
  if (level.a.block == 3)
    prolong_add<3>(level.p, next.x.data(), level.x.data());
  else
    prolong_add<kModes>(level.p, next.x.data(), level.x.data());
  chebyshev(level, false);
}

bool BlockAmgSolver::setup(const Matrix& lower) {
  Impl& m = *impl_;
  if (lower.cols() != static_cast<long>(m.row_of_free.size()))
    throw std::logic_error("BlockAmgSolver: another matrix");
  const auto start = std::chrono::steady_clock::now();
  m.fine_values(lower);
  const auto values_done = std::chrono::steady_clock::now();
  m.ready = m.build_hierarchy();
  if (!m.ready) return false;
  if (std::getenv("SPEC2FAB_FEM_TRACE")) {
    const auto end = std::chrono::steady_clock::now();
    std::fprintf(stderr, "block_amg: values %.3f s, hierarchy %.3f s, levels",
                 std::chrono::duration<double>(values_done - start).count(),
                 std::chrono::duration<double>(end - values_done).count());
    for (const Level& level : m.levels)
      std::fprintf(stderr, " %zu (%zu blocks, lambda %.3f)", level.size(), level.a.column.size(),
                   level.lambda);
    std::fprintf(stderr, ", complexity %.3f\n", operator_complexity());
  }
  const auto n = static_cast<long>(m.levels.front().size());
  m.cg_x.resize(n);
  m.cg_r.resize(n);
  m.cg_p.resize(n);
  m.cg_q.resize(n);
  return true;
}

bool BlockAmgSolver::solve(const Eigen::VectorXd& b, Eigen::VectorXd& x) {
  Impl& m = *impl_;
  if (!m.ready) return false;
  Level& fine = m.levels.front();
  const Vector& z = fine.x;  // the V-cycle's answer: the preconditioned residual
  m.cg_x.setZero();
  m.cg_r.setZero();
  for (size_t i = 0; i < m.row_of_free.size(); ++i)
    m.cg_r[m.row_of_free[i]] = b[static_cast<long>(i)];
  const double norm_b = m.cg_r.norm();
  m.iterations = 0;
  m.relative_residual = 0;
  bool converged = norm_b == 0;
  if (!converged) {
    fine.b = m.cg_r;
    m.vcycle(0);
    m.cg_p = z;
    double rz = m.cg_r.dot(z);
    while (m.iterations < m.max_iterations) {
      multiply(fine.a, m.cg_p, m.cg_q);
      const double pq = m.cg_p.dot(m.cg_q);
      if (!(pq > 0) || !(rz > 0)) break;
      const double alpha = rz / pq;
      m.cg_x += alpha * m.cg_p;
      m.cg_r -= alpha * m.cg_q;
      ++m.iterations;
      m.relative_residual = m.cg_r.norm() / norm_b;
      if (m.relative_residual <= m.tolerance) {
        converged = true;
        break;
      }
      fine.b = m.cg_r;
      m.vcycle(0);
      const double rz_next = m.cg_r.dot(z);
      m.cg_p = z + (rz_next / rz) * m.cg_p;
      rz = rz_next;
    }
  }
  x.resize(static_cast<long>(m.row_of_free.size()));
  for (size_t i = 0; i < m.row_of_free.size(); ++i)
    x[static_cast<long>(i)] = m.cg_x[m.row_of_free[i]];
  if (std::getenv("SPEC2FAB_FEM_TRACE"))
    std::fprintf(stderr, "block_amg: %d CG iterations to %.3g\n", m.iterations,
                 m.relative_residual);
  return converged;
}

int BlockAmgSolver::last_iterations() const { return impl_->iterations; }
double BlockAmgSolver::last_relative_residual() const { return impl_->relative_residual; }

double BlockAmgSolver::operator_complexity() const {
  double total = 0;
  for (const Level& level : impl_->levels) total += static_cast<double>(level.a.values.size());
  return impl_->levels.empty() ? 0.0
                               : total / static_cast<double>(impl_->levels.front().a.values.size());
}

}  // namespace spec2fab::fem
