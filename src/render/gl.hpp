#pragma once
// The one place that includes OpenGL for sd_render (internal header). libOSMesa exports every
// gl* entry point, but it is not linked: loading it (and the LLVM, z3 and ICU it needs) took
// about half the start-up of a run that renders nothing. The first Renderer opens it with
// dlopen (load_gl) and each function below is called through a pointer of its own type, like a
// GL loader does: the name is a macro for the pointer (member name_ of gl::functions). A gl* call
// missing from the list fails to link (nothing defines the function), so the list cannot fall
// behind the code.

#ifndef GL_GLEXT_PROTOTYPES
#define GL_GLEXT_PROTOTYPES 1  // the prototypes give each pointer its type (decltype)
#endif
#include <GL/gl.h>  // before glext.h, which needs its types (sorted first by name too)
#include <GL/glext.h>
#include <GL/osmesa.h>

// Every OSMesa and OpenGL function sd_render calls.
#define SD_GL_FUNCTIONS(X)            \
  X(OSMesaCreateContextAttribs)       \
  X(OSMesaDestroyContext)             \
  X(OSMesaGetCurrentContext)          \
  X(OSMesaMakeCurrent)                \
  X(glActiveTexture)                  \
  X(glAttachShader)                   \
  X(glBindBuffer)                     \
  X(glBindBufferBase)                 \
  X(glBindFramebuffer)                \
  X(glBindRenderbuffer)               \
  X(glBindTexture)                    \
  X(glBindVertexArray)                \
  X(glBlitFramebuffer)                \
  X(glBufferData)                     \
  X(glCheckFramebufferStatus)         \
  X(glClear)                          \
  X(glClearColor)                     \
  X(glColorMask)                      \
  X(glCompileShader)                  \
  X(glCreateProgram)                  \
  X(glCreateShader)                   \
  X(glDeleteBuffers)                  \
  X(glDeleteFramebuffers)             \
  X(glDeleteProgram)                  \
  X(glDeleteRenderbuffers)            \
  X(glDeleteShader)                   \
  X(glDeleteTextures)                 \
  X(glDeleteVertexArrays)             \
  X(glDepthFunc)                      \
  X(glDepthMask)                      \
  X(glDisable)                        \
  X(glDrawArrays)                     \
  X(glDrawBuffer)                     \
  X(glDrawElements)                   \
  X(glEnable)                         \
  X(glEnableVertexAttribArray)        \
  X(glFramebufferRenderbuffer)        \
  X(glFramebufferTexture2D)           \
  X(glGenBuffers)                     \
  X(glGenFramebuffers)                \
  X(glGenRenderbuffers)               \
  X(glGenTextures)                    \
  X(glGenVertexArrays)                \
  X(glGetError)                       \
  X(glGetIntegerv)                    \
  X(glGetProgramInfoLog)              \
  X(glGetProgramiv)                   \
  X(glGetShaderInfoLog)               \
  X(glGetShaderiv)                    \
  X(glGetString)                      \
  X(glGetUniformLocation)             \
  X(glLinkProgram)                    \
  X(glPixelStorei)                    \
  X(glPolygonOffset)                  \
  X(glReadBuffer)                     \
  X(glReadPixels)                     \
  X(glRenderbufferStorage)            \
  X(glRenderbufferStorageMultisample) \
  X(glShaderSource)                   \
  X(glTexParameterfv)                 \
  X(glTexParameteri)                  \
  X(glTexStorage2D)                   \
  X(glUniform1f)                      \
  X(glUniform1i)                      \
  X(glUniform2fv)                     \
  X(glUniform3fv)                     \
  X(glUniformMatrix4fv)               \
  X(glUseProgram)                     \
  X(glVertexAttribPointer)            \
  X(glViewport)

namespace sd::render::gl {

struct Functions {
#define SD_GL_POINTER(name) decltype(&::name) name##_ = nullptr;
  SD_GL_FUNCTIONS(SD_GL_POINTER)
#undef SD_GL_POINTER
};

// The loaded functions; all null until load_gl has succeeded.
extern Functions functions;

// Opens libOSMesa and looks up every function, once per process (later calls return at once;
// safe from several threads). Throws RenderError naming the library or the missing function.
void load_gl();

}  // namespace sd::render::gl

#define OSMesaCreateContextAttribs ::sd::render::gl::functions.OSMesaCreateContextAttribs_
#define OSMesaDestroyContext ::sd::render::gl::functions.OSMesaDestroyContext_
#define OSMesaGetCurrentContext ::sd::render::gl::functions.OSMesaGetCurrentContext_
#define OSMesaMakeCurrent ::sd::render::gl::functions.OSMesaMakeCurrent_
#define glActiveTexture ::sd::render::gl::functions.glActiveTexture_
#define glAttachShader ::sd::render::gl::functions.glAttachShader_
#define glBindBuffer ::sd::render::gl::functions.glBindBuffer_
#define glBindBufferBase ::sd::render::gl::functions.glBindBufferBase_
#define glBindFramebuffer ::sd::render::gl::functions.glBindFramebuffer_
#define glBindRenderbuffer ::sd::render::gl::functions.glBindRenderbuffer_
#define glBindTexture ::sd::render::gl::functions.glBindTexture_
#define glBindVertexArray ::sd::render::gl::functions.glBindVertexArray_
#define glBlitFramebuffer ::sd::render::gl::functions.glBlitFramebuffer_
#define glBufferData ::sd::render::gl::functions.glBufferData_
#define glCheckFramebufferStatus ::sd::render::gl::functions.glCheckFramebufferStatus_
#define glClear ::sd::render::gl::functions.glClear_
#define glClearColor ::sd::render::gl::functions.glClearColor_
#define glColorMask ::sd::render::gl::functions.glColorMask_
#define glCompileShader ::sd::render::gl::functions.glCompileShader_
#define glCreateProgram ::sd::render::gl::functions.glCreateProgram_
#define glCreateShader ::sd::render::gl::functions.glCreateShader_
#define glDeleteBuffers ::sd::render::gl::functions.glDeleteBuffers_
#define glDeleteFramebuffers ::sd::render::gl::functions.glDeleteFramebuffers_
#define glDeleteProgram ::sd::render::gl::functions.glDeleteProgram_
#define glDeleteRenderbuffers ::sd::render::gl::functions.glDeleteRenderbuffers_
#define glDeleteShader ::sd::render::gl::functions.glDeleteShader_
#define glDeleteTextures ::sd::render::gl::functions.glDeleteTextures_
#define glDeleteVertexArrays ::sd::render::gl::functions.glDeleteVertexArrays_
#define glDepthFunc ::sd::render::gl::functions.glDepthFunc_
#define glDepthMask ::sd::render::gl::functions.glDepthMask_
#define glDisable ::sd::render::gl::functions.glDisable_
#define glDrawArrays ::sd::render::gl::functions.glDrawArrays_
#define glDrawBuffer ::sd::render::gl::functions.glDrawBuffer_
#define glDrawElements ::sd::render::gl::functions.glDrawElements_
#define glEnable ::sd::render::gl::functions.glEnable_
#define glEnableVertexAttribArray ::sd::render::gl::functions.glEnableVertexAttribArray_
#define glFramebufferRenderbuffer ::sd::render::gl::functions.glFramebufferRenderbuffer_
#define glFramebufferTexture2D ::sd::render::gl::functions.glFramebufferTexture2D_
#define glGenBuffers ::sd::render::gl::functions.glGenBuffers_
#define glGenFramebuffers ::sd::render::gl::functions.glGenFramebuffers_
#define glGenRenderbuffers ::sd::render::gl::functions.glGenRenderbuffers_
#define glGenTextures ::sd::render::gl::functions.glGenTextures_
#define glGenVertexArrays ::sd::render::gl::functions.glGenVertexArrays_
#define glGetError ::sd::render::gl::functions.glGetError_
#define glGetIntegerv ::sd::render::gl::functions.glGetIntegerv_
#define glGetProgramInfoLog ::sd::render::gl::functions.glGetProgramInfoLog_
#define glGetProgramiv ::sd::render::gl::functions.glGetProgramiv_
#define glGetShaderInfoLog ::sd::render::gl::functions.glGetShaderInfoLog_
#define glGetShaderiv ::sd::render::gl::functions.glGetShaderiv_
#define glGetString ::sd::render::gl::functions.glGetString_
#define glGetUniformLocation ::sd::render::gl::functions.glGetUniformLocation_
#define glLinkProgram ::sd::render::gl::functions.glLinkProgram_
#define glPixelStorei ::sd::render::gl::functions.glPixelStorei_
#define glPolygonOffset ::sd::render::gl::functions.glPolygonOffset_
#define glReadBuffer ::sd::render::gl::functions.glReadBuffer_
#define glReadPixels ::sd::render::gl::functions.glReadPixels_
#define glRenderbufferStorage ::sd::render::gl::functions.glRenderbufferStorage_
#define glRenderbufferStorageMultisample \
  ::sd::render::gl::functions.glRenderbufferStorageMultisample_
#define glShaderSource ::sd::render::gl::functions.glShaderSource_
#define glTexParameterfv ::sd::render::gl::functions.glTexParameterfv_
#define glTexParameteri ::sd::render::gl::functions.glTexParameteri_
#define glTexStorage2D ::sd::render::gl::functions.glTexStorage2D_
#define glUniform1f ::sd::render::gl::functions.glUniform1f_
#define glUniform1i ::sd::render::gl::functions.glUniform1i_
#define glUniform2fv ::sd::render::gl::functions.glUniform2fv_
#define glUniform3fv ::sd::render::gl::functions.glUniform3fv_
#define glUniformMatrix4fv ::sd::render::gl::functions.glUniformMatrix4fv_
#define glUseProgram ::sd::render::gl::functions.glUseProgram_
#define glVertexAttribPointer ::sd::render::gl::functions.glVertexAttribPointer_
#define glViewport ::sd::render::gl::functions.glViewport_
