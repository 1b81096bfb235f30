#pragma once
// Synthetic meshes and an independent CPU reference for the rendering tests: projection of
// points written from the Camera's definition (not from the renderer's matrices) and a
// pixel-centre rasteriser giving the exact silhouette the GPU should cover.

#include <Eigen/Geometry>
#include <cmath>
#include <numbers>
#include <vector>

#include "meshing/tri_mesh.hpp"
#include "src/render/camera.hpp"
#include "src/render/image.hpp"

namespace sd::test {

// Axis-aligned box [lo, hi], 12 triangles counter-clockwise seen from outside.
inline meshing::TriMesh box_mesh(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  meshing::TriMesh m;
  m.vertices.resize(8, 3);
  for (int i = 0; i < 8; ++i)
    m.vertices.row(i) << ((i & 1) ? hi.x() : lo.x()), ((i & 2) ? hi.y() : lo.y()),
        ((i & 4) ? hi.z() : lo.z());
  m.faces.resize(12, 3);
  m.faces << 0, 2, 1, 1, 2, 3,  // -z
      4, 5, 6, 5, 7, 6,         // +z
      0, 1, 4, 1, 5, 4,         // -y
      2, 6, 3, 3, 6, 7,         // +y
      0, 4, 2, 2, 4, 6,         // -x
      1, 3, 5, 3, 7, 5;         // +x
  return m;
}

// Concatenation of meshes (separate components).
inline meshing::TriMesh merge(const std::vector<meshing::TriMesh>& parts) {
  Eigen::Index nv = 0, nf = 0;
  for (const auto& p : parts) nv += p.vertex_count(), nf += p.face_count();
  meshing::TriMesh m;
  m.vertices.resize(nv, 3);
  m.faces.resize(nf, 3);
  nv = nf = 0;
  for (const auto& p : parts) {
    m.vertices.middleRows(nv, p.vertex_count()) = p.vertices;
    m.faces.middleRows(nf, p.face_count()) = p.faces.array() + static_cast<int>(nv);
    nv += p.vertex_count();
    nf += p.face_count();
  }
  return m;
}

// Pixel coordinates (x right, y down, pixel centres at +0.5) of world point p, from the
// pinhole model: direction (x, y) in the camera's right/up frame over depth, scaled by
// tan(fov/2). Returns false if p is behind the camera.
inline bool project(const render::Camera& c, const Eigen::Vector3d& p, render::ImageSize size,
                    Eigen::Vector2d& pixel) {
  const Eigen::Vector3d forward = (c.target - c.eye).normalized();
  const Eigen::Vector3d right = forward.cross(c.up).normalized();
  const Eigen::Vector3d up = right.cross(forward);
  const Eigen::Vector3d d = p - c.eye;
  const double depth = d.dot(forward);
  if (depth <= 0) return false;
  const double t = std::tan(c.fov_y_deg * std::numbers::pi / 360.0);
  const double nx = d.dot(right) / depth / (t * size.aspect());
  const double ny = d.dot(up) / depth / t;
  pixel = {(nx + 1) / 2 * size.width, (1 - ny) / 2 * size.height};
  return true;
}

// 1 where a pixel centre lies inside some projected triangle, row-major, y down.
inline std::vector<unsigned char> cpu_silhouette(const meshing::TriMesh& mesh,
                                                 const render::Camera& c, render::ImageSize size) {
  std::vector<unsigned char> mask(static_cast<size_t>(size.width) * size.height, 0);
  std::vector<Eigen::Vector2d> px(static_cast<size_t>(mesh.vertex_count()),
                                  Eigen::Vector2d::Zero());
  for (Eigen::Index v = 0; v < mesh.vertex_count(); ++v)
    project(c, mesh.vertices.row(v).transpose(), size, px[static_cast<size_t>(v)]);
  for (Eigen::Index f = 0; f < mesh.face_count(); ++f) {
    const Eigen::Vector2d a = px[mesh.faces(f, 0)], b = px[mesh.faces(f, 1)],
                          d = px[mesh.faces(f, 2)];
    const double area = (b - a).x() * (d - a).y() - (b - a).y() * (d - a).x();
    if (std::abs(area) < 1e-12) continue;
    const int x0 = std::max(0, static_cast<int>(std::floor(std::min({a.x(), b.x(), d.x()}))));
    const int x1 =
        std::min(size.width - 1, static_cast<int>(std::ceil(std::max({a.x(), b.x(), d.x()}))));
    const int y0 = std::max(0, static_cast<int>(std::floor(std::min({a.y(), b.y(), d.y()}))));
    const int y1 =
        std::min(size.height - 1, static_cast<int>(std::ceil(std::max({a.y(), b.y(), d.y()}))));
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) {
        const Eigen::Vector2d p(x + 0.5, y + 0.5);
        const auto edge = [&](const Eigen::Vector2d& u, const Eigen::Vector2d& v) {
          return ((v - u).x() * (p - u).y() - (v - u).y() * (p - u).x()) / area;
        };
        if (edge(a, b) >= 0 && edge(b, d) >= 0 && edge(d, a) >= 0)
          mask[static_cast<size_t>(y) * size.width + x] = 1;
      }
  }
  return mask;
}

// Pixels whose 3x3 neighbourhood in `mask` holds both values: where anti-aliasing and
// rasterisation rules may legitimately disagree with a pixel-centre test.
inline std::vector<unsigned char> mask_boundary(const std::vector<unsigned char>& mask, int width,
                                                int height) {
  std::vector<unsigned char> out(mask.size(), 0);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      bool any0 = false, any1 = false;
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const int xx = std::clamp(x + dx, 0, width - 1), yy = std::clamp(y + dy, 0, height - 1);
          (mask[static_cast<size_t>(yy) * width + xx] ? any1 : any0) = true;
        }
      out[static_cast<size_t>(y) * width + x] = any0 && any1;
    }
  return out;
}

inline int channel_difference(const render::Image& a, const render::Image& b, int x, int y) {
  int d = 0;
  for (int c = 0; c < 3; ++c) d = std::max(d, std::abs(a.pixel(x, y)[c] - b.pixel(x, y)[c]));
  return d;
}

inline double luminance(const render::Image& image, int x, int y) {
  const std::uint8_t* p = image.pixel(x, y);
  return 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
}

}  // namespace sd::test
