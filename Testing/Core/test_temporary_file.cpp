// SPDX-License-Identifier: BSD-3-Clause
// Temporary files of atomic writes: which leftovers the next writer removes, and which it keeps.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fstream>
#include <string>

#include "afam/format/temporary_file.hpp"
#include "scratch_dir.hpp"

using namespace afam;

namespace {

bool exists(const std::string& p) {
  struct stat s {};
  return ::lstat(p.c_str(), &s) == 0;
}
void touch(const std::string& p) { std::ofstream(p) << "left over"; }

}  // namespace

TEST(TemporaryFile, RemovesOnlyUnlockedFilesOfItsOwnPattern) {
  const std::string out = afam_test::scratchPath("model.afam");
  std::string live;
  const int fd = createLockedTemporary(out, live);  // a writer alive in this process
  ASSERT_GE(fd, 0);
  EXPECT_EQ(live.substr(0, out.size() + 5), out + ".tmp-");
  const std::string stale = out + ".tmp-AbC123";     // unlocked: its writer is gone
  const std::string shortName = out + ".tmp-AbC12";  // not mkstemp's six characters
  const std::string longName = out + ".tmp-AbC1234";
  const std::string punct = out + ".tmp-AbC.12";
  const std::string other = afam_test::scratchPath("other.afam.tmp-AbC123");  // another output
  for (const std::string& p : {stale, shortName, longName, punct, other}) touch(p);
  EXPECT_EQ(removeStaleTemporaries(out), 1);
  EXPECT_FALSE(exists(stale));
  EXPECT_TRUE(exists(live)) << "a live writer's temporary file was removed";
  for (const std::string& p : {shortName, longName, punct, other}) EXPECT_TRUE(exists(p)) << p;
  ::close(fd);  // the writer "dies": its lock goes with the descriptor
  EXPECT_EQ(removeStaleTemporaries(out), 1);
  EXPECT_FALSE(exists(live));
}

TEST(TemporaryFile, AKilledWritersFileIsKeptWhileItLivesAndRemovedAfterKill9) {
  const std::string out = afam_test::scratchPath("killed.afam");
  int ready[2];
  ASSERT_EQ(::pipe(ready), 0);
  const pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {  // the writer: create and lock, report, then wait to be killed
    std::string tmp;
    createLockedTemporary(out, tmp);
    const char c = 1;
    (void)!::write(ready[1], &c, 1);
    for (;;) ::pause();
  }
  char c = 0;
  ASSERT_EQ(::read(ready[0], &c, 1), 1);
  EXPECT_EQ(removeStaleTemporaries(out), 0)
      << "the file of a live writer (pid " << pid << ") was removed";
  ASSERT_EQ(::kill(pid, SIGKILL), 0);
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL);
  EXPECT_EQ(removeStaleTemporaries(out), 1);
  ::close(ready[0]);
  ::close(ready[1]);
}

TEST(TemporaryFile, OutputInAMissingFolderIsAClearError) {
  std::string tmp;
  try {
    createLockedTemporary(afam_test::scratchPath("no/such/folder/x.afam"), tmp);
    FAIL() << "no error";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("no/such/folder/x.afam"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("No such file"), std::string::npos) << e.what();
  }
  EXPECT_EQ(removeStaleTemporaries(afam_test::scratchPath("no/such/folder/x.afam")), 0);
}
