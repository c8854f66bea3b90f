// SPDX-FileCopyrightText: Adaptive-FAM authors
// SPDX-License-Identifier: BSD-3-Clause
// Private helper of vtkAFAMVolumeMapper (not wrapped, not installed): draws a frame's premultiplied
// float RGBA image (row 0 = top) over the current viewport, blended, scaled to the viewport when
// the image is smaller (interactive frames). The image comes either from host memory (CPU frames)
// or, in CUDA builds, from an OpenGL pixel buffer that CUDA writes into while it is mapped
// (CUDA-OpenGL interop): the GPU's image then reaches the window without leaving the GPU. Either
// way it is copied into one float texture kept across frames and drawn with a quad whose texture
// coordinates flip it, so no host flip and no new texture per frame.
#ifndef vtkAFAMImageDraw_h
#define vtkAFAMImageDraw_h

#include "vtkAFAMCudaGLBuffer.h"

#include <cstddef>
#include <string>

class vtkOpenGLRenderWindow;
class vtkTextureObject;
class vtkWindow;

class vtkAFAMImageDraw
{
public:
  vtkAFAMImageDraw();
  ~vtkAFAMImageDraw();
  vtkAFAMImageDraw(const vtkAFAMImageDraw&) = delete;
  vtkAFAMImageDraw& operator=(const vtkAFAMImageDraw&) = delete;

  /// Device memory (CUDA) for the next image of width x height: the pixel buffer, mapped, and in
  /// `floats` its capacity. nullptr when interop is unavailable (a build without CUDA, an OpenGL
  /// that is not on the CUDA device, e.g. Mesa): Problem() says why, and it is not tried again
  /// until ReleaseGraphicsResources.
  /// `stream`: the cudaStream_t the GPU renderer casts on.
  float* MapDeviceImage(int width, int height, void* stream, size_t& floats);
  /// Gives the mapped buffer back to OpenGL without drawing it (nothing was cast into it).
  void UnmapDeviceImage();
  /// The stream the image was mapped on is gone (vtkAFAMCudaGLBuffer::StreamEnded).
  void DeviceImageStreamEnded()
  {
    this->ImageBuffer.StreamEnded();
  }
  /// Draws the image CUDA left in the mapped buffer (unmapping it first).
  void DrawDeviceImage(vtkOpenGLRenderWindow* window, int width, int height);
  /// Draws `rgba` (width * height * 4 floats in host memory).
  void DrawHostImage(vtkOpenGLRenderWindow* window, int width, int height, const float* rgba);

  /// Why interop is unavailable; empty while it is (or while it has not been tried).
  const std::string& Problem() const
  {
    return this->ImageBuffer.Problem();
  }
  /// Frees the texture, the pixel buffer and its CUDA registration (the window's context goes).
  void ReleaseGraphicsResources(vtkWindow* window);

private:
  /// The texture, allocated for width x height (kept when the size is the same).
  void PrepareTexture(vtkOpenGLRenderWindow* window, int width, int height);
  /// Draws the texture, rows flipped, blended (premultiplied alpha) over the viewport.
  void DrawTexture(vtkOpenGLRenderWindow* window);

  vtkTextureObject* Texture = nullptr;
  vtkAFAMCudaGLBuffer ImageBuffer{ vtkAFAMCudaGLBuffer::CUDA_WRITES };
};

#endif
