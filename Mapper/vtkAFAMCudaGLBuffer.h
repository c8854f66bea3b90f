// SPDX-FileCopyrightText: Adaptive-FAM authors
// SPDX-License-Identifier: BSD-3-Clause
// Private helper of vtkAFAMVolumeMapper (not wrapped, not installed): one OpenGL buffer object
// registered with CUDA (CUDA-OpenGL interop), mapped into CUDA's address space while a frame uses
// it. Either CUDA writes it and OpenGL reads it (the cast image, unpacked into a texture), or
// OpenGL writes it and CUDA reads it (the depth buffer, packed by glReadPixels). In builds without
// CUDA every call fails with a reason. The OpenGL context must be current for every call but Unmap.
#ifndef vtkAFAMCudaGLBuffer_h
#define vtkAFAMCudaGLBuffer_h

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>

class vtkAFAMCudaGLBuffer
{
public:
  enum Direction
  {
    CUDA_WRITES, ///< written by CUDA, read by OpenGL
    CUDA_READS   ///< written by OpenGL, read by CUDA
  };
  explicit vtkAFAMCudaGLBuffer(Direction direction);
  /// The UUID of the GPU the current OpenGL context runs on (GL_EXT_memory_object's
  /// GL_DEVICE_UUID_EXT, as CUDA's cudaDeviceProp::uuid gives it), or none where the OpenGL does
  /// not say. Interop needs CUDA on that GPU.
  static std::optional<std::array<uint8_t, 16>> ContextDeviceUuid();
  /// Unregisters from CUDA; the OpenGL name goes with the context (Free while it is current).
  ~vtkAFAMCudaGLBuffer();
  vtkAFAMCudaGLBuffer(const vtkAFAMCudaGLBuffer&) = delete;
  vtkAFAMCudaGLBuffer& operator=(const vtkAFAMCudaGLBuffer&) = delete;

  /// At least `bytes` bytes, registered with CUDA (kept when already large enough). False when
  /// that fails: Problem() says why, and it stays failed until Free().
  bool Reserve(size_t bytes);
  /// The buffer in CUDA's address space (nullptr and a Problem() when mapping fails). `stream`
  /// (a cudaStream_t) is where CUDA uses it: OpenGL's earlier work on the buffer is ordered before
  /// that stream's later work, without the host waiting.
  void* Map(void* stream);
  /// Gives it back to OpenGL (no-op when not mapped): CUDA's earlier work on the stream comes
  /// first.
  void Unmap();
  /// The stream it was mapped on was destroyed while it was mapped (its renderer was rebuilt
  /// within the frame, as when the file changed on disk and was opened again): waits for the
  /// device, and Unmap then uses the default stream (unmapping on a destroyed stream crashes the
  /// driver).
  void StreamEnded();
  /// Unregisters and deletes the buffer, and forgets a Problem (a new context may do better).
  void Free();
  unsigned int Name() const
  {
    return this->Buffer;
  }
  const std::string& Problem() const
  {
    return this->Failure;
  }

private:
  void Fail(const std::string& why);
  Direction Dir;
  unsigned int Buffer = 0; // OpenGL name (0: none)
  size_t Bytes = 0;
  void* Resource = nullptr; // cudaGraphicsResource*
  void* Stream = nullptr;   // cudaStream_t of the mapping
  bool Mapped = false;
  std::string Failure;
};

#endif
