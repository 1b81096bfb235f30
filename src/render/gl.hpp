#pragma once
// The one place that includes OpenGL for sd_render (internal header). libOSMesa exports every
// gl* entry point, so prototypes are declared directly and no loader is needed; the define must
// come before the first GL include.

#ifndef GL_GLEXT_PROTOTYPES
#define GL_GLEXT_PROTOTYPES 1
#endif
#include <GL/gl.h>  // before glext.h, which needs its types (sorted first by name too)
#include <GL/glext.h>
#include <GL/osmesa.h>
