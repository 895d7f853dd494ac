#pragma once
/// One linear tetrahedron of co-rotated linear elasticity (McAdams et al.
/// 2011, "Efficient elasticity for character skinning with contact and
/// collisions"; Sifakis & Barbič 2012, "FEM simulation of 3D deformable
/// solids", §5): with F = R S the polar decomposition of the deformation
/// gradient, the energy density is
///     Ψ(F) = μ ‖F − R‖² + λ/2 tr(RᵀF − I)²,
/// i.e. linear elasticity measured in the element's rotated frame. Its first
/// Piola–Kirchhoff stress is P = 2μ(F − R) + λ tr(RᵀF − I) R, and the tangent
/// here is the *consistent* one — it carries dR, the change of the rotation
/// (not stiffness warping's R K₀ Rᵀ) — so Newton converges quadratically and
/// the tangent equals the derivative of the forces (checked in the tests).
///
/// Units: positions in mm, λ and μ in MPa (N/mm²), forces in N.
/// Node order is the tet's; the 12 DOFs are (x0, y0, z0, x1, …, z3).

#include <Eigen/Core>

namespace spec2fab::fem {

using Mat3 = Eigen::Matrix3d;
using Vec12 = Eigen::Matrix<double, 12, 1>;
using Mat12 = Eigen::Matrix<double, 12, 12>;

/// Rest-shape data of one tet: Bm = Dm⁻¹ with Dm = [X1−X0, X2−X0, X3−X0].
struct TetRest {
  Mat3 inverse_rest_edges = Mat3::Identity();
  double volume_mm3 = 0;
};

/// From rest corners; volume must be positive (the caller orients the tet).
TetRest tet_rest(const Eigen::Vector3d& x0, const Eigen::Vector3d& x1, const Eigen::Vector3d& x2,
                 const Eigen::Vector3d& x3);

/// Lamé parameters (MPa) from Young's modulus (MPa) and Poisson's ratio.
inline double lame_lambda(double youngs_mpa, double poisson) {
  return youngs_mpa * poisson / ((1 + poisson) * (1 - 2 * poisson));
}
inline double lame_mu(double youngs_mpa, double poisson) { return youngs_mpa / (2 * (1 + poisson)); }

/// The rotation of F's polar decomposition (proper: det R = +1, also for an
/// inverted element, where the smallest singular value's sign is flipped).
Mat3 polar_rotation(const Mat3& deformation_gradient);

/// Deformation gradient F = Ds·Bm at current corner positions `x` (12 values, mm).
Mat3 deformation_gradient(const TetRest& rest, const double* x);

/// Internal (elastic) forces f = ∂E/∂x (N; the force the element exerts on its
/// nodes is −f) at current corner positions `x` (12 values, mm), and, when
/// `tangent` is not null, the consistent tangent ∂f/∂x (N/mm).
/// `corotated` false gives small-strain linear elasticity (R = I).
/// Also returns the element's elastic energy V·Ψ (N·mm).
double tet_forces(const TetRest& rest, double lambda, double mu, const double* x, bool corotated,
                  Vec12& forces, Mat12* tangent);

/// Small-strain stiffness, ∂f/∂x of tet_forces with `corotated` false, in
/// closed form from the shape-function gradients gₐ (node a, axes i, j):
///   K(ai, bj) = V·(λ gₐᵢ g_bj + μ (gₐⱼ g_bᵢ + δᵢⱼ gₐ·g_b)).
/// The same matrix as that tangent, at a tenth of its cost: linear solves
/// (the elastic bound assembles two stiffnesses per call) need nothing else.
void linear_tet_stiffness(const TetRest& rest, double lambda, double mu, Mat12& stiffness);

}  // namespace spec2fab::fem
