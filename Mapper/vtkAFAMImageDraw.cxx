// SPDX-FileCopyrightText: Adaptive-FAM authors
// SPDX-License-Identifier: BSD-3-Clause
#include "vtkAFAMImageDraw.h"

#include "vtkOpenGLRenderWindow.h"
#include "vtkOpenGLState.h"
#include "vtkTextureObject.h"
#include "vtk_glew.h"

vtkAFAMImageDraw::vtkAFAMImageDraw() = default;

vtkAFAMImageDraw::~vtkAFAMImageDraw()
{
  if (this->Texture)
  {
    this->Texture->Delete();
  }
}

float* vtkAFAMImageDraw::MapDeviceImage(int width, int height, void* stream, size_t& floats)
{
  floats = 0;
  if (width < 1 || height < 1)
  {
    return nullptr;
  }
  const size_t wanted = static_cast<size_t>(width) * static_cast<size_t>(height) * 4;
  if (!this->ImageBuffer.Reserve(wanted * sizeof(float)))
  {
    return nullptr;
  }
  auto* pointer = static_cast<float*>(this->ImageBuffer.Map(stream));
  floats = pointer ? wanted : 0;
  return pointer;
}

void vtkAFAMImageDraw::UnmapDeviceImage()
{
  this->ImageBuffer.Unmap();
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
  glBindBuffer(GL_PIXEL_UNPACK_BUFFER, this->ImageBuffer.Name());
  glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, width, height, GL_RGBA, GL_FLOAT, nullptr); // GPU copy
  glBindBuffer(GL_PIXEL_UNPACK_BUFFER, 0);
  this->Texture->Deactivate();
  this->DrawTexture(window);
}

void vtkAFAMImageDraw::DrawHostImage(vtkOpenGLRenderWindow* window,
  int width,
  int height,
  const float* rgba)
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
  this->ImageBuffer.Free(); // and its problem: a new context may have what this one lacked
  if (this->Texture)
  {
    this->Texture->ReleaseGraphicsResources(window);
  }
}
