#pragma once
// The up axis given for a body is wrong: the figure would lie on its side; or the facing given
// runs along the up axis (load_body throws them; a sketch reports them at /body/up or
// /body/facing rather than /body/mesh).

#include "garment/body.hpp"

namespace sd::garment {

class BodyUpError : public BodyError {
 public:
  using BodyError::BodyError;
};

class BodyFacingError : public BodyError {
 public:
  using BodyError::BodyError;
};

}  // namespace sd::garment
