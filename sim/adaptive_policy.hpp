#pragma once
// The rules of adaptive detail (docs/adaptive.md, "Rules"): which blocks to merge and which edges
// to split on this step, from the error estimate and the state. Pure selection: nothing here
// changes the mesh or the cloth.

#include <Eigen/Core>
#include <array>
#include <functional>
#include <optional>
#include <utility>
#include <vector>

#include "meshing/mesh48.hpp"
#include "sim/adaptive_settings.hpp"
#include "sim/cloth_model.hpp"

namespace sd::sim {

// What the merge rules read: the mesh, the settings, each triangle's birth time (by id, simulated
// seconds) and the state (flat positions and velocities, 3·#V).
struct MergeInputs {
  const meshing::Mesh48& mesh;
  const AdaptiveSettings& settings;
  BendRestShape bend_rest;
  const std::vector<double>& birth;
  const Eigen::VectorXd& x;
  const Eigen::VectorXd& v;
  double now;  // s
  // The body sag under the chord between two points (adaptive_estimate.hpp), or empty without a
  // body in contact: a merge next to a curved body would make the next split.
  std::function<double(const Eigen::Vector3d&, const Eigen::Vector3d&)> body_sag;
};

// Whether split block k (children leaves) may merge now, and how far the merge moves the surface
// (|x_E − (x_B + x_C)/2|): old enough, flat (that and the sag of every hinge around E below the
// coarsen threshold), steady (every hinge around E turns slower than steady_rate), the parent's
// outer edges flat enough, and no body bulging under its diagonal.
std::optional<double> merge_error(const MergeInputs& in, meshing::BlockId k);

// The blocks to merge on this step with their merge errors, flattest first: split blocks whose
// children are leaves, at or above min_level, that merge_error accepts; with even_levels, even
// blocks together with their split children (each child judged as any merge, the block as it
// will be once they are merged).
std::vector<std::pair<double, meshing::BlockId>> merge_candidates(const MergeInputs& in);

// How many merges the candidates make (with even_levels a block's split children count too).
std::size_t merge_count(const meshing::Mesh48& mesh, const AdaptiveSettings& settings,
                        const std::vector<std::pair<double, meshing::BlockId>>& merges);

// Interior edges (rows of Mesh48Arrays::interior_edges) whose estimate is above the refine
// threshold and that can still be refined, largest first.
std::vector<std::pair<double, int>> refine_candidates(const Eigen::VectorXd& errors,
                                                      const meshing::Mesh48Arrays& arrays,
                                                      const AdaptiveSettings& settings);

// With even_levels, the complete leaf blocks at an odd level below max_level: they are split on
// this step whatever their estimate (only splits make them; a pending one is the strip next to a
// coarser region and stays).
std::vector<meshing::BlockId> odd_level_blocks(const meshing::Mesh48& mesh,
                                               const AdaptiveSettings& settings);

}  // namespace sd::sim
