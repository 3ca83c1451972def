#pragma once

// The OpenGL entry points Canopy uses, resolved at run time through the current backend's own
// GetProcAddress (OSMesa, EGL or GLFW) into one table. No GL library is linked for direct calls:
// libOSMesa and libGL both export gl* symbols, and a binary that binds the wrong ones renders
// nothing (see DESIGN.md). glcorearb.h without GL_GLCOREARB_PROTOTYPES declares only types.
#include <GL/glcorearb.h>

#include <functional>
#include <string>

namespace canopy::gl {

// X(type of the pointer, name without the "gl" prefix)
#define CANOPY_GL_FUNCTIONS(X)                                                 \
  X(PFNGLGETSTRINGPROC, GetString)                                             \
  X(PFNGLGETSTRINGIPROC, GetStringi)                                           \
  X(PFNGLGETINTEGERVPROC, GetIntegerv)                                         \
  X(PFNGLGETERRORPROC, GetError)                                               \
  X(PFNGLVIEWPORTPROC, Viewport)                                               \
  X(PFNGLSCISSORPROC, Scissor)                                                 \
  X(PFNGLCLEARPROC, Clear)                                                     \
  X(PFNGLCLEARCOLORPROC, ClearColor)                                           \
  X(PFNGLCLEARDEPTHPROC, ClearDepth)                                           \
  X(PFNGLCLEARBUFFERFVPROC, ClearBufferfv)                                     \
  X(PFNGLENABLEPROC, Enable)                                                   \
  X(PFNGLDISABLEPROC, Disable)                                                 \
  X(PFNGLDEPTHFUNCPROC, DepthFunc)                                             \
  X(PFNGLDEPTHMASKPROC, DepthMask)                                             \
  X(PFNGLCOLORMASKPROC, ColorMask)                                             \
  X(PFNGLBLENDFUNCPROC, BlendFunc)                                             \
  X(PFNGLBLENDFUNCSEPARATEPROC, BlendFuncSeparate)                             \
  X(PFNGLCULLFACEPROC, CullFace)                                               \
  X(PFNGLFRONTFACEPROC, FrontFace)                                             \
  X(PFNGLPOLYGONMODEPROC, PolygonMode)                                         \
  X(PFNGLPOLYGONOFFSETPROC, PolygonOffset)                                     \
  X(PFNGLLINEWIDTHPROC, LineWidth)                                             \
  X(PFNGLFINISHPROC, Finish)                                                   \
  X(PFNGLFLUSHPROC, Flush)                                                     \
  X(PFNGLREADPIXELSPROC, ReadPixels)                                           \
  X(PFNGLREADBUFFERPROC, ReadBuffer)                                           \
  X(PFNGLDRAWBUFFERSPROC, DrawBuffers)                                         \
  X(PFNGLPIXELSTOREIPROC, PixelStorei)                                         \
  X(PFNGLGENBUFFERSPROC, GenBuffers)                                           \
  X(PFNGLDELETEBUFFERSPROC, DeleteBuffers)                                     \
  X(PFNGLBINDBUFFERPROC, BindBuffer)                                           \
  X(PFNGLBINDBUFFERBASEPROC, BindBufferBase)                                   \
  X(PFNGLBUFFERDATAPROC, BufferData)                                           \
  X(PFNGLBUFFERSUBDATAPROC, BufferSubData)                                     \
  X(PFNGLGENVERTEXARRAYSPROC, GenVertexArrays)                                 \
  X(PFNGLDELETEVERTEXARRAYSPROC, DeleteVertexArrays)                           \
  X(PFNGLBINDVERTEXARRAYPROC, BindVertexArray)                                 \
  X(PFNGLENABLEVERTEXATTRIBARRAYPROC, EnableVertexAttribArray)                 \
  X(PFNGLVERTEXATTRIBPOINTERPROC, VertexAttribPointer)                         \
  X(PFNGLVERTEXATTRIBIPOINTERPROC, VertexAttribIPointer)                       \
  X(PFNGLVERTEXATTRIBDIVISORPROC, VertexAttribDivisor)                         \
  X(PFNGLGENTEXTURESPROC, GenTextures)                                         \
  X(PFNGLDELETETEXTURESPROC, DeleteTextures)                                   \
  X(PFNGLBINDTEXTUREPROC, BindTexture)                                         \
  X(PFNGLACTIVETEXTUREPROC, ActiveTexture)                                     \
  X(PFNGLTEXIMAGE2DPROC, TexImage2D)                                           \
  X(PFNGLTEXIMAGE3DPROC, TexImage3D)                                           \
  X(PFNGLTEXSUBIMAGE2DPROC, TexSubImage2D)                                     \
  X(PFNGLTEXSUBIMAGE3DPROC, TexSubImage3D)                                     \
  X(PFNGLCOMPRESSEDTEXIMAGE2DPROC, CompressedTexImage2D)                       \
  X(PFNGLCOMPRESSEDTEXSUBIMAGE2DPROC, CompressedTexSubImage2D)                 \
  X(PFNGLCOMPRESSEDTEXSUBIMAGE3DPROC, CompressedTexSubImage3D)                 \
  X(PFNGLTEXPARAMETERIPROC, TexParameteri)                                     \
  X(PFNGLTEXPARAMETERFPROC, TexParameterf)                                     \
  X(PFNGLGENERATEMIPMAPPROC, GenerateMipmap)                                   \
  X(PFNGLGETTEXIMAGEPROC, GetTexImage)                                         \
  X(PFNGLGENFRAMEBUFFERSPROC, GenFramebuffers)                                 \
  X(PFNGLDELETEFRAMEBUFFERSPROC, DeleteFramebuffers)                           \
  X(PFNGLBINDFRAMEBUFFERPROC, BindFramebuffer)                                 \
  X(PFNGLFRAMEBUFFERTEXTURE2DPROC, FramebufferTexture2D)                       \
  X(PFNGLFRAMEBUFFERRENDERBUFFERPROC, FramebufferRenderbuffer)                 \
  X(PFNGLCHECKFRAMEBUFFERSTATUSPROC, CheckFramebufferStatus)                   \
  X(PFNGLGENRENDERBUFFERSPROC, GenRenderbuffers)                               \
  X(PFNGLDELETERENDERBUFFERSPROC, DeleteRenderbuffers)                         \
  X(PFNGLBINDRENDERBUFFERPROC, BindRenderbuffer)                               \
  X(PFNGLRENDERBUFFERSTORAGEPROC, RenderbufferStorage)                         \
  X(PFNGLBLITFRAMEBUFFERPROC, BlitFramebuffer)                                 \
  X(PFNGLCREATESHADERPROC, CreateShader)                                       \
  X(PFNGLSHADERSOURCEPROC, ShaderSource)                                       \
  X(PFNGLCOMPILESHADERPROC, CompileShader)                                     \
  X(PFNGLGETSHADERIVPROC, GetShaderiv)                                         \
  X(PFNGLGETSHADERINFOLOGPROC, GetShaderInfoLog)                               \
  X(PFNGLDELETESHADERPROC, DeleteShader)                                       \
  X(PFNGLCREATEPROGRAMPROC, CreateProgram)                                     \
  X(PFNGLATTACHSHADERPROC, AttachShader)                                       \
  X(PFNGLLINKPROGRAMPROC, LinkProgram)                                         \
  X(PFNGLGETPROGRAMIVPROC, GetProgramiv)                                       \
  X(PFNGLGETPROGRAMINFOLOGPROC, GetProgramInfoLog)                             \
  X(PFNGLDELETEPROGRAMPROC, DeleteProgram)                                     \
  X(PFNGLUSEPROGRAMPROC, UseProgram)                                           \
  X(PFNGLGETUNIFORMLOCATIONPROC, GetUniformLocation)                           \
  X(PFNGLUNIFORM1IPROC, Uniform1i)                                             \
  X(PFNGLUNIFORM2IPROC, Uniform2i)                                             \
  X(PFNGLUNIFORM1FPROC, Uniform1f)                                             \
  X(PFNGLUNIFORM2FPROC, Uniform2f)                                             \
  X(PFNGLUNIFORM3FPROC, Uniform3f)                                             \
  X(PFNGLUNIFORM4FPROC, Uniform4f)                                             \
  X(PFNGLUNIFORM3FVPROC, Uniform3fv)                                           \
  X(PFNGLUNIFORM4FVPROC, Uniform4fv)                                           \
  X(PFNGLUNIFORMMATRIX3FVPROC, UniformMatrix3fv)                               \
  X(PFNGLUNIFORMMATRIX4FVPROC, UniformMatrix4fv)                               \
  X(PFNGLDRAWARRAYSPROC, DrawArrays)                                           \
  X(PFNGLDRAWELEMENTSPROC, DrawElements)                                       \
  X(PFNGLDRAWARRAYSINSTANCEDPROC, DrawArraysInstanced)                         \
  X(PFNGLDRAWELEMENTSINSTANCEDPROC, DrawElementsInstanced)                     \
  X(PFNGLDRAWELEMENTSBASEVERTEXPROC, DrawElementsBaseVertex)                   \
  X(PFNGLBINDSAMPLERPROC, BindSampler)                                         \
  X(PFNGLBLENDEQUATIONPROC, BlendEquation)                                     \
  X(PFNGLBLENDEQUATIONSEPARATEPROC, BlendEquationSeparate)                     \
  X(PFNGLCLIPCONTROLPROC, ClipControl)                                         \
  X(PFNGLDETACHSHADERPROC, DetachShader)                                       \
  X(PFNGLGETATTRIBLOCATIONPROC, GetAttribLocation)                             \
  X(PFNGLISENABLEDPROC, IsEnabled)                                             \
  X(PFNGLDRAWELEMENTSINSTANCEDBASEVERTEXPROC, DrawElementsInstancedBaseVertex) \
  X(PFNGLGENQUERIESPROC, GenQueries)                                           \
  X(PFNGLDELETEQUERIESPROC, DeleteQueries)                                     \
  X(PFNGLBEGINQUERYPROC, BeginQuery)                                           \
  X(PFNGLENDQUERYPROC, EndQuery)                                               \
  X(PFNGLGETQUERYOBJECTUI64VPROC, GetQueryObjectui64v)                         \
  X(PFNGLSAMPLECOVERAGEPROC, SampleCoverage)

struct Api {
#define CANOPY_GL_DECLARE(type, name) type name = nullptr;
  CANOPY_GL_FUNCTIONS(CANOPY_GL_DECLARE)
#undef CANOPY_GL_DECLARE
};

// Resolves a symbol name ("glClear") to an address, or nullptr.
using ProcResolver = std::function<void*(const char*)>;

// Fills every entry; throws std::runtime_error naming the first entry point it cannot resolve.
Api loadApi(const ProcResolver& resolve);

// The table of the context made current last; asserts that one is current.
const Api& api();
void setCurrentApi(const Api* table);

// Throws std::runtime_error naming `where` and the GL error code when glGetError reports one.
void checkError(const char* where);

}  // namespace canopy::gl
