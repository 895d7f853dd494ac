// ElasticSolver::solve: one linear solve (small strain), or co-rotational
// Newton with load steps, a secant predictor and an energy line search.
#include "fem/elastic_solver.h"
#include "fem/elastic_solver_impl.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <stdexcept>

#include "core/ranks.h"

namespace spec2fab::fem {

/// One solve: the constraints, the load's size, what the report counts and
/// the energy of the last residual evaluated.
struct ElasticSolver::Impl::Equilibrium {
  Impl& m;
  const TetMesh& mesh;
  const Constraints& c;
  SolveReport& report;
  size_t dofs = 3 * mesh.nodes.size();
  double external = external_load(c);
  double energy = 0;  ///< total potential energy (elastic minus the loads' work, N·mm) at the last residual

  static double external_load(const Constraints& constraints) {
    double sum = 0;
    for (double f : constraints.force_n) sum += f * f;
    return std::sqrt(sum);
  }

  /// ‖free residual‖ at the displacement `at`, loads scaled by `scale`;
  /// fills m.residual with −r (the Newton right-hand side), `energy`, and
  /// `reference` (the load or the reactions, whichever is larger).
  double residual_norm(std::span<const double> at, double scale, bool corotated, bool tangent, double& reference) {
    const auto start = Clock::now();
    energy = m.form(mesh, at, corotated, tangent);
    report.assembly_seconds += seconds_since(start);
    double sum = 0, reactions = 0;
    for (size_t d = 0; d < dofs; ++d) {
      const int i = m.dof_index[d];
      if (i < 0) {
        reactions += m.forces[d] * m.forces[d];
        continue;
      }
      energy -= scale * c.force_n[d] * at[d];
      const double r = m.forces[d] - scale * c.force_n[d];
      m.residual[i] = -r;
      sum += r * r;
    }
    reference = std::max(scale * external, std::sqrt(reactions));
    return std::sqrt(sum);
  }

  /// Small strain: one linear solve from the prescribed displacements.
  void solve_linear(std::vector<double>& u) {
    for (size_t d = 0; d < dofs; ++d) u[d] = m.dof_index[d] < 0 ? c.prescribed_mm[d] : 0.0;
    double reference = 0;
    residual_norm(u, 1.0, false, true, reference);
    if (!m.factorize_and_solve(report)) {
      throw std::runtime_error(m.kind == LinearSolver::cholesky
                                   ? "FEM: the stiffness matrix is singular"
                                   : "FEM: conjugate gradients did not converge (try \"linear_solver\": \"cholesky\")");
    }
    for (size_t d = 0; d < dofs; ++d) {
      if (const int i = m.dof_index[d]; i >= 0) u[d] += m.step[i];
    }
    // The linear system's own residual b − K·Δ (a matrix product, not another
    // pass over the elements); with the rows split over the ranks, each
    // rank's rows are whole in its matrix, and their sums are added.
    m.saved_residual.noalias() = m.stiffness.selfadjointView<Eigen::Lower>() * m.step;
    double r = 0;
    if (m.share.whole()) {
      r = (m.residual - m.saved_residual).norm();
    } else {
      double mine = 0;
      for (size_t d = 0; d < dofs; ++d) {
        const int i = m.dof_index[d];
        if (i >= 0 && m.owns_dof(d)) mine += (m.residual[i] - m.saved_residual[i]) * (m.residual[i] - m.saved_residual[i]);
      }
      std::vector<std::uint8_t> bytes(sizeof mine);
      std::memcpy(bytes.data(), &mine, sizeof mine);
      for (const std::vector<std::uint8_t>& theirs : ranks::all_gather(bytes)) {
        double part = 0;
        std::memcpy(&part, theirs.data(), sizeof part);
        r += part;
      }
      r = std::sqrt(r);
    }
    report.relative_residual = reference > 0 ? r / reference : r;
    report.newton_iterations = 1;
    report.load_steps = 1;
    report.converged = true;
  }

  /// Newton's iterations at load `scale` from `u`; whether they converged.
  bool newton(std::vector<double>& u, double scale, const SolveOptions& options, bool trace) {
    double reference = 0;
    for (int iteration = 0; iteration < options.max_newton_iterations; ++iteration) {
      const double r = residual_norm(u, scale, true, true, reference);
      report.relative_residual = reference > 0 ? r / reference : r;
      if (trace) std::fprintf(stderr, "fem: load %.3f, iteration %d, relative residual %.3e\n", scale, iteration, report.relative_residual);
      if (r <= options.tolerance * std::max(reference, 1e-300)) return true;
      ++report.newton_iterations;
      if (!m.factorize_and_solve(report)) return false;
      if (iteration > 0 && correction_negligible(u)) {
        for (size_t d = 0; d < dofs; ++d) {
          if (const int i = m.dof_index[d]; i >= 0) u[d] += m.step[i];
        }
        return true;
      }
      line_search(u, scale);
    }
    return false;
  }

  /// Forces are differences of nearly equal stresses (F − R) at small
  /// strains, so the residual has a round-off floor; a Newton correction
  /// below 1e-10 of the displacement is converged whatever it says.
  bool correction_negligible(const std::vector<double>& u) const {
    double largest_u = 0, largest_step = 0;
    for (size_t d = 0; d < dofs; ++d) largest_u = std::max(largest_u, std::abs(u[d]));
    for (int i = 0; i < m.free_count; ++i) largest_step = std::max(largest_step, std::abs(m.step[i]));
    return largest_step <= 1e-10 * largest_u;
  }

  /// Backtracking on the potential energy (the model is hyperelastic, so
  /// equilibrium minimises it): a full Newton step on a slender body can
  /// overshoot far past the minimum along the step. Moves `u` along it.
  void line_search(std::vector<double>& u, double scale) {
    const double start_energy = energy;
    const double slope = -m.residual.dot(m.step);  // dE/dα at α = 0 (< 0 for a descent step)
    double alpha = 1.0;
    for (int tries = 0; tries < 8; ++tries) {
      for (size_t d = 0; d < dofs; ++d) {
        const int i = m.dof_index[d];
        m.trial[d] = i < 0 ? u[d] : u[d] + alpha * m.step[i];
      }
      double unused = 0;
      m.saved_residual = m.residual;
      residual_norm(m.trial, scale, true, false, unused);
      m.residual = m.saved_residual;
      // (Round-off in the energy sum is allowed for near convergence.)
      const double noise = 1e-11 * std::abs(start_energy);
      if (slope >= 0 || (std::isfinite(energy) && energy <= start_energy + 1e-4 * alpha * slope + noise)) break;
      alpha *= 0.5;
    }
    std::copy(m.trial.begin(), m.trial.end(), u.begin());
  }

  /// Predictor for load `scale`: the last step's change, scaled to this one
  /// (a secant extrapolation of the load path); the prescribed DOFs at it.
  void predict(std::vector<double>& u, double scale, double done, double previous_scale) {
    if (report.load_steps > 0 && previous_scale < done) {
      const double ratio = (scale - done) / (done - previous_scale);
      for (size_t d = 0; d < dofs; ++d) {
        u[d] = m.dof_index[d] < 0 ? scale * c.prescribed_mm[d] : u[d] + ratio * (u[d] - m.previous_converged[d]);
      }
    } else {
      for (size_t d = 0; d < dofs; ++d) {
        if (m.dof_index[d] < 0) u[d] = scale * c.prescribed_mm[d];
      }
    }
  }
};

SolveReport ElasticSolver::solve(const Constraints& c, const SolveOptions& options, std::vector<double>& u) {
  Impl& m = *impl_;
  SolveReport report;
  Impl::Equilibrium equilibrium{m, mesh_, c, report};
  if (u.size() != equilibrium.dofs) u.assign(equilibrium.dofs, 0.0);
  if (!options.nonlinear) {
    equilibrium.solve_linear(u);
    return report;
  }
  // Load steps, each halved (up to 6 times in all) when Newton fails.
  const bool trace = std::getenv("SPEC2FAB_FEM_TRACE") != nullptr;  // Newton's progress on stderr
  std::vector<double>& last_converged = m.last_converged;
  last_converged = u;
  double done = 0, previous_scale = -1;
  double increment = 1.0 / std::max(1, options.load_steps);
  int halvings = 0;
  while (done < 1.0 - 1e-12) {
    const double scale = std::min(1.0, done + increment);
    equilibrium.predict(u, scale, done, previous_scale);
    if (equilibrium.newton(u, scale, options, trace)) {
      m.previous_converged.swap(last_converged);
      previous_scale = done;
      done = scale;
      ++report.load_steps;
      last_converged = u;
      continue;
    }
    if (++halvings > 6) {
      report.converged = false;
      return report;
    }
    u = last_converged;
    increment *= 0.5;
  }
  report.converged = true;
  return report;
}

}  // namespace spec2fab::fem
