// SPDX-FileCopyrightText: Adaptive-FAM authors
// SPDX-License-Identifier: BSD-3-Clause
#include "vtkAFAMImageDraw.h"

#include "vtkOpenGLRenderWindow.h"
#include "vtkOpenGLState.h"
#include "vtkTextureObject.h"
#include "vtk_glew.h" // before CUDA's interop header, whose GL/gl.h it then stands for

#if defined(AFAM_HAVE_CUDA)
#include <cuda_gl_interop.h>
#include <cuda_runtime_api.h>
#endif

namespace
{
#if defined(AFAM_HAVE_CUDA)
std::string CudaProblem(const char* step, cudaError_t e)
{
  (void)cudaGetLastError(); // clear it: the CPU path must not trip over it
  return std::string(step) + " failed: " + cudaGetErrorString(e) + " (" + cudaGetErrorName(e) +
    "); the GPU's image goes through the host";
}
#endif
}

vtkAFAMImageDraw::vtkAFAMImageDraw() = default;

vtkAFAMImageDraw::~vtkAFAMImageDraw()
{
  // Without a context only the CUDA side can go; the window frees its GL objects with itself.
  this->UnmapDeviceImage();
#if defined(AFAM_HAVE_CUDA)
  if (this->Resource)
  {
    (void)cudaGraphicsUnregisterResource(static_cast<cudaGraphicsResource*>(this->Resource));
  }
#endif
  if (this->Texture)
  {
    this->Texture->Delete();
  }
}

void vtkAFAMImageDraw::Fail(const std::string& problem)
{
  this->InteropProblem = problem;
  this->FreePixelBuffer();
}

bool vtkAFAMImageDraw::EnsurePixelBuffer(size_t floats)
{
#if defined(AFAM_HAVE_CUDA)
  if (this->PixelBuffer && this->PixelBufferFloats >= floats)
  {
    return true;
  }
  this->FreePixelBuffer();
  glGenBuffers(1, &this->PixelBuffer);
  glBindBuffer(GL_PIXEL_UNPACK_BUFFER, this->PixelBuffer);
  glBufferData(GL_PIXEL_UNPACK_BUFFER, static_cast<GLsizeiptr>(floats * sizeof(float)), nullptr,
    GL_STREAM_DRAW);
  glBindBuffer(GL_PIXEL_UNPACK_BUFFER, 0);
  if (glGetError() != GL_NO_ERROR)
  {
    this->Fail("no OpenGL pixel buffer of " + std::to_string(floats * sizeof(float)) +
      " bytes; the GPU's image goes through the host");
    return false;
  }
  this->PixelBufferFloats = floats;
  cudaGraphicsResource* resource = nullptr;
  const cudaError_t e = cudaGraphicsGLRegisterBuffer(
    &resource, this->PixelBuffer, cudaGraphicsRegisterFlagsWriteDiscard);
  if (e != cudaSuccess)
  {
    // E.g. Mesa's OpenGL, or OpenGL on another GPU than CUDA's.
    this->Fail(CudaProblem("registering the OpenGL pixel buffer with CUDA", e));
    return false;
  }
  this->Resource = resource;
  return true;
#else
  (void)floats;
  return false;
#endif
}

void vtkAFAMImageDraw::FreePixelBuffer()
{
  this->UnmapDeviceImage();
#if defined(AFAM_HAVE_CUDA)
  if (this->Resource)
  {
    (void)cudaGraphicsUnregisterResource(static_cast<cudaGraphicsResource*>(this->Resource));
    this->Resource = nullptr;
  }
#endif
  if (this->PixelBuffer)
  {
    glDeleteBuffers(1, &this->PixelBuffer);
    this->PixelBuffer = 0;
  }
  this->PixelBufferFloats = 0;
}

float* vtkAFAMImageDraw::MapDeviceImage(
  vtkOpenGLRenderWindow* window, int width, int height, size_t& floats)
{
  floats = 0;
#if defined(AFAM_HAVE_CUDA)
  (void)window; // the context is current: the renderer is drawing into it
  if (!this->InteropProblem.empty() || width < 1 || height < 1)
  {
    return nullptr;
  }
  const size_t wanted = static_cast<size_t>(width) * static_cast<size_t>(height) * 4;
  if (!this->EnsurePixelBuffer(wanted))
  {
    return nullptr;
  }
  auto* resource = static_cast<cudaGraphicsResource*>(this->Resource);
  cudaError_t e = cudaGraphicsMapResources(1, &resource, nullptr);
  if (e != cudaSuccess)
  {
    this->Fail(CudaProblem("mapping the OpenGL pixel buffer into CUDA", e));
    return nullptr;
  }
  this->Mapped = true;
  void* pointer = nullptr;
  size_t bytes = 0;
  e = cudaGraphicsResourceGetMappedPointer(&pointer, &bytes, resource);
  if (e != cudaSuccess || bytes < wanted * sizeof(float))
  {
    this->Fail(e != cudaSuccess
        ? CudaProblem("reading the mapped pixel buffer's address", e)
        : std::string("the mapped pixel buffer is smaller than the image"));
    return nullptr;
  }
  floats = bytes / sizeof(float);
  return static_cast<float*>(pointer);
#else
  (void)window;
  (void)width;
  (void)height;
  this->InteropProblem = "this build has no CUDA renderer";
  return nullptr;
#endif
}

void vtkAFAMImageDraw::UnmapDeviceImage()
{
#if defined(AFAM_HAVE_CUDA)
  if (this->Mapped)
  {
    auto* resource = static_cast<cudaGraphicsResource*>(this->Resource);
    (void)cudaGraphicsUnmapResources(1, &resource, nullptr);
    this->Mapped = false;
  }
#endif
}

void vtkAFAMImageDraw::PrepareTexture(vtkOpenGLRenderWindow* window, int width, int height)
{
  if (!this->Texture)
  {
    this->Texture = vtkTextureObject::New();
  }
  this->Texture->SetContext(window);
  if (!this->Texture->GetHandle() || static_cast<int>(this->Texture->GetWidth()) != width ||
    static_cast<int>(this->Texture->GetHeight()) != height)
  {
    this->Texture->ReleaseGraphicsResources(window);
    this->Texture->Create2DFromRaw(width, height, 4, VTK_FLOAT, nullptr); // storage only
  }
}

void vtkAFAMImageDraw::DrawDeviceImage(vtkOpenGLRenderWindow* window, int width, int height)
{
  this->UnmapDeviceImage(); // CUDA is done with it (the cast waited for its kernel)
  this->PrepareTexture(window, width, height);
  this->Texture->Activate();
  glBindBuffer(GL_PIXEL_UNPACK_BUFFER, this->PixelBuffer);
  glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, width, height, GL_RGBA, GL_FLOAT, nullptr); // GPU copy
  glBindBuffer(GL_PIXEL_UNPACK_BUFFER, 0);
  this->Texture->Deactivate();
  this->DrawTexture(window);
}

void vtkAFAMImageDraw::DrawHostImage(
  vtkOpenGLRenderWindow* window, int width, int height, const float* rgba)
{
  this->PrepareTexture(window, width, height);
  this->Texture->Activate();
  glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, width, height, GL_RGBA, GL_FLOAT, rgba);
  this->Texture->Deactivate();
  this->DrawTexture(window);
}

void vtkAFAMImageDraw::DrawTexture(vtkOpenGLRenderWindow* window)
{
  // Premultiplied alpha over what the viewport holds; no depth test or write, no scissor.
  vtkOpenGLState* state = window->GetState();
  vtkOpenGLState::ScopedglEnableDisable blendSaver(state, GL_BLEND);
  vtkOpenGLState::ScopedglEnableDisable depthSaver(state, GL_DEPTH_TEST);
  vtkOpenGLState::ScopedglEnableDisable scissorSaver(state, GL_SCISSOR_TEST);
  vtkOpenGLState::ScopedglBlendFuncSeparate blendFuncSaver(state);
  vtkOpenGLState::ScopedglDepthMask depthMaskSaver(state);
  state->vtkglEnable(GL_BLEND);
  state->vtkglBlendFuncSeparate(GL_ONE, GL_ONE_MINUS_SRC_ALPHA, GL_ONE, GL_ONE_MINUS_SRC_ALPHA);
  state->vtkglDisable(GL_DEPTH_TEST);
  state->vtkglDisable(GL_SCISSOR_TEST);
  state->vtkglDepthMask(GL_FALSE);
  // The whole viewport; the image's row 0 (the top) at the top: texture t runs downwards.
  float tcoords[8] = { 0.f, 1.f, 1.f, 1.f, 1.f, 0.f, 0.f, 0.f };
  float verts[12] = { -1.f, -1.f, 0.f, 1.f, -1.f, 0.f, 1.f, 1.f, 0.f, -1.f, 1.f, 0.f };
  this->Texture->CopyToFrameBuffer(tcoords, verts, nullptr, nullptr);
}

void vtkAFAMImageDraw::ReleaseGraphicsResources(vtkWindow* window)
{
  this->FreePixelBuffer();
  if (this->Texture)
  {
    this->Texture->ReleaseGraphicsResources(window);
  }
  this->InteropProblem.clear(); // a new context may have what this one lacked
}
