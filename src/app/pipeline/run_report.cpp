#include "src/app/pipeline/run_report.hpp"

#include <algorithm>
#include <cmath>

#include "sim/forces.hpp"

namespace sd::app {
namespace {

nlohmann::json energy_json(const std::vector<sim::EnergySample>& samples) {
  nlohmann::json series = {
      {"time", nlohmann::json::array()},    {"stretch", nlohmann::json::array()},
      {"shear", nlohmann::json::array()},   {"bend", nlohmann::json::array()},
      {"kinetic", nlohmann::json::array()}, {"potential", nlohmann::json::array()}};
  for (const sim::EnergySample& s : samples) {
    series["time"].push_back(s.time);
    series["stretch"].push_back(s.stretch);
    series["shear"].push_back(s.shear);
    series["bend"].push_back(s.bend);
    series["kinetic"].push_back(s.kinetic);
    series["potential"].push_back(s.potential);
  }
  return series;
}

nlohmann::json simulation_json(const sim::SimulationReport& r, const sim::SimulationSettings& s) {
  return {{"steps", r.steps},
          {"sim_time", r.sim_time},
          {"wall_time_s", r.wall_time_s},
          {"cpu_time_s", r.cpu_time_s},
          {"at_rest", r.at_rest},
          {"retries", r.retries},
          {"forced_steps", r.forced_steps},
          {"nan_free", r.nan_free},
          {"vertices", r.vertices},
          {"triangles", r.triangles},
          {"linear_solves", r.linear_solves},
          {"cg_iterations_mean", r.cg_iterations_mean},
          {"cg_iterations_max", r.cg_iterations_max},
          {"cholmod_factorizations", r.cholmod_factorizations},
          {"cholmod_analyses", r.cholmod_analyses},
          {"newton_iterations_mean", r.newton_iterations_mean},
          {"dt_min_used", r.dt_min_used},
          {"dt_max_used", r.dt_max_used},
          {"max_strain", r.max_strain},
          {"max_principal_stretch", r.max_principal_stretch},
          {"max_principal_compression", r.max_principal_compression},
          {"rest",
           {{"speed_window_m_s", r.rest_speed_window},
            {"kinetic_per_kg_window_J_kg", r.rest_kinetic_per_kg_window},
            {"kinetic_per_kg_window_mean_J_kg", r.rest_kinetic_per_kg_window_mean},
            {"speed_final_m_s", r.rest_speed_final},
            {"kinetic_per_kg_final_J_kg", r.rest_kinetic_per_kg_final},
            {"speed_limit_m_s", s.rest_speed},
            {"kinetic_per_kg_limit_J_kg", s.rest_kinetic_energy},
            {"window_s", s.rest_window},
            {"drift_m",
             std::isnan(r.rest_drift) ? nlohmann::json(nullptr) : nlohmann::json(r.rest_drift)},
            {"drift_limit_m", s.rest_speed * s.rest_window},
            {"still_s", r.rest_still_time}}},
          {"contacts_max", r.contacts_max},
          {"max_penetration_m", r.max_penetration_m},
          {"penetrating_vertices_final", r.penetrating_vertices_final},
          {"piercing_body_vertices_final", r.piercing_body_vertices_final},
          {"max_piercing_final_m", r.max_piercing_final_m},
          {"contacts_final", r.contacts_final},
          {"self_collision", s.self_contact.enabled},
          {"self_intersections_start", r.self_intersections_start},
          {"self_untangled_vertices", r.self_untangled_vertices},
          {"self_contacts_max", r.self_contacts_max},
          {"self_contacts_final", r.self_contacts_final},
          {"self_collisions", r.self_collisions},
          {"self_zone_vertices", r.self_zone_vertices},
          {"self_unresolved_steps", r.self_unresolved_steps},
          {"self_culled_share", r.self_culled_share},
          {"self_collision_share", r.wall_time_s > 0.0 ? r.self_collision_s / r.wall_time_s : 0.0},
          {"timing_s",
           {{"forces", r.forces_s},
            {"solve", r.solve_s},
            {"collision", r.collision_s},
            {"self_collision", r.self_collision_s},
            {"other", r.other_s}}},
          {"settings",
           {{"integrator", sim::integrator_name(s.integrator)},
            {"solver", sim::solver_name(s.solver)},
            {"dt", s.dt},
            {"duration", s.duration},
            {"stop_at_rest", s.stop_at_rest}}},
          {"energy", energy_json(r.energy)}};
}

// Per accepted step: time, splits (requested and forced), merges and particles after it.
nlohmann::json adaptive_steps_json(const std::vector<sim::AdaptiveStepRecord>& steps) {
  nlohmann::json out = {{"time", nlohmann::json::array()},
                        {"splits", nlohmann::json::array()},
                        {"merges", nlohmann::json::array()},
                        {"vertices", nlohmann::json::array()}};
  for (const sim::AdaptiveStepRecord& step : steps) {
    out["time"].push_back(step.time);
    out["splits"].push_back(step.splits + step.forced_splits);
    out["merges"].push_back(step.merges);
    out["vertices"].push_back(step.vertices);
  }
  return out;
}

nlohmann::json meshing_json(const MeshingSummary& m) {
  nlohmann::json panels = nlohmann::json::array();
  for (const MeshingSummary::Panel& p : m.panels)
    panels.push_back({{"id", p.id},
                      {"sides", p.sides},
                      {"distortion", p.distortion},
                      {"irregular_vertices", p.irregular_vertices},
                      {"partition", p.partition},
                      {"quads", p.quads}});
  return {{"distortion", m.distortion},
          {"irregular_vertices", m.irregular_vertices},
          {"quads", m.quads},
          {"meshing_ms", m.meshing_ms},
          {"panels", panels}};
}

nlohmann::json adaptive_json(const sim::AdaptiveReport& a) {
  return {{"splits", a.splits},
          {"forced_splits", a.forced_splits},
          {"merges", a.merges},
          {"moved_off_body", a.moved_off_body},
          {"splits_declined_on_body", a.splits_declined_on_body},
          {"body_sags_computed", a.body_sags_computed},
          {"body_sags_reused", a.body_sags_reused},
          {"topology_changes", a.topology_changes},
          {"vertices_min", a.vertices_min},
          {"vertices_max", a.vertices_max},
          {"max_level_reached", a.max_level_reached},
          {"adaptivity_s", a.adaptivity_s()},
          {"steps", adaptive_steps_json(a.steps)}};
}

}  // namespace

std::optional<MeshingSummary> meshing_summary(const ClothScene& scene) {
  if (!scene.garment) return std::nullopt;
  MeshingSummary m;
  for (const garment::GarmentPanel& p : scene.garment->panels) {
    m.distortion += p.distortion;
    m.irregular_vertices += p.irregular_vertices;
    m.panels.push_back(
        {p.id, p.side_counts.size(), p.distortion, p.irregular_vertices, p.partition, p.faces});
  }
  m.quads = scene.garment->mesh.face_count();
  m.meshing_ms = scene.meshing_ms;
  return m;
}

// How far the drape is from the cloth's rest shape (the pattern with "rest": "flat"), per group:
// each triangle's principal stretches σ₁ ≥ σ₂ (sim::principal_stretches, the report's
// max_principal_stretch / _compression over all groups), strain = max(σ₁ − 1, 1 − σ₂); max and
// rest-area-weighted mean.
std::vector<GroupStrain> group_strains(const sim::ClothModel& model,
                                       const Eigen::MatrixX3d& positions,
                                       const Eigen::VectorXi& triangle_group,
                                       const std::vector<std::string>& group_names) {
  std::vector<double> worst(group_names.size(), 0.0), sum(group_names.size(), 0.0),
      area(group_names.size(), 0.0);
  std::vector<GroupStrain> out;
  for (const std::string& name : group_names) out.push_back({name});
  const Eigen::VectorXd x = sim::flatten_positions(positions);
  for (size_t t = 0; t < model.triangles.size(); ++t) {
    const sim::TriangleElement& e = model.triangles[t];
    const Eigen::Vector2d sigma = sim::principal_stretches(e, x);
    const double strain = std::max(sigma(0) - 1, 1 - sigma(1));
    const size_t g = t < static_cast<size_t>(triangle_group.size())
                         ? static_cast<size_t>(triangle_group(static_cast<Eigen::Index>(t)))
                         : 0;
    worst[g] = std::max(worst[g], strain);
    sum[g] += e.rest_area * strain;
    area[g] += e.rest_area;
    if (sigma(0) - 1 > out[g].stretch_max) {
      out[g].stretch_max = sigma(0) - 1;
      out[g].stretch_at = (positions.row(e.vertices[0]) + positions.row(e.vertices[1]) +
                           positions.row(e.vertices[2]))
                              .transpose() /
                          3;
    }
  }
  for (size_t g = 0; g < group_names.size(); ++g) {
    out[g].max = worst[g];
    out[g].mean = area[g] > 0 ? sum[g] / area[g] : 0.0;
  }
  return out;
}

nlohmann::json run_report_json(const RunReport& r) {
  nlohmann::json out = simulation_json(r.simulation, r.settings);
  // Which settings ran, and why the rule chose them (null when the file set solver and step).
  out["settings"]["preconditioner"] =
      r.settings.solver == sim::LinearSolverKind::pcg
          ? (r.settings.pcg_preconditioner == sim::PcgPreconditioner::block_jacobi ? "block-jacobi"
             : r.settings.pcg_preconditioner == sim::PcgPreconditioner::two_level  ? "two-level"
                                                                                   : "block-ic0")
          : "none";
  out["settings"]["automatic"] =
      r.automatic ? nlohmann::json(*r.automatic) : nlohmann::json(nullptr);
  out["self_intersections_final"] = r.self_intersections_final;
  out["format"] = "sketchdrape/1 run report";
  out["sketch"] = r.sketch;
  out["scene"] = r.scene;
  out["fabric"] = r.fabric;
  out["body"] = r.body ? nlohmann::json(*r.body) : nlohmann::json(nullptr);
  out["pinned_vertices"] = r.pinned_vertices;
  out["meshing"] = r.meshing ? meshing_json(*r.meshing) : nlohmann::json(nullptr);
  if (r.imported) out["imported"] = *r.imported;
  out["bending"] = r.bending;
  out["compression"] = r.compression;
  if (r.cusick) out["cusick"] = *r.cusick;
  if (r.cantilever) out["cantilever"] = *r.cantilever;
  out["rest_shape"] = r.rest_shape;
  nlohmann::json strain = nlohmann::json::array();
  for (const GroupStrain& s : r.strain)
    strain.push_back({{"group", s.group},
                      {"strain_max", s.max},
                      {"strain_mean", s.mean},
                      {"stretch_max", s.stretch_max}});
  out["strain"] = strain;
  if (r.pattern) out["pattern"] = *r.pattern;
  out["adaptive"] = r.adaptive ? adaptive_json(*r.adaptive) : nlohmann::json(nullptr);
  if (r.slice_dent) {
    const meshing::SliceDent& dent = *r.slice_dent;
    out["slice_dent"] = {{"depth_m", dent.depth},
                         {"height_m", dent.height},
                         {"where", {dent.where.x(), dent.where.y(), dent.where.z()}},
                         {"from_fraction", 0.1},
                         {"to_fraction", r.slice_dent_to}};
  } else {
    out["slice_dent"] = nullptr;  // no garment, or none of it below the crotch (a top)
  }
  out["settled_drop_m"] =
      r.settled_drop ? nlohmann::json(*r.settled_drop) : nlohmann::json(nullptr);
  // What the run warned about (the same sentences as on the terminal), empty when nothing.
  out["warnings"] = r.warnings;
  out["quality_warnings"] = r.quality_warnings;
  out["images"] = r.images;
  out["frames"] = r.frames;
  out["body_motion"] = nullptr;
  if (r.body_motion) {
    const BodyMotionSummary& m = *r.body_motion;
    out["body_motion"] = {{"type", m.type}, {"start", m.start}, {"end", m.end}};
    if (m.poses) out["body_motion"]["poses"] = *m.poses;
    if (m.degrees) out["body_motion"]["degrees"] = *m.degrees;
  }
  // Adaptivity (estimates, splits, merges, model rebuilds) next to the simulator's split.
  out["timing_s"]["adaptivity"] = r.adaptive ? r.adaptive->adaptivity_s() : 0.0;
  out["timing_s"]["images"] = r.images_s;
  out["timing_s"]["total"] = r.total_s;
  return out;
}

std::optional<double> slice_dent_top(double low, double high, std::optional<double> crotch) {
  if (!crotch) return 0.6;
  if (*crotch - low < 0.05 || !(high > low)) return std::nullopt;
  return std::min(0.6, (*crotch - low) / (high - low));
}

}  // namespace sd::app
