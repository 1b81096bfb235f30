#pragma once
// Inside the scene layer: the parsers of a sketch file's sections, each checking its own fields
// with the Reader (sketch_reader.hpp). parse_sketch (sketch_file.cpp) reads the top level and
// calls them.

#include <nlohmann/json.hpp>

#include "scene/sketch_file.hpp"
#include "scene/sketch_reader.hpp"

namespace sd::scene::detail {

// The garment request's sections (sketch_garment.cpp).
void parse_body(const Reader& r, const json& j, BodySpec& body);
// The same for a body at another JSON path ("/body/drawn_on"): no "motion" or "drawn_on" there.
void parse_body(const Reader& r, const json& j, BodySpec& body, const std::string& path);
// "curves", "panels" and "join": the file has curves and panels (not a sheet or garment_mesh).
void parse_garment(const Reader& r, const json& root, Sketch& sketch);

// The simulator's, the sheet's and the outputs' sections (sketch_settings.cpp).
void parse_simulate(const Reader& r, const json& j, SimulateSpec& sim);
SheetSpec parse_sheet(const Reader& r, const json& j);
void parse_output(const Reader& r, const json& j, OutputSpec& out);

}  // namespace sd::scene::detail
