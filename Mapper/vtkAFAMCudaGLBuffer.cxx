// SPDX-FileCopyrightText: Adaptive-FAM authors
// SPDX-License-Identifier: BSD-3-Clause
#include "vtkAFAMCudaGLBuffer.h"

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
  (void)cudaGetLastError(); // cleared: the host path that follows must not trip over it
  return std::string(step) + " failed: " + cudaGetErrorString(e) + " (" + cudaGetErrorName(e) + ")";
}
#endif
}

std::optional<std::array<uint8_t, 16>> vtkAFAMCudaGLBuffer::ContextDeviceUuid()
{
  std::array<uint8_t, 16> uuid{};
  static_assert(GL_UUID_SIZE_EXT == 16, "OpenGL's UUIDs are CUDA's 16 bytes");
  if (!GLEW_EXT_memory_object || !glGetUnsignedBytei_vEXT)
  {
    return std::nullopt;
  }
  while (glGetError() != GL_NO_ERROR)
  {
  }
  GLint devices = 0;
  glGetIntegerv(GL_NUM_DEVICE_UUIDS_EXT, &devices);
  if (devices < 1 || glGetError() != GL_NO_ERROR)
  {
    return std::nullopt;
  }
  glGetUnsignedBytei_vEXT(GL_DEVICE_UUID_EXT, 0, uuid.data());
  if (glGetError() != GL_NO_ERROR)
  {
    return std::nullopt;
  }
  return uuid;
}

vtkAFAMCudaGLBuffer::vtkAFAMCudaGLBuffer(Direction direction)
  : Dir(direction)
{
}

vtkAFAMCudaGLBuffer::~vtkAFAMCudaGLBuffer()
{
  this->Unmap();
#if defined(AFAM_HAVE_CUDA)
  if (this->Resource)
  {
    (void)cudaGraphicsUnregisterResource(static_cast<cudaGraphicsResource*>(this->Resource));
  }
#endif
}

void vtkAFAMCudaGLBuffer::Fail(const std::string& why)
{
  this->Free();
  this->Failure = why;
}

bool vtkAFAMCudaGLBuffer::Reserve(size_t bytes)
{
#if defined(AFAM_HAVE_CUDA)
  if (!this->Failure.empty())
  {
    return false;
  }
  if (this->Buffer && this->Bytes >= bytes)
  {
    return true;
  }
  this->Free();
  const GLenum target = this->Dir == CUDA_WRITES ? GL_PIXEL_UNPACK_BUFFER : GL_PIXEL_PACK_BUFFER;
  // COPY: the driver keeps it in video memory (neither side is the host).
  const GLenum usage = this->Dir == CUDA_WRITES ? GL_DYNAMIC_COPY : GL_STREAM_COPY;
  while (glGetError() != GL_NO_ERROR)
  {
  }
  glGenBuffers(1, &this->Buffer);
  glBindBuffer(target, this->Buffer);
  glBufferData(target, static_cast<GLsizeiptr>(bytes), nullptr, usage);
  glBindBuffer(target, 0);
  if (glGetError() != GL_NO_ERROR)
  {
    this->Fail("no OpenGL buffer of " + std::to_string(bytes) + " bytes");
    return false;
  }
  this->Bytes = bytes;
  cudaGraphicsResource* resource = nullptr;
  const cudaError_t e = cudaGraphicsGLRegisterBuffer(&resource,
    this->Buffer,
    this->Dir == CUDA_WRITES ? cudaGraphicsRegisterFlagsWriteDiscard
                             : cudaGraphicsRegisterFlagsReadOnly);
  if (e != cudaSuccess)
  {
    // E.g. Mesa's OpenGL, or OpenGL on another GPU than CUDA's.
    this->Fail(CudaProblem("registering an OpenGL buffer with CUDA", e));
    return false;
  }
  this->Resource = resource;
  return true;
#else
  (void)bytes;
  this->Failure = "this build has no CUDA renderer";
  return false;
#endif
}

void* vtkAFAMCudaGLBuffer::Map(void* stream)
{
#if defined(AFAM_HAVE_CUDA)
  if (!this->Resource)
  {
    return nullptr;
  }
  auto* resource = static_cast<cudaGraphicsResource*>(this->Resource);
  cudaError_t e = cudaGraphicsMapResources(1, &resource, static_cast<cudaStream_t>(stream));
  if (e != cudaSuccess)
  {
    this->Fail(CudaProblem("mapping an OpenGL buffer into CUDA", e));
    return nullptr;
  }
  this->Mapped = true;
  this->Stream = stream;
  void* pointer = nullptr;
  size_t bytes = 0;
  e = cudaGraphicsResourceGetMappedPointer(&pointer, &bytes, resource);
  if (e != cudaSuccess || bytes < this->Bytes)
  {
    this->Fail(e != cudaSuccess ? CudaProblem("reading a mapped buffer's address", e)
                                : std::string("a mapped OpenGL buffer is smaller than asked for"));
    return nullptr;
  }
  return pointer;
#else
  (void)stream;
  return nullptr;
#endif
}

void vtkAFAMCudaGLBuffer::Unmap()
{
#if defined(AFAM_HAVE_CUDA)
  if (this->Mapped)
  {
    auto* resource = static_cast<cudaGraphicsResource*>(this->Resource);
    (void)cudaGraphicsUnmapResources(1, &resource, static_cast<cudaStream_t>(this->Stream));
    this->Mapped = false;
  }
#endif
}

void vtkAFAMCudaGLBuffer::StreamEnded()
{
#if defined(AFAM_HAVE_CUDA)
  if (this->Mapped && this->Stream)
  {
    (void)cudaDeviceSynchronize();
    this->Stream = nullptr;
  }
#endif
}

void vtkAFAMCudaGLBuffer::Free()
{
  this->Unmap();
#if defined(AFAM_HAVE_CUDA)
  if (this->Resource)
  {
    (void)cudaGraphicsUnregisterResource(static_cast<cudaGraphicsResource*>(this->Resource));
    this->Resource = nullptr;
  }
#endif
  if (this->Buffer)
  {
    glDeleteBuffers(1, &this->Buffer);
    this->Buffer = 0;
  }
  this->Bytes = 0;
  this->Failure.clear();
}
