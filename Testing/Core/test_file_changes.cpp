// SPDX-License-Identifier: BSD-3-Clause
// A file another process changes while it is open: noticed at the next read (FileChangedError,
// naming the path and what changed), never taken for damage, never mixed with the old contents.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "afam/base/errors.hpp"
#include "afam/format/file_identity.hpp"
#include "afam/render/renderer.hpp"
#include "render_test_util.hpp"

using namespace afam;

namespace {

std::vector<char> bytesOf(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::vector<char>((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

/// Overwrites `path` in place (same inode, as `cp` or a non-atomic writer does).
void rewriteInPlace(const std::string& path, const std::vector<char>& bytes) {
  std::ofstream(path, std::ios::binary | std::ios::trunc)
      .write(bytes.data(), std::streamsize(bytes.size()));
}

/// A private copy of a small encoding, opened (each test changes its own copy).
std::shared_ptr<const AfamFile> openCopy(const std::string& name) {
  const std::string path = afam_test::tempPath(name);
  rewriteInPlace(path,
                 bytesOf(afam_test::encodeMl(33, EncodingMode::Adaptive, 3, 4, 1e-3)->path()));
  return AfamFile::open(path);
}

/// The message of the FileChangedError `read` throws ("" when it throws nothing).
template <typename Read>
std::string changeMessage(Read read) {
  try {
    read();
  } catch (const FileChangedError& e) {
    return e.what();
  }
  return {};
}

RenderOptions options() {
  RenderOptions o;
  o.threads = 2;
  o.sampleDistance = 0.02f;
  o.cache = CacheBudget{};
  return o;
}

Camera camera() { return Camera::lookAt({1.6, 1.9, 1.3}, {0, 0, 0}, {0, 0, 1}, 60, 48, 48); }

}  // namespace

TEST(FileChanges, UnchangedFileReadsAndChecksClean) {
  const auto f = openCopy("unchanged");
  for (int64_t e = 0; e < int64_t(f->entries().size()); ++e) EXPECT_NO_THROW(f->readPayload(e));
  EXPECT_NO_THROW(f->checkUnchanged());
}

TEST(FileChanges, InPlaceRewriteWithAnotherEncodingIsNoticedAtTheNextRead) {
  const auto f = openCopy("rewritten");
  const std::vector<float> before = f->readPayload(0);
  rewriteInPlace(f->path(),
                 bytesOf(afam_test::encodeMl(33, EncodingMode::Adaptive, 2, 4, 1e-2)->path()));
  const std::string message = changeMessage([&] { f->readPayload(0); });
  EXPECT_NE(message.find(f->path()), std::string::npos) << message;
  EXPECT_NE(message.find("changed since it was opened"), std::string::npos) << message;
  EXPECT_NE(message.find("its size went from"), std::string::npos) << message;
  // Every entry: a read that lands on new bytes is a change, not damage (no FormatError).
  for (int64_t e = 0; e < int64_t(f->entries().size()); ++e)
    EXPECT_THROW(f->readPayload(e), FileChangedError);
  EXPECT_THROW(f->checkUnchanged(), FileChangedError);
  EXPECT_FALSE(before.empty());
}

TEST(FileChanges, TruncationIsAChangeNotATruncatedPayload) {
  const auto f = openCopy("shrunk");
  const uint64_t size = f->fileSize();
  ASSERT_EQ(::truncate(f->path().c_str(), off_t(size * 6 / 10)), 0);
  const int64_t last = int64_t(f->entries().size()) - 1;  // its payload is now past the end
  const std::string message = changeMessage([&] { f->readPayload(last); });
  EXPECT_NE(message.find("its size went from " + std::to_string(size) + " to " +
                         std::to_string(size * 6 / 10)),
            std::string::npos)
      << message;
  EXPECT_THROW(f->readPayload(0), FileChangedError);  // still inside the file, but not trusted
  // Opened again, the file says what it is now.
  try {
    AfamFile::open(f->path());
    ADD_FAILURE() << "a truncated file opened";
  } catch (const FormatError& e) {
    EXPECT_NE(std::string(e.what()).find("truncated"), std::string::npos) << e.what();
  }
}

TEST(FileChanges, NewModificationTimeAloneIsAChange) {
  const auto f = openCopy("touched");
  const struct timespec times[2] = {{0, UTIME_OMIT}, {1000000000, 0}};  // mtime: 2001-09-09
  ASSERT_EQ(::utimensat(AT_FDCWD, f->path().c_str(), times, 0), 0);
  const std::string message = changeMessage([&] { f->readPayload(0); });
  EXPECT_NE(message.find("modification time"), std::string::npos) << message;
}

TEST(FileChanges, ReplacementByRenameIsNoticedByTheFrameCheckWhileReadsStayOnTheOldFile) {
  const auto f = openCopy("replaced");
  const std::vector<float> before = f->readPayload(1);
  const std::string other = afam_test::tempPath("replacement");
  rewriteInPlace(other,
                 bytesOf(afam_test::encodeMl(33, EncodingMode::Adaptive, 2, 4, 1e-2)->path()));
  ASSERT_EQ(std::rename(other.c_str(), f->path().c_str()), 0);
  // The descriptor still reads the file that was opened, whole and consistent ...
  EXPECT_EQ(f->readPayload(1), before);
  // ... and the path now names another file, which the per-frame check says.
  const std::string message = changeMessage([&] { f->checkUnchanged(); });
  EXPECT_NE(message.find("replaced by another file"), std::string::npos) << message;
}

TEST(FileChanges, RemovedFileIsNoticed) {
  const auto f = openCopy("removed");
  ASSERT_EQ(::unlink(f->path().c_str()), 0);
  const std::string message = changeMessage([&] { f->checkUnchanged(); });
  EXPECT_NE(message.find("no longer exists"), std::string::npos) << message;
}

TEST(FileChanges, RendererStopsAtAChangedFileWithoutRecordingDamage) {
  const auto f = openCopy("render");
  Renderer r(f, options());
  FrameStats st;
  r.renderFrame(camera(), st);
  EXPECT_GT(st.misses, 0u);
  ASSERT_EQ(::truncate(f->path().c_str(), off_t(f->fileSize() / 2)), 0);
  // Every block is in the cache now; the frame check still stops the frame before any is drawn.
  EXPECT_THROW(r.renderFrame(camera(), st), FileChangedError);
  EXPECT_EQ(r.cache().damage().count(), 0u);
  // A renderer that has read nothing yet stops the same way, and records no damage either.
  const auto g = openCopy("render_cold");
  Renderer cold(g, options());
  rewriteInPlace(g->path(),
                 bytesOf(afam_test::encodeMl(33, EncodingMode::Adaptive, 2, 4, 1e-2)->path()));
  EXPECT_THROW(cold.renderFrame(camera(), st), FileChangedError);
  EXPECT_EQ(cold.cache().damage().count(), 0u);
}

TEST(FileChanges, DescribeChangeNamesWhatChanged) {
  FileIdentity a;
  a.exists = true;
  a.device = 1;
  a.inode = 2;
  a.size = 100;
  a.mtimeNs = 5;
  FileIdentity b = a;
  EXPECT_EQ(describeChange(a, b), "");
  b.size = 60;
  EXPECT_EQ(describeChange(a, b), "its size went from 100 to 60 bytes");
  b = a;
  b.inode = 3;
  EXPECT_EQ(describeChange(a, b), "it was replaced by another file");
  b = a;
  b.mtimeNs = 6;
  EXPECT_EQ(describeChange(a, b), "it was rewritten (its modification time changed)");
  EXPECT_EQ(describeChange(a, FileIdentity{}), "it no longer exists");
}
