// SPDX-License-Identifier: BSD-3-Clause
// Typed errors thrown by Core. Messages name the file, the block and what is wrong; the VTK layer
// forwards them through vtkErrorMacro, the command line prints them on one line of stderr.
#pragma once

#include <stdexcept>
#include <string>

namespace afam {

struct Error : std::runtime_error {
  using std::runtime_error::runtime_error;
};
/// A file that is not a valid .afam file (bad magic, truncated, checksum mismatch, absurd counts).
struct FormatError : Error {
  using Error::Error;
};
/// Data the numerics cannot take (NaN/Inf samples, ill-posed systems).
struct NumericError : Error {
  using Error::Error;
};
/// A caller's argument out of range.
struct InvalidArgument : Error {
  using Error::Error;
};
/// Operating-system I/O failure (open, read, write, rename).
struct IoError : Error {
  using Error::Error;
};
/// The user cancelled a long operation through its callback.
struct Cancelled : Error {
  using Error::Error;
};

}  // namespace afam
