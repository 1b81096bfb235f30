#pragma once
// What a designer changes when two panels pass through each other in a narrow crease of the
// body (under the arm, between the legs): there the body's two walls face each other closer than
// 2.5 times the curves' offset, the offset surfaces of both walls merge, and two panels drawn
// on it lie on the same one (trial 37's bolero on the built-in body: 'front' through
// 'sleeve_front' at the underarm with the file's offset of 1.5 cm, clean at 1.2 cm). The quality
// gate (quality_gate.hpp) then says how wide the crease is and offers the largest smaller offset
// that meshed the garment with fewer warnings (docs/sketch-format.md, "Quality gate").

#include <cstddef>
#include <functional>
#include <optional>
#include <vector>

#include "garment/body_surface.hpp"
#include "garment/garment_mesh.hpp"
#include "garment/garment_request.hpp"
#include "garment/quality_gate.hpp"

namespace sd::garment {

// m: the width of the body's crease at `where` (a point of the cloth): from the body's point
// nearest it, along that point's normal, to the first wall facing back (normals more than 120°
// apart); empty when no such wall is within `reach` metres.
std::optional<double> crease_width(const BodySurface& body, const Eigen::Vector3d& where,
                                   double reach);

// Every curve's offset no larger than `offset`, and the file's that (the sketch to try).
GarmentRequest with_offset_at_most(const GarmentRequest& sketch, double offset);

// Adds to each "self_intersection" warning between two panels whose crossing lies in a crease
// narrower than 2.5 times the sketch's largest curve offset the crease's width and, when
// `warnings_with` (how many warnings a sketch gives, SIZE_MAX when it does not mesh) gives
// fewer for a smaller offset (the largest of 2.5 mm, 5 mm below the file's, and 1 cm, that
// does), that offset.
void advise_crossings_in_creases(
    std::vector<QualityWarning>& warnings, const GarmentRequest& sketch, const BodySurface& body,
    const std::function<std::size_t(const GarmentRequest&)>& warnings_with);

}  // namespace sd::garment
