#pragma once
// Static equilibrium of the cloth under gravity with pinned vertices: Newton's method on the
// total potential energy (elastic + gravitational) with the exact force Jacobian, a backtracking
// line search and load steps. Used for the standard textile tests (cantilever, docs/fabrics.md),
// where the quantity measured is a static shape, so no time stepping is needed.

#include <Eigen/Core>
#include <string>
#include <vector>

#include "sim/cloth_model.hpp"
#include "sim/forces.hpp"

namespace sd::sim {

struct StaticOptions {
  ForceSettings forces;      // gravity and terms; damping and drag are ignored (no velocity)
  int load_steps = 8;        // gravity is applied in this many equal increments
  int max_iterations = 300;  // Newton iterations per load step
  // Converged when every free vertex's net force is below this fraction of the largest vertex
  // weight m_i·|g|.
  double tolerance = 1e-4;
};

struct StaticResult {
  bool converged = false;
  int iterations = 0;     // Newton iterations over all load steps
  double residual = 0.0;  // N, largest net force on a free vertex at the end
  std::string failure;    // why it did not converge
};

// Moves the free vertices of x (3n, metres) to a static equilibrium; pinned vertices keep their
// positions. The equilibrium found is the one reached continuously from x as gravity grows.
StaticResult solve_static(const ClothModel& model, Eigen::VectorXd& x,
                          const std::vector<int>& pinned, const StaticOptions& options = {});

}  // namespace sd::sim
