#include "fem/corotated_tet.h"

#include <Eigen/LU>
#include <Eigen/SVD>

namespace spec2fab::fem {

TetRest tet_rest(const Eigen::Vector3d& x0, const Eigen::Vector3d& x1, const Eigen::Vector3d& x2,
                 const Eigen::Vector3d& x3) {
  Mat3 edges;
  edges << x1 - x0, x2 - x0, x3 - x0;
  TetRest rest;
  rest.volume_mm3 = edges.determinant() / 6.0;
  rest.inverse_rest_edges = edges.inverse();
  return rest;
}

Mat3 polar_rotation(const Mat3& f) {
  Eigen::JacobiSVD<Mat3> svd(f, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Mat3 u = svd.matrixU();
  const Mat3 v = svd.matrixV();
  if ((u * v.transpose()).determinant() < 0) u.col(2) = -u.col(2);  // singular values sorted: flip the smallest
  return u * v.transpose();
}

Mat3 deformation_gradient(const TetRest& rest, const double* x) {
  Mat3 ds;
  for (int c = 0; c < 3; ++c) {
    for (int d = 0; d < 3; ++d) ds(d, c) = x[3 * (c + 1) + d] - x[d];
  }
  return ds * rest.inverse_rest_edges;
}

namespace {

// f for nodes 1..3 = V·P·Bmᵀ (columns); node 0 balances them.
void scatter_stress(const TetRest& rest, const Mat3& p, double* out) {
  const Mat3 h = rest.volume_mm3 * p * rest.inverse_rest_edges.transpose();
  for (int d = 0; d < 3; ++d) {
    out[d] = -(h(d, 0) + h(d, 1) + h(d, 2));
    for (int c = 0; c < 3; ++c) out[3 * (c + 1) + d] = h(d, c);
  }
}

// dF for a unit displacement of DOF j.
Mat3 unit_gradient(const TetRest& rest, int j) {
  const int node = j / 3, dim = j % 3;
  Mat3 dds = Mat3::Zero();
  if (node == 0) {
    dds.row(dim).setConstant(-1.0);
  } else {
    dds(dim, node - 1) = 1.0;
  }
  return dds * rest.inverse_rest_edges;
}

Eigen::Vector3d axial(const Mat3& skew) { return {skew(2, 1), skew(0, 2), skew(1, 0)}; }

Mat3 cross_matrix(const Eigen::Vector3d& w) {
  Mat3 m;
  m << 0, -w.z(), w.y(), w.z(), 0, -w.x(), -w.y(), w.x(), 0;
  return m;
}

}  // namespace

double tet_forces(const TetRest& rest, double lambda, double mu, const double* x, bool corotated,
                  Vec12& forces, Mat12* tangent) {
  const Mat3 f = deformation_gradient(rest, x);
  const Mat3 r = corotated ? polar_rotation(f) : Mat3::Identity();
  const Mat3 s = r.transpose() * f;
  Mat3 p;
  double energy_density = 0;
  if (corotated) {
    p = 2 * mu * (f - r) + lambda * (s.trace() - 3) * r;
    energy_density = mu * (f - r).squaredNorm() + 0.5 * lambda * (s.trace() - 3) * (s.trace() - 3);
  } else {
    const Mat3 strain = 0.5 * (f + f.transpose()) - Mat3::Identity();
    p = 2 * mu * strain + lambda * strain.trace() * Mat3::Identity();
    energy_density = mu * strain.squaredNorm() + 0.5 * lambda * strain.trace() * strain.trace();
  }
  scatter_stress(rest, p, forces.data());
  const double energy = rest.volume_mm3 * energy_density;
  if (!tangent) return energy;

  // dP = 2μ dF + (λ tr(S − I) − 2μ) dR + λ tr(Rᵀ dF) R, with dR = R [w]×,
  // (tr(S) I − S) w = axial(Rᵀ dF − dFᵀ R).
  Mat3 spin_solve = Mat3::Zero();
  if (corotated) spin_solve = (s.trace() * Mat3::Identity() - s).inverse();
  const double rotation_weight = lambda * (s.trace() - 3) - 2 * mu;
  for (int j = 0; j < 12; ++j) {
    const Mat3 df = unit_gradient(rest, j);
    Mat3 dp;
    if (corotated) {
      const Mat3 m = r.transpose() * df;
      const Eigen::Vector3d w = spin_solve * axial(m - m.transpose());
      const Mat3 dr = r * cross_matrix(w);
      dp = 2 * mu * df + rotation_weight * dr + lambda * m.trace() * r;
    } else {
      const Mat3 dstrain = 0.5 * (df + df.transpose());
      dp = 2 * mu * dstrain + lambda * dstrain.trace() * Mat3::Identity();
    }
    scatter_stress(rest, dp, tangent->col(j).data());
  }
  return energy;
}

void linear_tet_stiffness(const TetRest& rest, double lambda, double mu, Mat12& stiffness) {
  // Node a ≥ 1's gradient is row a − 1 of the inverse rest edges; node 0's
  // balances them (the shape functions sum to one).
  Eigen::Matrix<double, 4, 3> g;
  g.bottomRows<3>() = rest.inverse_rest_edges;
  g.row(0) = -g.bottomRows<3>().colwise().sum();
  const Eigen::Matrix4d dots = g * g.transpose();
  const double v = rest.volume_mm3;
  for (int b = 0; b < 4; ++b) {
    for (int a = 0; a < 4; ++a) {
      Mat3 block = lambda * g.row(a).transpose() * g.row(b) + mu * g.row(b).transpose() * g.row(a);
      block.diagonal().array() += mu * dots(a, b);
      stiffness.block<3, 3>(3 * a, 3 * b) = v * block;
    }
  }
}

}  // namespace spec2fab::fem
