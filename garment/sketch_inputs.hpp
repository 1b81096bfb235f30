#pragma once
// The files a sketch file points at (the body, an imported garment), loaded with errors that
// name the sketch file and the JSON path of the reference.

#include "garment/body.hpp"
#include "garment/garment_request.hpp"
#include "meshing/tri_mesh.hpp"

namespace sd::garment {

// The sketch's body (builtin or a path relative to the sketch file) with its height, scale and
// up axis. A body that cannot be loaded throws SketchError at /body/mesh.
Body load_sketch_body(const GarmentRequest& sketch);
// The same for another body of the sketch (`spec` at JSON path `path`, e.g. "/body/drawn_on"),
// its mesh path relative to the sketch file.
Body load_sketch_body(const GarmentRequest& sketch, const BodySpec& spec, const std::string& path);

// The triangle garment of "garment_mesh" (Wavefront OBJ; polygons are fan-triangulated), in
// metres as written. Throws SketchError at /garment_mesh when it is missing, unreadable or has
// no faces or non-finite or out-of-range values. `file_faces`, when given, gets the number of faces
// the file writes (its "f" lines: a quad is one face there and two triangles here).
meshing::TriMesh load_garment_mesh(const GarmentRequest& sketch, long* file_faces = nullptr);

}  // namespace sd::garment
