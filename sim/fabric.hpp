#pragma once
// Fabric material constants in SI units, their validation, and the presets shipped in
// data/fabrics/*.json (embedded in the library at build time).

#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace sd::sim {

// A fabric constant that is missing, negative, zero where it must not be, or not finite.
class InvalidFabricError : public std::invalid_argument {
 public:
  explicit InvalidFabricError(const std::string& message, std::string pointer = {})
      : std::invalid_argument(message), pointer_(std::move(pointer)) {}
  // JSON pointer of the offending value inside the fabric's JSON ("/bend"), empty if none.
  const std::string& pointer() const { return pointer_; }

 private:
  std::string pointer_;
};

// A preset name that is not shipped (the message lists the known names).
class UnknownFabricError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

// A measured tensile curve along warp or weft (KES-F tensile test, a strip test): the stress
// (force per unit width, N/m) at increasing strains, starting at (0, 0); both strictly increase.
// Between points the stress is linear in the strain; beyond the last point the last segment's
// slope continues. Empty: the fabric is linear in tension (its stretch constant).
struct TensileCurve {
  std::vector<double> strain;  // 1 (not %), strain[0] = 0
  std::vector<double> stress;  // N/m, stress[0] = 0

  bool empty() const { return strain.empty(); }
  // At a strain ε ≥ 0: the energy per unit area W(ε) = ∫₀^ε σ (J/m²), the stress σ(ε) (N/m) and
  // the tangent stiffness dσ/dε (N/m, the slope of the segment ε lies on).
  struct Point {
    double energy = 0.0;
    double stress = 0.0;
    double tangent = 0.0;
  };
  Point at(double strain) const;
};

// Constants of the Baraff-Witkin model as densities, so that one set behaves the same at any
// mesh resolution (see docs/simulator.md, "Resolution invariance"):
//   stretch/shear energy of a triangle = ½ · stiffness · rest area · condition²,
//   bend energy of an edge             = ½ · bend · |e|²/(A1+A2) · (θ − θ0)².
struct FabricParameters {
  std::string name = "custom";
  double area_density = 0.15;    // kg/m²
  double stretch_warp = 5.0e3;   // N/m, membrane stiffness along the warp (u)
  double stretch_weft = 5.0e3;   // N/m, along the weft (v)
  double shear = 50.0;           // N/m, in-plane shear stiffness (per unit shear strain)
  double bend = 1.0e-5;          // N·m, bending rigidity (moment per unit width per curvature)
  double damping = 2.0e-3;       // s, stiffness-proportional damping of stretch and shear
  double bend_damping = 2.0e-2;  // s, stiffness-proportional damping of bending
  double friction = 0.3;         // Coulomb coefficient against the body (contacts, later)
  double thickness = 5.0e-4;     // m, collision thickness
  // Optional measured curves in tension (docs/fabrics.md, "Tensile curves"): when given, the
  // tension along that direction follows the curve and stretch_warp/stretch_weft only answer
  // compression (and set the buckling strain).
  TensileCurve tensile_warp;
  TensileCurve tensile_weft;

  // Throws InvalidFabricError naming the first bad constant.
  void validate() const;
};

// Parses one fabric file (the format of data/fabrics/*.json: every constant is an object
// {"value": number, "unit": "...", "source": "..."} and the unit must be the SI unit above).
// `origin` names the file in error messages. Throws InvalidFabricError.
FabricParameters parse_fabric_json(std::string_view text, const std::string& origin);

// Reads and parses a fabric file from disk.
FabricParameters load_fabric_file(const std::string& path);

// A shipped preset by name ("cotton", "denim", "silk", "jersey", "wool", "polyester").
// Throws UnknownFabricError for other names.
FabricParameters fabric_preset(std::string_view name);

// Names of the shipped presets, sorted.
std::vector<std::string> fabric_preset_names();

}  // namespace sd::sim
