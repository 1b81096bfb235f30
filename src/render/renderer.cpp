#include "src/render/renderer.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>

#include "src/render/gl.hpp"
#include "src/render/shader_program.hpp"

namespace sd::render {
namespace {

// Lighting, in linear RGB. The key light comes from above and to the camera's left (so every
// named view is lit from the front), the fill from the right and lower.
constexpr double kKeyAzimuthDeg = 35;    // left of the camera, around +Y
constexpr double kKeyElevationDeg = 50;  // above the horizon
constexpr double kFillAzimuthDeg = -60;  // right of the camera
constexpr double kFillElevationDeg = 15;
const Eigen::Vector3f kKeyColour{0.86f, 0.83f, 0.78f};
const Eigen::Vector3f kFillColour{0.18f, 0.20f, 0.25f};
const Eigen::Vector3f kSkyAmbient{0.24f, 0.25f, 0.28f};
const Eigen::Vector3f kGroundAmbient{0.10f, 0.09f, 0.08f};

// Shadow softness: PCF taps this many texels apart (a 3x3 grid: the penumbra is ~2 spreads + 1
// texel, about 1.3 cm on the floor of a standing body with a 2048 map).
constexpr float kPcfSpreadTexels = 2.5f;
// The floor extends this many times the scene's largest extent from its centre, fading out.
constexpr double kGroundRadiusFactor = 1.2;

constexpr int kDefaultBufferSide = 16;  // OSMesa's own buffer; frames go to framebuffer objects

void check_gl(const char* what) {
  const GLenum error = glGetError();
  if (error == GL_NO_ERROR) return;
  while (glGetError() != GL_NO_ERROR) {
  }
  throw RenderError(fmt::format("OpenGL error 0x{:04x} while {}", error, what));
}

void check_framebuffer(const char* what) {
  const GLenum status = glCheckFramebufferStatus(GL_FRAMEBUFFER);
  if (status != GL_FRAMEBUFFER_COMPLETE)
    throw RenderError(fmt::format("framebuffer for {} is incomplete (0x{:04x})", what, status));
}

double radians(double degrees) {
  return degrees * std::numbers::pi / 180.0;
}

// Unit vector toward a light at `azimuth` (counter-clockwise seen from above, from the
// camera's backward horizontal direction) and `elevation`.
Eigen::Vector3d light_direction(const Camera& camera, double azimuth_deg, double elevation_deg) {
  Eigen::Vector3d back = camera.eye - camera.target;
  back.y() = 0;
  if (back.norm() < 1e-9 * (camera.eye - camera.target).norm()) {
    // Looking straight down or up: "behind the camera" is the image's downward direction.
    back = -camera.up;
    back.y() = 0;
  }
  if (back.norm() < 1e-12) back = Eigen::Vector3d::UnitZ();
  back.normalize();
  const Eigen::Vector3d horizontal =
      Eigen::AngleAxisd(radians(-azimuth_deg), Eigen::Vector3d::UnitY()) * back;
  return std::cos(radians(elevation_deg)) * horizontal +
         std::sin(radians(elevation_deg)) * Eigen::Vector3d::UnitY();
}

std::array<Eigen::Vector3d, 8> box_corners(const meshing::BoundingBox& box) {
  std::array<Eigen::Vector3d, 8> out;
  for (int i = 0; i < 8; ++i)
    out[i] = {(i & 1) ? box.max.x() : box.min.x(), (i & 2) ? box.max.y() : box.min.y(),
              (i & 4) ? box.max.z() : box.min.z()};
  return out;
}

GLuint make_buffer(GLenum target, GLsizeiptr bytes, const void* data) {
  GLuint id = 0;
  glGenBuffers(1, &id);
  glBindBuffer(target, id);
  glBufferData(target, bytes, data, GL_STATIC_DRAW);
  return id;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// The context and everything that lives as long as it.

struct Renderer::Impl {
  RendererOptions options;
  OSMesaContext context = nullptr;
  std::vector<unsigned char> default_buffer;
  std::string version, renderer_name;
  int samples = 1;  // per pixel in the draw framebuffer

  std::unique_ptr<ShaderProgram> mesh_program, ground_program, shadow_program, line_program;
  GLuint shadow_fbo = 0, shadow_texture = 0;

  // Frame targets for one framebuffer size, rebuilt when the size changes.
  int target_width = 0, target_height = 0;
  GLuint draw_fbo = 0, draw_colour = 0, draw_depth = 0;  // multisampled with MSAA
  GLuint resolve_fbo = 0, resolve_colour = 0;            // MSAA only
  std::vector<std::uint8_t> readback;

  Impl() = default;
  Impl(const Impl&) = delete;
  Impl& operator=(const Impl&) = delete;

  ~Impl() {
    if (context == nullptr) return;
    if (!try_make_current()) {  // cannot free GL objects; the context takes them with it
      OSMesaDestroyContext(context);
      return;
    }
    release_targets();
    glDeleteFramebuffers(1, &shadow_fbo);
    glDeleteTextures(1, &shadow_texture);
    mesh_program.reset();
    ground_program.reset();
    shadow_program.reset();
    line_program.reset();
    OSMesaDestroyContext(context);
  }

  bool try_make_current() noexcept {
    return OSMesaGetCurrentContext() == context ||
           OSMesaMakeCurrent(context, default_buffer.data(), GL_UNSIGNED_BYTE, kDefaultBufferSide,
                             kDefaultBufferSide);
  }

  void make_current() {
    if (!try_make_current()) throw RenderError("OSMesa could not make the OpenGL context current");
  }

  void create_context() {
    // The highest core profile first; Mesa 22 offers 4.5 (4.6 is refused).
    for (const auto& [major, minor] : {std::pair{4, 6}, std::pair{4, 5}}) {
      const int attributes[] = {OSMESA_FORMAT,
                                OSMESA_RGBA,
                                OSMESA_DEPTH_BITS,
                                0,
                                OSMESA_STENCIL_BITS,
                                0,
                                OSMESA_ACCUM_BITS,
                                0,
                                OSMESA_PROFILE,
                                OSMESA_CORE_PROFILE,
                                OSMESA_CONTEXT_MAJOR_VERSION,
                                major,
                                OSMESA_CONTEXT_MINOR_VERSION,
                                minor,
                                0};
      context = OSMesaCreateContextAttribs(attributes, nullptr);
      if (context != nullptr) break;
    }
    if (context == nullptr)
      throw RenderError(
          "OSMesa could not create an OpenGL 4.5 core context (is libosmesa6 from Mesa 20 or "
          "newer installed?)");
    default_buffer.assign(kDefaultBufferSide * kDefaultBufferSide * 4, 0);
    make_current();
    const auto text = [](GLenum name) {
      const auto* s = reinterpret_cast<const char*>(glGetString(name));
      return std::string(s ? s : "unknown");
    };
    version = text(GL_VERSION);
    renderer_name = text(GL_RENDERER);
    GLint max_samples = 1;
    glGetIntegerv(GL_MAX_SAMPLES, &max_samples);
    samples =
        options.antialiasing == Antialiasing::kMsaa4 ? std::min(4, std::max(1, max_samples)) : 1;
    spdlog::debug("OpenGL {} on {}, GLSL {}, {} sample(s) per pixel", version, renderer_name,
                  text(GL_SHADING_LANGUAGE_VERSION), samples);
  }

  void create_shadow_map() {
    const int side = options.shadow_map_size;
    glGenTextures(1, &shadow_texture);
    glBindTexture(GL_TEXTURE_2D, shadow_texture);
    glTexStorage2D(GL_TEXTURE_2D, 1, GL_DEPTH_COMPONENT24, side, side);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_BORDER);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_BORDER);
    const float far_depth[] = {1, 1, 1, 1};  // outside the map: lit
    glTexParameterfv(GL_TEXTURE_2D, GL_TEXTURE_BORDER_COLOR, far_depth);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_COMPARE_MODE, GL_COMPARE_REF_TO_TEXTURE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_COMPARE_FUNC, GL_LEQUAL);
    glGenFramebuffers(1, &shadow_fbo);
    glBindFramebuffer(GL_FRAMEBUFFER, shadow_fbo);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_TEXTURE_2D, shadow_texture, 0);
    glDrawBuffer(GL_NONE);
    glReadBuffer(GL_NONE);
    check_framebuffer("the shadow map");
    check_gl("creating the shadow map");
  }

  void release_targets() {
    glDeleteFramebuffers(1, &draw_fbo);
    glDeleteFramebuffers(1, &resolve_fbo);
    glDeleteRenderbuffers(1, &draw_colour);
    glDeleteRenderbuffers(1, &draw_depth);
    glDeleteRenderbuffers(1, &resolve_colour);
    draw_fbo = resolve_fbo = draw_colour = draw_depth = resolve_colour = 0;
    target_width = target_height = 0;
  }

  void ensure_targets(int width, int height) {
    if (width == target_width && height == target_height) return;
    release_targets();
    const auto storage = [&](GLuint& rb, GLenum format, int count) {
      glGenRenderbuffers(1, &rb);
      glBindRenderbuffer(GL_RENDERBUFFER, rb);
      if (count > 1)
        glRenderbufferStorageMultisample(GL_RENDERBUFFER, count, format, width, height);
      else
        glRenderbufferStorage(GL_RENDERBUFFER, format, width, height);
    };
    storage(draw_colour, GL_RGBA8, samples);
    storage(draw_depth, GL_DEPTH_COMPONENT24, samples);
    glGenFramebuffers(1, &draw_fbo);
    glBindFramebuffer(GL_FRAMEBUFFER, draw_fbo);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, draw_colour);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, draw_depth);
    check_framebuffer("drawing");
    if (samples > 1) {
      storage(resolve_colour, GL_RGBA8, 1);
      glGenFramebuffers(1, &resolve_fbo);
      glBindFramebuffer(GL_FRAMEBUFFER, resolve_fbo);
      glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER,
                                resolve_colour);
      check_framebuffer("resolving samples");
    }
    check_gl("allocating the frame (is the image too large?)");
    target_width = width;
    target_height = height;
  }
};

// ---------------------------------------------------------------------------------------------
// A scene on the GPU.

namespace {

struct GpuMesh {
  GLuint vao = 0, vertex_buffer = 0, index_buffer = 0, colour_buffer = 0;
  GLsizei index_count = 0;
  bool two_sided = false;
  Eigen::Vector3f back_colour = Eigen::Vector3f::Zero();
  float specular = 0, shininess = 1;
  GLuint line_vao = 0, line_buffer = 0;
  GLsizei line_vertex_count = 0;
  float line_width = 1;
};

}  // namespace

struct PreparedScene::Data {
  std::shared_ptr<Renderer::Impl> owner;
  std::vector<GpuMesh> meshes;
  meshing::BoundingBox bounds;
  bool ground = false, shadows = false;
  Eigen::Vector3f background = Eigen::Vector3f::Ones(), ground_colour = Eigen::Vector3f::Ones();
  Eigen::Vector3d ground_centre = Eigen::Vector3d::Zero();
  double ground_radius = 1;
  GLuint ground_vao = 0, ground_buffer = 0;

  Data() = default;
  Data(const Data&) = delete;
  Data& operator=(const Data&) = delete;

  ~Data() {
    if (!owner || !owner->try_make_current()) return;
    for (GpuMesh& m : meshes) {
      glDeleteVertexArrays(1, &m.vao);
      glDeleteVertexArrays(1, &m.line_vao);
      const GLuint buffers[] = {m.vertex_buffer, m.index_buffer, m.colour_buffer, m.line_buffer};
      glDeleteBuffers(4, buffers);
    }
    glDeleteVertexArrays(1, &ground_vao);
    glDeleteBuffers(1, &ground_buffer);
  }

  // Every point that must be inside the view and shadow frusta: mesh bounds and floor corners.
  std::vector<Eigen::Vector3d> extent_points() const {
    std::vector<Eigen::Vector3d> points;
    for (const Eigen::Vector3d& c : box_corners(bounds)) points.push_back(c);
    if (ground)
      for (int i = 0; i < 4; ++i)
        points.push_back(ground_centre + Eigen::Vector3d((i & 1) ? ground_radius : -ground_radius,
                                                         0,
                                                         (i & 2) ? ground_radius : -ground_radius));
    return points;
  }
};

PreparedScene::PreparedScene(std::unique_ptr<Data> data) : data_(std::move(data)) {}
PreparedScene::PreparedScene(PreparedScene&&) noexcept = default;
PreparedScene& PreparedScene::operator=(PreparedScene&&) noexcept = default;
PreparedScene::~PreparedScene() = default;
const meshing::BoundingBox& PreparedScene::bounds() const {
  return data_->bounds;
}

namespace {

// Interleaved position + normal (6 floats per vertex) in attribute locations 0 and 1.
void upload_surface(GpuMesh& gpu, const meshing::TriMesh& mesh, const Eigen::MatrixX3f& colours) {
  const Eigen::MatrixX3d normals = meshing::vertex_normals(mesh);
  Eigen::Matrix<float, Eigen::Dynamic, 6, Eigen::RowMajor> vertices(mesh.vertex_count(), 6);
  vertices.leftCols<3>() = mesh.vertices.cast<float>();
  vertices.rightCols<3>() = normals.cast<float>();
  const Eigen::Matrix<GLuint, Eigen::Dynamic, 3, Eigen::RowMajor> indices =
      mesh.faces.cast<GLuint>();
  Eigen::Matrix<float, Eigen::Dynamic, 4, Eigen::RowMajor> face_colours(mesh.face_count(), 4);
  face_colours.leftCols<3>() = colours;
  face_colours.col(3).setOnes();

  glGenVertexArrays(1, &gpu.vao);
  glBindVertexArray(gpu.vao);
  gpu.vertex_buffer =
      make_buffer(GL_ARRAY_BUFFER, vertices.size() * sizeof(float), vertices.data());
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 6 * sizeof(float), nullptr);
  glEnableVertexAttribArray(1);
  glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, 6 * sizeof(float),
                        reinterpret_cast<const void*>(3 * sizeof(float)));
  gpu.index_buffer =
      make_buffer(GL_ELEMENT_ARRAY_BUFFER, indices.size() * sizeof(GLuint), indices.data());
  gpu.index_count = static_cast<GLsizei>(indices.size());
  glBindVertexArray(0);
  // An SSBO may not be empty; one dummy colour for a mesh without faces.
  gpu.colour_buffer = make_buffer(GL_SHADER_STORAGE_BUFFER,
                                  std::max<Eigen::Index>(face_colours.size(), 4) * sizeof(float),
                                  face_colours.size() ? face_colours.data() : nullptr);
}

// Two vertices per edge, position + sRGB colour, in attribute locations 0 and 1.
void upload_wireframe(GpuMesh& gpu, const meshing::TriMesh& mesh, const Wireframe& wire) {
  Eigen::VectorXd values = wire.edge_values;
  if (wire.face_values.size() > 0)
    values = edge_values_from_faces(mesh, wire.edges, wire.face_values);
  double lo = wire.min_value, hi = wire.max_value;
  if (!(lo < hi) && values.size() > 0) {
    lo = std::numeric_limits<double>::infinity();
    hi = -lo;
    for (double v : values)
      if (std::isfinite(v)) lo = std::min(lo, v), hi = std::max(hi, v);
  }
  const auto colour_of = [&](Eigen::Index e) -> Eigen::Vector3f {
    if (values.size() == 0 || !std::isfinite(values[e])) return wire.colour;
    if (wire.colour_map == ColourMap::kLevels)
      return colour_map(ColourMap::kLevels, values[e] - lo);
    return colour_map(ColourMap::kViridis, hi > lo ? (values[e] - lo) / (hi - lo) : 0.0);
  };
  Eigen::Matrix<float, Eigen::Dynamic, 6, Eigen::RowMajor> vertices(2 * wire.edges.rows(), 6);
  for (Eigen::Index e = 0; e < wire.edges.rows(); ++e) {
    const Eigen::Vector3f colour = colour_of(e);
    for (int k = 0; k < 2; ++k) {
      vertices.block<1, 3>(2 * e + k, 0) = mesh.vertices.row(wire.edges(e, k)).cast<float>();
      vertices.block<1, 3>(2 * e + k, 3) = colour.transpose();
    }
  }
  glGenVertexArrays(1, &gpu.line_vao);
  glBindVertexArray(gpu.line_vao);
  gpu.line_buffer = make_buffer(GL_ARRAY_BUFFER, vertices.size() * sizeof(float), vertices.data());
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 6 * sizeof(float), nullptr);
  glEnableVertexAttribArray(1);
  glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, 6 * sizeof(float),
                        reinterpret_cast<const void*>(3 * sizeof(float)));
  glBindVertexArray(0);
  gpu.line_vertex_count = static_cast<GLsizei>(vertices.rows());
  gpu.line_width = wire.width_px;
}

void upload_ground(PreparedScene::Data& data, double floor_y) {
  const Eigen::Vector3d c = data.ground_centre;
  const double r = data.ground_radius;
  // Two triangles, position + normal (+Y), same layout as a mesh.
  const float y = static_cast<float>(floor_y);
  const float x0 = static_cast<float>(c.x() - r), x1 = static_cast<float>(c.x() + r);
  const float z0 = static_cast<float>(c.z() - r), z1 = static_cast<float>(c.z() + r);
  const std::array<float, 36> vertices{x0, y, z0, 0, 1, 0, x0, y, z1, 0, 1, 0, x1, y, z1, 0, 1, 0,
                                       x0, y, z0, 0, 1, 0, x1, y, z1, 0, 1, 0, x1, y, z0, 0, 1, 0};
  glGenVertexArrays(1, &data.ground_vao);
  glBindVertexArray(data.ground_vao);
  data.ground_buffer = make_buffer(GL_ARRAY_BUFFER, sizeof(vertices), vertices.data());
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 6 * sizeof(float), nullptr);
  glEnableVertexAttribArray(1);
  glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, 6 * sizeof(float),
                        reinterpret_cast<const void*>(3 * sizeof(float)));
  glBindVertexArray(0);
}

}  // namespace

// ---------------------------------------------------------------------------------------------

Renderer::Renderer(const RendererOptions& options) : impl_(std::make_shared<Impl>()) {
  if (options.shadow_map_size < 64 || options.shadow_map_size > 8192)
    throw std::invalid_argument(
        fmt::format("shadow map size {} is outside [64, 8192]", options.shadow_map_size));
  impl_->options = options;
  gl::load_gl();  // OSMesa is opened by the first renderer, not at start-up (src/render/gl.hpp)
  impl_->create_context();
  impl_->mesh_program =
      std::make_unique<ShaderProgram>(std::vector<std::pair<GLenum, std::string_view>>{
          {GL_VERTEX_SHADER, "mesh.vert"}, {GL_FRAGMENT_SHADER, "mesh.frag"}});
  impl_->ground_program =
      std::make_unique<ShaderProgram>(std::vector<std::pair<GLenum, std::string_view>>{
          {GL_VERTEX_SHADER, "mesh.vert"}, {GL_FRAGMENT_SHADER, "ground.frag"}});
  impl_->shadow_program =
      std::make_unique<ShaderProgram>(std::vector<std::pair<GLenum, std::string_view>>{
          {GL_VERTEX_SHADER, "shadow.vert"}, {GL_FRAGMENT_SHADER, "shadow.frag"}});
  impl_->line_program = std::make_unique<ShaderProgram>(
      std::vector<std::pair<GLenum, std::string_view>>{{GL_VERTEX_SHADER, "line.vert"},
                                                       {GL_GEOMETRY_SHADER, "line.geom"},
                                                       {GL_FRAGMENT_SHADER, "line.frag"}});
  impl_->create_shadow_map();
}

Renderer::~Renderer() = default;
Renderer::Renderer(Renderer&&) noexcept = default;
Renderer& Renderer::operator=(Renderer&&) noexcept = default;

void load_renderer_library() {
  gl::load_gl();
}

const std::string& Renderer::gl_version() const {
  return impl_->version;
}
const std::string& Renderer::gl_renderer() const {
  return impl_->renderer_name;
}
const RendererOptions& Renderer::options() const {
  return impl_->options;
}

PreparedScene Renderer::prepare(const Scene& scene) {
  validate_scene(scene);
  impl_->make_current();
  auto data = std::make_unique<PreparedScene::Data>();
  data->owner = impl_;
  data->bounds = scene_bounds(scene);
  data->ground = scene.ground;
  data->shadows = scene.shadows;
  data->background = scene.background;
  data->ground_colour = scene.ground_colour;
  for (const SceneMesh& m : scene.meshes) {
    GpuMesh& gpu = data->meshes.emplace_back();
    Eigen::MatrixX3f colours = m.face_colours;
    if (colours.rows() == 0) colours = m.colour.transpose().replicate(m.mesh.face_count(), 1);
    upload_surface(gpu, m.mesh, colours);
    gpu.two_sided = m.role == MeshRole::kCloth;
    gpu.back_colour = m.back_colour;
    gpu.specular = m.role == MeshRole::kBody ? 0.18f : 0.05f;
    gpu.shininess = m.role == MeshRole::kBody ? 40.0f : 12.0f;
    if (m.wireframe && m.wireframe->edges.rows() > 0) upload_wireframe(gpu, m.mesh, *m.wireframe);
  }
  if (scene.ground) {
    const meshing::BoundingBox& b = data->bounds;
    data->ground_centre = {b.centre().x(), b.min.y(), b.centre().z()};
    data->ground_radius = kGroundRadiusFactor * std::max(b.extent().maxCoeff(), 1e-3);
    // A millimetre below the lowest point so soles do not fight with the floor for depth.
    upload_ground(*data, b.min.y() - 1e-3 * std::max(1.0, b.extent().maxCoeff()));
  }
  check_gl("uploading the scene");
  return PreparedScene(std::move(data));
}

Image Renderer::render(const Scene& scene, const Camera& camera, ImageSize size) {
  return render(prepare(scene), camera, size);
}

Image Renderer::render(const PreparedScene& prepared, const Camera& camera, ImageSize size) {
  validate_camera(camera);
  if (size.width < 1 || size.height < 1 || size.width > kMaxImageSide ||
      size.height > kMaxImageSide)
    throw ImageSizeError(fmt::format("cannot render a {}x{} image", size.width, size.height));
  const PreparedScene::Data& scene = *prepared.data_;
  if (scene.owner != impl_)
    throw std::invalid_argument("the scene was prepared by another renderer");
  Impl& gl = *impl_;
  gl.make_current();
  const int factor = gl.options.antialiasing == Antialiasing::kSupersample2 ? 2 : 1;
  const int width = size.width * factor, height = size.height * factor;
  gl.ensure_targets(width, height);

  // Camera: near and far planes bracket everything that can be seen.
  const std::vector<Eigen::Vector3d> points = scene.extent_points();
  const Eigen::Vector3d forward = (camera.target - camera.eye).normalized();
  double nearest = std::numeric_limits<double>::infinity(), farthest = 0;
  for (const Eigen::Vector3d& p : points) {
    const double depth = (p - camera.eye).dot(forward);
    nearest = std::min(nearest, depth);
    farthest = std::max(farthest, depth);
  }
  farthest = std::max(farthest * 1.05, 1e-3);
  nearest = std::max(nearest * 0.95, farthest * 1e-4);
  const Eigen::Matrix4f view_proj =
      (perspective_matrix(camera.fov_y_deg, size.aspect(), nearest, farthest) * view_matrix(camera))
          .cast<float>();

  // Key light: an orthographic depth map fitted around the casters and the floor.
  const Eigen::Vector3d key_dir = light_direction(camera, kKeyAzimuthDeg, kKeyElevationDeg);
  const Eigen::Vector3d fill_dir = light_direction(camera, kFillAzimuthDeg, kFillElevationDeg);
  const bool shadows = scene.shadows && !scene.meshes.empty();
  Eigen::Matrix4f light_view_proj = Eigen::Matrix4f::Identity();
  float shadow_texel_m = 0;
  if (shadows) {
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
    for (const Eigen::Vector3d& p : points) centre += p / static_cast<double>(points.size());
    double radius = 1e-3;
    for (const Eigen::Vector3d& p : points) radius = std::max(radius, (p - centre).norm());
    Camera light;
    light.eye = centre + 2 * radius * key_dir;
    light.target = centre;
    light.up = std::abs(key_dir.y()) > 0.99 ? Eigen::Vector3d::UnitZ() : Eigen::Vector3d::UnitY();
    const Eigen::Matrix4d light_view = view_matrix(light);
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
    Eigen::Vector3d hi = -lo;
    for (const Eigen::Vector3d& p : points) {
      const Eigen::Vector3d q = (light_view * p.homogeneous()).head<3>();
      lo = lo.cwiseMin(q);
      hi = hi.cwiseMax(q);
    }
    const double pad = 0.01 * radius;
    light_view_proj = (orthographic_matrix(lo.x() - pad, hi.x() + pad, lo.y() - pad, hi.y() + pad,
                                           -hi.z() - pad, -lo.z() + pad) *
                       light_view)
                          .cast<float>();
    shadow_texel_m = static_cast<float>(std::max(hi.x() - lo.x(), hi.y() - lo.y()) + 2 * pad) /
                     static_cast<float>(gl.options.shadow_map_size);

    glBindFramebuffer(GL_FRAMEBUFFER, gl.shadow_fbo);
    glViewport(0, 0, gl.options.shadow_map_size, gl.options.shadow_map_size);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glDepthMask(GL_TRUE);
    glClear(GL_DEPTH_BUFFER_BIT);
    glEnable(GL_POLYGON_OFFSET_FILL);
    glPolygonOffset(2.0f, 4.0f);  // slope-scaled bias against shadow acne
    gl.shadow_program->use();
    gl.shadow_program->set("u_light_view_proj", light_view_proj);
    for (const GpuMesh& m : scene.meshes) {
      glBindVertexArray(m.vao);
      glDrawElements(GL_TRIANGLES, m.index_count, GL_UNSIGNED_INT, nullptr);
    }
    glDisable(GL_POLYGON_OFFSET_FILL);
  }

  glBindFramebuffer(GL_FRAMEBUFFER, gl.draw_fbo);
  glViewport(0, 0, width, height);
  glClearColor(scene.background.x(), scene.background.y(), scene.background.z(), 1.0f);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LEQUAL);
  glDepthMask(GL_TRUE);
  glDisable(GL_CULL_FACE);
  if (gl.samples > 1) glEnable(GL_MULTISAMPLE);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_2D, gl.shadow_texture);

  const auto set_lighting = [&](ShaderProgram& program) {
    program.use();
    program.set("u_view_proj", view_proj);
    program.set("u_key_dir", Eigen::Vector3f(key_dir.cast<float>()));
    program.set("u_fill_dir", Eigen::Vector3f(fill_dir.cast<float>()));
    program.set("u_key_colour", kKeyColour);
    program.set("u_fill_colour", kFillColour);
    program.set("u_sky_ambient", kSkyAmbient);
    program.set("u_ground_ambient", kGroundAmbient);
    program.set("u_shadows", shadows ? 1 : 0);
    program.set("u_shadow_map", 0);
    program.set("u_light_view_proj", light_view_proj);
    program.set("u_shadow_texel", 1.0f / static_cast<float>(gl.options.shadow_map_size));
    program.set("u_pcf_spread", kPcfSpreadTexels);
    program.set("u_normal_offset", 1.5f * shadow_texel_m);
  };

  // Depth pre-pass: lay down the meshes' depth with a trivial shader, so the lighting shader
  // below runs once per visible pixel instead of once per layer (bodies are drawn two-sided
  // and cloth hides the body: without it llvmpipe shades hidden layers too). Both passes
  // use the same offset, and both vertex shaders declare gl_Position invariant, so the depths
  // match exactly and the second pass uses GL_LEQUAL. Surfaces are pushed back a little so
  // wireframe lines lying on them win the depth test.
  glEnable(GL_POLYGON_OFFSET_FILL);
  glPolygonOffset(1.0f, 1.0f);
  gl.shadow_program->use();
  gl.shadow_program->set("u_light_view_proj", view_proj);
  glColorMask(GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
  for (const GpuMesh& m : scene.meshes) {
    glBindVertexArray(m.vao);
    glDrawElements(GL_TRIANGLES, m.index_count, GL_UNSIGNED_INT, nullptr);
  }
  glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
  glDepthMask(GL_FALSE);
  set_lighting(*gl.mesh_program);
  gl.mesh_program->set("u_eye", Eigen::Vector3f(camera.eye.cast<float>()));
  for (const GpuMesh& m : scene.meshes) {
    gl.mesh_program->set("u_two_sided", m.two_sided ? 1 : 0);
    gl.mesh_program->set("u_back_colour", m.back_colour);
    gl.mesh_program->set("u_specular", m.specular);
    gl.mesh_program->set("u_shininess", m.shininess);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, m.colour_buffer);
    glBindVertexArray(m.vao);
    glDrawElements(GL_TRIANGLES, m.index_count, GL_UNSIGNED_INT, nullptr);
  }
  glDepthMask(GL_TRUE);
  glDisable(GL_POLYGON_OFFSET_FILL);

  // The floor last, so the depth test drops the parts the meshes cover before shading.
  if (scene.ground) {
    set_lighting(*gl.ground_program);
    gl.ground_program->set("u_ground_colour", scene.ground_colour);
    gl.ground_program->set("u_background", scene.background);
    gl.ground_program->set("u_ground_centre", Eigen::Vector3f(scene.ground_centre.cast<float>()));
    gl.ground_program->set("u_ground_radius", static_cast<float>(scene.ground_radius));
    glBindVertexArray(scene.ground_vao);
    glDrawArrays(GL_TRIANGLES, 0, 6);
  }

  gl.line_program->use();
  gl.line_program->set("u_view_proj", view_proj);
  gl.line_program->set("u_viewport",
                       Eigen::Vector2f(static_cast<float>(width), static_cast<float>(height)));
  for (const GpuMesh& m : scene.meshes) {
    if (m.line_vertex_count == 0) continue;
    gl.line_program->set("u_width_px", m.line_width * static_cast<float>(factor));
    glBindVertexArray(m.line_vao);
    glDrawArrays(GL_LINES, 0, m.line_vertex_count);
  }
  glBindVertexArray(0);

  // Resolve the samples, read back (OpenGL rows run bottom to top) and flip.
  GLuint read_fbo = gl.draw_fbo;
  if (gl.samples > 1) {
    glBindFramebuffer(GL_READ_FRAMEBUFFER, gl.draw_fbo);
    glBindFramebuffer(GL_DRAW_FRAMEBUFFER, gl.resolve_fbo);
    glBlitFramebuffer(0, 0, width, height, 0, 0, width, height, GL_COLOR_BUFFER_BIT, GL_NEAREST);
    read_fbo = gl.resolve_fbo;
  }
  glBindFramebuffer(GL_READ_FRAMEBUFFER, read_fbo);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  gl.readback.resize(static_cast<size_t>(width) * height * 4);
  glReadPixels(0, 0, width, height, GL_RGBA, GL_UNSIGNED_BYTE, gl.readback.data());
  check_gl("drawing the frame");

  Image image(size.width, size.height);
  const auto source = [&](int x, int y) {  // y counted from the top
    return &gl.readback[4 * (static_cast<size_t>(height - 1 - y) * width + x)];
  };
  if (factor == 1) {
    for (int y = 0; y < height; ++y)
      std::copy_n(source(0, y), 4 * static_cast<size_t>(width), image.pixel(0, y));
  } else {
    for (int y = 0; y < size.height; ++y)
      for (int x = 0; x < size.width; ++x)
        for (int c = 0; c < 4; ++c) {
          const int sum = source(2 * x, 2 * y)[c] + source(2 * x + 1, 2 * y)[c] +
                          source(2 * x, 2 * y + 1)[c] + source(2 * x + 1, 2 * y + 1)[c];
          image.pixel(x, y)[c] = static_cast<std::uint8_t>((sum + 2) / 4);
        }
  }
  return image;
}

}  // namespace sd::render
