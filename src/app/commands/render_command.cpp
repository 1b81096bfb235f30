// `sketchdrape render MESH [--body BODY] [--up A] [--facing A] [--height M] [--scale S]
// [--view V ...] [--size WxH] -o OUT`: preview images.
//
// MESH alone is a body ("builtin" or any file assimp reads), normalised by load_body with the
// body options `info` takes. With
// --body, MESH is a garment drawn as cloth over that body; it must already be in the body's
// normalised frame (metres, +Y up, facing +Z, feet on y = 0), as the pipeline exports it, and
// each mesh/group in the file becomes one panel colour.
//
// OUT is a directory receiving <view>.png per view, unless it ends in ".png": then it is the
// file for the single view asked. All images are staged and committed together.

#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <array>
#include <assimp/Importer.hpp>
#include <cctype>
#include <chrono>
#include <filesystem>
#include <iostream>
#include <map>
#include <optional>
#include <stdexcept>

#include "garment/body.hpp"
#include "garment/body_landmarks.hpp"
#include "garment/input_checks.hpp"
#include "garment/sketch_ranges.hpp"
#include "src/app/commands/cli.hpp"
#include "src/app/pipeline/atomic_file.hpp"
#include "src/app/pipeline/progress.hpp"
#include "src/render/camera.hpp"
#include "src/render/image.hpp"
#include "src/render/renderer.hpp"
#include "src/render/scene.hpp"

namespace sd::app {
namespace {

// A garment mesh file that cannot be used. Bad user input (exit code 2).
class MeshFileError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

struct RenderOptions {
  std::string mesh;
  std::string body;
  BodyFileOptions reading;  // how to read the body file, as `info` takes it
  std::vector<std::string> views;
  std::string size = "800x1200";
  std::string output;
  std::vector<double> eye, target;
  double fov = render::kDefaultFovYDeg;
  bool wireframe = false;
  bool no_shadows = false;
  bool no_ground = false;
  bool landmarks = false;
};

// A small red octahedron (radius 1.5 cm) at every landmark of the body, as one mesh.
render::SceneMesh landmark_markers(const meshing::TriMesh& body) {
  const garment::BodyLandmarks landmarks = garment::find_landmarks(body);
  constexpr double kRadius = 0.015;
  const int corners[8][3] = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4},
                             {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
  const Eigen::Vector3d axes[6] = {{1, 0, 0},  {-1, 0, 0}, {0, 0, 1},
                                   {0, 0, -1}, {0, 1, 0},  {0, -1, 0}};
  render::SceneMesh markers;
  const auto n = static_cast<Eigen::Index>(landmarks.points.size());
  markers.mesh.vertices.resize(6 * n, 3);
  markers.mesh.faces.resize(8 * n, 3);
  for (Eigen::Index l = 0; l < n; ++l) {
    for (int k = 0; k < 6; ++k)
      markers.mesh.vertices.row(6 * l + k) =
          (landmarks.points[static_cast<size_t>(l)].position + kRadius * axes[k]).transpose();
    for (int f = 0; f < 8; ++f)
      markers.mesh.faces.row(8 * l + f) << 6 * l + corners[f][0], 6 * l + corners[f][1],
          6 * l + corners[f][2];
  }
  markers.role = render::MeshRole::kCloth;
  markers.colour = {0.85f, 0.1f, 0.1f};
  markers.back_colour = {0.85f, 0.1f, 0.1f};
  return markers;
}

struct GarmentMesh {
  meshing::TriMesh mesh;
  Eigen::VectorXi panel_ids;  // #F: index of the file's mesh (group) each triangle came from
};

void collect(const aiScene& scene, const aiNode& node, const aiMatrix4x4& parent,
             std::vector<Eigen::Vector3d>& points, std::vector<Eigen::Vector3i>& triangles,
             std::vector<int>& panels) {
  const aiMatrix4x4 transform = parent * node.mTransformation;
  for (unsigned m = 0; m < node.mNumMeshes; ++m) {
    const aiMesh& mesh = *scene.mMeshes[node.mMeshes[m]];
    const int base = static_cast<int>(points.size());
    for (unsigned v = 0; v < mesh.mNumVertices; ++v) {
      const aiVector3D p = transform * mesh.mVertices[v];
      points.emplace_back(p.x, p.y, p.z);
    }
    for (unsigned f = 0; f < mesh.mNumFaces; ++f) {
      const aiFace& face = mesh.mFaces[f];
      if (face.mNumIndices != 3) continue;  // points and lines
      triangles.emplace_back(base + static_cast<int>(face.mIndices[0]),
                             base + static_cast<int>(face.mIndices[1]),
                             base + static_cast<int>(face.mIndices[2]));
      panels.push_back(static_cast<int>(node.mMeshes[m]));
    }
  }
  for (unsigned c = 0; c < node.mNumChildren; ++c)
    collect(scene, *node.mChildren[c], transform, points, triangles, panels);
}

// Reads a garment mesh as it is: no rescaling or re-orientation (it shares the body's frame).
GarmentMesh load_garment_mesh(const std::string& path) {
  if (const auto problem = garment::input_file_problem(path, garment::kMaxMeshFileBytes))
    throw MeshFileError(fmt::format("garment mesh file '{}' {}", path, *problem));
  try {
    // The body's loader refuses these headers too: assimp would reserve gigabytes for a PLY or
    // OFF header's counts, or read a PLY header without end_header for ever.
    garment::check_mesh_file_header(path, "garment mesh");
  } catch (const garment::BodyError& e) {
    throw MeshFileError(e.what());
  }
  Assimp::Importer importer;
  const aiScene* scene =
      importer.ReadFile(path, aiProcess_Triangulate | aiProcess_JoinIdenticalVertices);
  if (scene == nullptr || scene->mRootNode == nullptr)
    throw MeshFileError(
        fmt::format("cannot read garment mesh '{}': {}", path, importer.GetErrorString()));
  std::vector<Eigen::Vector3d> points;
  std::vector<Eigen::Vector3i> triangles;
  std::vector<int> panels;
  collect(*scene, *scene->mRootNode, aiMatrix4x4(), points, triangles, panels);
  if (triangles.empty())
    throw MeshFileError(fmt::format("garment mesh '{}' holds no triangles", path));
  GarmentMesh out;
  out.mesh.vertices.resize(static_cast<Eigen::Index>(points.size()), 3);
  for (size_t i = 0; i < points.size(); ++i) {
    if (!points[i].allFinite())
      throw MeshFileError(fmt::format("garment mesh '{}' has NaN or infinite coordinates", path));
    out.mesh.vertices.row(static_cast<Eigen::Index>(i)) = points[i].transpose();
  }
  out.mesh.faces.resize(static_cast<Eigen::Index>(triangles.size()), 3);
  out.panel_ids.resize(static_cast<Eigen::Index>(triangles.size()));
  for (size_t i = 0; i < triangles.size(); ++i) {
    out.mesh.faces.row(static_cast<Eigen::Index>(i)) = triangles[i].transpose();
    out.panel_ids[static_cast<Eigen::Index>(i)] = panels[i];
  }
  // The same check as for a body: a mesh without area draws nothing and frames no camera.
  if (const auto problem = garment::mesh_problem(out.mesh))
    throw MeshFileError(fmt::format("garment mesh '{}' {}", path, *problem));
  return out;
}

// The faces with each vertex replaced by the first one at the same position: assimp gives every
// group of a garment file its own vertices, so the panels sewn together share positions only.
Eigen::MatrixXi faces_joined_by_position(const meshing::TriMesh& mesh) {
  std::map<std::array<double, 3>, int> first;
  std::vector<int> joined(static_cast<size_t>(mesh.vertices.rows()));
  for (Eigen::Index v = 0; v < mesh.vertices.rows(); ++v)
    joined[static_cast<size_t>(v)] =
        first
            .emplace(std::array{mesh.vertices(v, 0), mesh.vertices(v, 1), mesh.vertices(v, 2)},
                     static_cast<int>(v))
            .first->second;
  Eigen::MatrixXi faces = mesh.faces;
  for (Eigen::Index f = 0; f < faces.rows(); ++f)
    for (Eigen::Index k = 0; k < faces.cols(); ++k)
      faces(f, k) = joined[static_cast<size_t>(faces(f, k))];
  return faces;
}

Eigen::Vector3d point_option(const std::vector<double>& values, const char* name) {
  if (values.size() != 3)
    throw std::invalid_argument(fmt::format("{} needs three numbers X,Y,Z in metres", name));
  return {values[0], values[1], values[2]};
}

bool names_png_file(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext == ".png";
}

struct ViewJob {
  std::string name;  // file stem: a view name or "custom"
  std::optional<render::ViewName> preset;
  render::Camera camera;  // used when preset is empty
};

void run_render(const RenderOptions& options, const GlobalOptions& global) {
  // Everything the user typed is checked before any mesh is loaded or file staged.
  const render::ImageSize size = render::parse_image_size(options.size);
  std::vector<ViewJob> jobs;
  for (const std::string& text : options.views) {
    const render::ViewName view = render::parse_view_name(text);
    const std::string name = render::view_name(view);
    if (std::none_of(jobs.begin(), jobs.end(), [&](const ViewJob& j) { return j.name == name; }))
      jobs.push_back({name, view, {}});
  }
  if (!options.eye.empty() || !options.target.empty()) {
    ViewJob custom{"custom", std::nullopt, {}};
    custom.camera.eye = point_option(options.eye, "--eye");
    custom.camera.target = point_option(options.target, "--target");
    custom.camera.fov_y_deg = options.fov;
    render::validate_camera(custom.camera);
    jobs.push_back(custom);
  }
  if (jobs.empty()) jobs.push_back({"front", render::ViewName::kFront, {}});
  const bool single_file = names_png_file(options.output);
  if (single_file && jobs.size() != 1)
    throw std::invalid_argument(fmt::format(
        "-o {} names one image but {} views were asked: give a directory to get one PNG per view",
        options.output, jobs.size()));
  check_output_folder(single_file ? std::filesystem::path(options.output).parent_path()
                                  : std::filesystem::path(options.output));

  render::Scene scene;
  scene.ground = !options.no_ground;
  scene.shadows = !options.no_shadows;
  if (options.body.empty()) {
    render::SceneMesh& body = scene.meshes.emplace_back();
    body.mesh = garment::load_body(options.mesh, options.reading.body_options()).mesh;
    body.role = render::MeshRole::kBody;
  } else {
    render::SceneMesh& body = scene.meshes.emplace_back();
    body.mesh = garment::load_body(options.body, options.reading.body_options()).mesh;
    body.role = render::MeshRole::kBody;
    GarmentMesh garment_mesh = load_garment_mesh(options.mesh);
    render::SceneMesh& cloth = scene.meshes.emplace_back();
    cloth.face_colours =
        render::panel_colours(garment_mesh.panel_ids, faces_joined_by_position(garment_mesh.mesh));
    cloth.mesh = std::move(garment_mesh.mesh);
    cloth.role = render::MeshRole::kCloth;
  }
  if (options.wireframe) {
    render::SceneMesh& drawn = scene.meshes.back();  // the garment if there is one
    render::Wireframe wire;
    wire.edges = render::triangle_edges(drawn.mesh);
    wire.width_px = 1.0f;
    drawn.wireframe = wire;
  }
  // Markers last, so that the wireframe above stays on the garment (or the body).
  if (options.landmarks) {
    render::SceneMesh markers = landmark_markers(scene.meshes.front().mesh);
    scene.meshes.push_back(std::move(markers));
  }

  const auto start = std::chrono::steady_clock::now();
  render::Renderer renderer;
  const render::PreparedScene prepared = renderer.prepare(scene);
  StagedOutputs outputs;
  outputs.keep(options.mesh);
  if (!options.body.empty()) outputs.keep(options.body);
  Progress progress("rendering", static_cast<long>(jobs.size()), global.quiet);
  for (size_t i = 0; i < jobs.size(); ++i) {
    const ViewJob& job = jobs[i];
    progress.update(static_cast<long>(i), job.name);
    const render::Camera camera =
        job.preset ? render::frame_view(*job.preset, prepared.bounds(), size.aspect()) : job.camera;
    const render::Image image = renderer.render(prepared, camera, size);
    const std::filesystem::path path =
        single_file ? std::filesystem::path(options.output)
                    : std::filesystem::path(options.output) / (job.name + ".png");
    outputs.stage(path, render::encode_png(image));
    spdlog::debug("{}: eye ({:.3f}, {:.3f}, {:.3f}) target ({:.3f}, {:.3f}, {:.3f}) fov {:.1f}",
                  job.name, camera.eye.x(), camera.eye.y(), camera.eye.z(), camera.target.x(),
                  camera.target.y(), camera.target.z(), camera.fov_y_deg);
  }
  progress.update(static_cast<long>(jobs.size()));
  progress.finish();
  outputs.commit();
  spdlog::debug("rendered {} view(s) at {}x{} in {:.3f} s", jobs.size(), size.width, size.height,
                std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  for (const auto& path : outputs.paths()) std::cout << path.string() << "\n";
}

}  // namespace

void add_render_command(CLI::App& app, const GlobalOptions& global) {
  auto options = std::make_shared<RenderOptions>();
  CLI::App* cmd = app.add_subcommand(
      "render", "Render a body, or a garment over a body, to one PNG per view (docs/rendering.md)");
  cmd->add_option("MESH", options->mesh,
                  "Body mesh ('builtin' or a file assimp reads), or with --body a garment mesh")
      ->required();
  cmd->add_option("--body", options->body,
                  "Draw MESH as cloth over this body ('builtin' or a file)");
  // The body (MESH, or --body's) read as `info` reads it: a file that breaks its up axis's
  // facing convention or needs a scale is drawn, and its landmarks found, only with these.
  add_body_file_options(*cmd, options->reading);
  cmd->add_option("--view", options->views,
                  "front, back, left, right, three-quarter or top; repeat for several (default "
                  "front)");
  cmd->add_option("--size", options->size, "Image size WIDTHxHEIGHT in pixels")
      ->capture_default_str();
  cmd->add_option("--eye", options->eye,
                  "Explicit camera position X,Y,Z (metres); adds view 'custom'")
      ->check(finite_range(-1000, 1000))
      ->expected(3)
      ->delimiter(',');
  cmd->add_option("--target", options->target, "Point the explicit camera looks at, X,Y,Z")
      ->check(finite_range(-1000, 1000))
      ->expected(3)
      ->delimiter(',');
  cmd->add_option("--fov", options->fov, "Vertical field of view of the explicit camera, degrees")
      ->check(finite_range(1, 170))
      ->capture_default_str();
  cmd->add_flag("--wireframe", options->wireframe, "Overlay the triangle edges of MESH");
  cmd->add_flag("--no-shadows", options->no_shadows, "Draw without the key light's shadows");
  cmd->add_flag("--no-ground", options->no_ground, "Draw without the floor");
  cmd->add_flag("--landmarks", options->landmarks,
                "Mark the body's landmarks (red; sketchdrape info lists them, docs/bodies.md)");
  cmd->add_option("-o,--output", options->output,
                  "Output directory (one <view>.png each), or a .png file for a single view")
      ->check(non_empty_path())
      ->required();
  cmd->callback([options, &global] { run_render(*options, global); });
}

}  // namespace sd::app
