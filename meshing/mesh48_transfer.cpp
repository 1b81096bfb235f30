#include "meshing/mesh48_transfer.hpp"

#include <algorithm>
#include <stdexcept>

namespace sd::meshing {
namespace {

void ensure_rows(Eigen::VectorXd& masses, Eigen::MatrixX3d& velocities, int rows) {
  const Eigen::Index old_m = masses.size(), old_v = velocities.rows();
  if (old_m < rows) {
    masses.conservativeResize(rows);
    masses.tail(rows - old_m).setZero();
  }
  if (old_v < rows) {
    velocities.conservativeResize(rows, Eigen::NoChange);
    velocities.bottomRows(rows - old_v).setZero();
  }
}

int max_id(const BlockChange& change) {
  return std::max(
      {change.e.value(), change.a.value(), change.b.value(), change.c.value(), change.d.value()});
}

}  // namespace

void transfer_mass_and_velocity(const BlockChange& change, const BlockDensities& densities,
                                Eigen::VectorXd& masses, Eigen::MatrixX3d& velocities) {
  if (!change.e.valid() || !change.b.valid() || !change.c.valid())
    throw std::invalid_argument("transfer_mass_and_velocity: the change record has no E, B or C");
  const bool has_d = change.d.valid();
  const double rho1 = densities.a1, rho2 = has_d ? densities.a2 : 0.0;
  const int e = change.e.value(), b = change.b.value(), c = change.c.value();
  ensure_rows(masses, velocities, max_id(change) + 1);

  if (change.kind == BlockChange::Kind::kSplit) {
    const double parent_mass = rho1 * change.area_a1 + rho2 * change.area_a2;  // 3 m_E
    const double to_e_from_b = rho1 * change.area_a10 + rho2 * change.area_a21;
    const double to_e_from_c = rho1 * change.area_a11 + rho2 * change.area_a20;
    masses(e) = parent_mass / 3;
    masses(b) +=
        (rho1 * (change.area_a11 - change.area_a1) + rho2 * (change.area_a20 - change.area_a2)) / 3;
    masses(c) +=
        (rho1 * (change.area_a10 - change.area_a1) + rho2 * (change.area_a21 - change.area_a2)) / 3;
    if (parent_mass > 0)
      velocities.row(e) =
          (velocities.row(c) * to_e_from_c + velocities.row(b) * to_e_from_b) / parent_mass;
    else
      velocities.row(e) = 0.5 * (velocities.row(b) + velocities.row(c));
    return;
  }

  // Merge: the split took (ρ1 (A1 − A11) + ρ2 (A2 − A20)) / 3 from B and the like from C.
  const double from_b = std::max(
      0.0, rho1 * (change.area_a1 - change.area_a11) + rho2 * (change.area_a2 - change.area_a20));
  const double from_c = std::max(
      0.0, rho1 * (change.area_a1 - change.area_a10) + rho2 * (change.area_a2 - change.area_a21));
  const double share_b = (from_b + from_c) > 0 ? from_b / (from_b + from_c) : 0.5;
  const double m_e = masses(e);
  const double gain_b = share_b * m_e, gain_c = m_e - gain_b;
  const Eigen::RowVector3d p_e = m_e * velocities.row(e);
  const Eigen::RowVector3d p_b = masses(b) * velocities.row(b) + share_b * p_e;
  const Eigen::RowVector3d p_c = masses(c) * velocities.row(c) + (p_e - share_b * p_e);
  masses(b) += gain_b;
  masses(c) += gain_c;
  if (masses(b) > 0) velocities.row(b) = p_b / masses(b);
  if (masses(c) > 0) velocities.row(c) = p_c / masses(c);
  masses(e) = 0;
  velocities.row(e).setZero();
}

void place_split_vertex(const BlockChange& change, Eigen::MatrixX3d& positions) {
  if (change.kind != BlockChange::Kind::kSplit) return;
  const int rows = max_id(change) + 1;
  if (positions.rows() < rows) {
    const Eigen::Index old = positions.rows();
    positions.conservativeResize(rows, Eigen::NoChange);
    positions.bottomRows(rows - old).setZero();
  }
  positions.row(change.e.value()) =
      0.5 * (positions.row(change.b.value()) + positions.row(change.c.value()));
}

Eigen::MatrixXd remap_rows(const Eigen::MatrixXd& rows, const std::vector<int>& old_to_new,
                           int new_count) {
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(new_count, rows.cols());
  const Eigen::Index n =
      std::min<Eigen::Index>(rows.rows(), static_cast<Eigen::Index>(old_to_new.size()));
  for (Eigen::Index i = 0; i < n; ++i) {
    const int to = old_to_new[static_cast<std::size_t>(i)];
    if (to < 0) continue;
    if (to >= new_count) throw std::invalid_argument("remap_rows: a new row index is out of range");
    out.row(to) = rows.row(i);
  }
  return out;
}

}  // namespace sd::meshing
