#pragma once
// The up axis given for a body is wrong: the figure would lie on its side (load_body throws it;
// a sketch reports it at /body/up rather than /body/mesh).

#include "garment/body.hpp"

namespace sd::garment {

class BodyUpError : public BodyError {
 public:
  using BodyError::BodyError;
};

}  // namespace sd::garment
