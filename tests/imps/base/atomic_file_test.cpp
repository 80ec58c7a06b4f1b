// SPDX-License-Identifier: MIT
// Atomic saves (imps/base/include/imps/atomic_file.h): the target is replaced whole or left untouched, no temporary
// file survives a failure, an existing target keeps its permissions, temporary names are exclusive.
#include "imps/atomic_file.h"

#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstdint>
#include <filesystem>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "scratch_dir.h"

namespace imps {
namespace {

namespace fs = std::filesystem;

mode_t modeOf(const fs::path& path) {
  struct stat st {};
  EXPECT_EQ(::stat(path.c_str(), &st), 0) << path;
  return st.st_mode & 07777;
}

class AtomicFile : public ::testing::Test {
 protected:
  // Every name in the directory: a save leaves the target and nothing else.
  std::set<std::string> names() const {
    std::set<std::string> out;
    for (const auto& entry : fs::directory_iterator(dir_.path())) out.insert(entry.path().filename().string());
    return out;
  }
  ScratchDir dir_{"imps_atomic_file_test"};
};

TEST_F(AtomicFile, CreatesANewFileWithExactlyTheBytes) {
  const fs::path target = dir_ / "new.txt";
  const std::string bytes("line 1\n\0binary\xff", 15);
  const auto saved = writeFileAtomically(target.string(), bytes);
  ASSERT_TRUE(saved) << saved.error().message;
  EXPECT_EQ(fileBytes(target), bytes);
  EXPECT_EQ(names(), std::set<std::string>{"new.txt"});
}

TEST_F(AtomicFile, ReplacesAnExistingFileWhole) {
  const fs::path target = dir_ / "scene.json";
  writeBytes(target, std::string(100000, 'o'));  // longer than the new contents: nothing of it may remain
  ASSERT_TRUE(writeFileAtomically(target.string(), std::string_view("short")));
  EXPECT_EQ(fileBytes(target), "short");
  EXPECT_EQ(names(), std::set<std::string>{"scene.json"});
}

TEST_F(AtomicFile, TheByteSpanOverloadWritesTheSameBytes) {
  const fs::path target = dir_ / "mesh.bin";
  const std::vector<uint8_t> bytes = {0, 1, 2, 0xfe, 0xff, 0};
  ASSERT_TRUE(writeFileAtomically(target.string(), std::span<const uint8_t>(bytes)));
  EXPECT_EQ(fileBytes(target), std::string("\0\1\2\xfe\xff\0", 6));
  ASSERT_TRUE(writeFileAtomically(target.string(), std::span<const uint8_t>()));
  EXPECT_EQ(fs::file_size(target), 0u);
}

TEST_F(AtomicFile, AnExistingTargetKeepsItsPermissions) {
  const fs::path target = dir_ / "private.json";
  writeBytes(target, "old");
  fs::permissions(target, fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read);
  ASSERT_TRUE(writeFileAtomically(target.string(), std::string_view("new")));
  EXPECT_EQ(fileBytes(target), "new");
  EXPECT_EQ(modeOf(target), mode_t{0640});
}

TEST_F(AtomicFile, ANewFileGetsTheUsualModeLessTheUmask) {
  const mode_t previous = ::umask(027);
  const bool saved = writeFileAtomically((dir_ / "a.txt").string(), std::string_view("a")).has_value();
  ::umask(previous);
  ASSERT_TRUE(saved);
  EXPECT_EQ(modeOf(dir_ / "a.txt"), mode_t{0640});  // 0666 & ~027
}

TEST_F(AtomicFile, AMissingDirectoryFailsWithTheStepAndReasonAndWritesNothing) {
  const fs::path target = dir_ / "no_such_dir" / "out.txt";
  const auto saved = writeFileAtomically(target.string(), std::string_view("x"));
  ASSERT_FALSE(saved);
  EXPECT_EQ(saved.error().message,
            "cannot save '" + target.string() + "': creating a temporary file: No such file or directory");
  EXPECT_EQ(saved.error().path, target.string());
  EXPECT_EQ(saved.error().code, ENOENT);
  EXPECT_TRUE(names().empty());
}

TEST_F(AtomicFile, AParentThatIsAFileFails) {
  writeBytes(dir_ / "plain", "I am a file");
  const auto saved = writeFileAtomically((dir_ / "plain" / "out.txt").string(), std::string_view("x"));
  ASSERT_FALSE(saved);
  const std::string error = saved.error().message;
  EXPECT_EQ(saved.error().code, ENOTDIR);
  EXPECT_NE(error.find("creating a temporary file: Not a directory"), std::string::npos) << error;
  EXPECT_EQ(fileBytes(dir_ / "plain"), "I am a file");
  EXPECT_EQ(names(), std::set<std::string>{"plain"});
}

TEST_F(AtomicFile, AnUnwritableDirectoryFailsAndLeavesTheTargetUntouched) {
  if (::geteuid() == 0) GTEST_SKIP() << "root writes into read-only directories";
  const fs::path target = dir_ / "kept.txt";
  writeBytes(target, "precious");
  fs::permissions(dir_.path(), fs::perms::owner_read | fs::perms::owner_exec);
  const auto saved = writeFileAtomically(target.string(), std::string_view("lost?"));
  fs::permissions(dir_.path(), fs::perms::owner_all);
  ASSERT_FALSE(saved);
  const std::string error = saved.error().message;
  EXPECT_NE(error.find("creating a temporary file: Permission denied"), std::string::npos) << error;
  EXPECT_EQ(fileBytes(target), "precious");
  EXPECT_EQ(names(), std::set<std::string>{"kept.txt"});
}

TEST_F(AtomicFile, ARenameFailureRemovesTheTemporaryFileAndLeavesTheTargetUntouched) {
  // A non-empty directory cannot be renamed over (for root too): the temporary file is written, then the rename fails.
  const fs::path target = dir_ / "occupied";
  fs::create_directories(target);
  writeBytes(target / "inside.txt", "still here");
  const auto saved = writeFileAtomically(target.string(), std::string_view("data"));
  ASSERT_FALSE(saved);
  const std::string error = saved.error().message;
  EXPECT_EQ(error.rfind("cannot save '" + target.string() + "': renaming the temporary file over it: ", 0), 0u)
      << error;
  EXPECT_EQ(names(), std::set<std::string>{"occupied"});
  EXPECT_EQ(fileBytes(target / "inside.txt"), "still here");
}

TEST_F(AtomicFile, AWriteFailureRemovesTheTemporaryFileAndLeavesTheTargetUntouched) {
  // A file size limit makes write() fail with EFBIG part way through (for root too).
  const fs::path target = dir_ / "big.bin";
  writeBytes(target, "old contents");
  rlimit previous{};
  ASSERT_EQ(::getrlimit(RLIMIT_FSIZE, &previous), 0);
  rlimit small = previous;
  small.rlim_cur = 4096;
  auto* previousHandler = std::signal(SIGXFSZ, SIG_IGN);
  ASSERT_EQ(::setrlimit(RLIMIT_FSIZE, &small), 0);
  const auto saved = writeFileAtomically(target.string(), std::string(100000, 'x'));
  ::setrlimit(RLIMIT_FSIZE, &previous);
  std::signal(SIGXFSZ, previousHandler);
  ASSERT_FALSE(saved);
  EXPECT_EQ(saved.error().message, "cannot save '" + target.string() + "': writing: File too large");
  EXPECT_EQ(saved.error().code, EFBIG);
  EXPECT_EQ(fileBytes(target), "old contents");
  EXPECT_EQ(names(), std::set<std::string>{"big.bin"});
}

TEST_F(AtomicFile, TemporaryNamesAreSiblingsAndNeverRepeat) {
  const std::string path = (dir_ / "t.json").string();
  const std::string prefix = path + ".tmp-" + std::to_string(::getpid()) + "-";
  std::set<std::string> seen;
  for (int i = 0; i < 1000; ++i) {
    const std::string name = temporarySibling(path);
    ASSERT_EQ(name.rfind(prefix, 0), 0u) << name;
    EXPECT_TRUE(seen.insert(name).second) << "repeated " << name;
  }
}

TEST_F(AtomicFile, AnExistingFileWithTheNextTemporaryNameIsNeverOverwritten) {
  // Another writer (or a stale file) already holds the next temporary names: the save creates its own, exclusively.
  const std::string path = (dir_ / "t.json").string();
  const std::string probe = temporarySibling(path);
  const size_t dash = probe.find_last_of('-');
  const unsigned long next = std::stoul(probe.substr(dash + 1)) + 1;
  std::vector<fs::path> squatters;
  for (unsigned long n = next; n < next + 3; ++n) {
    squatters.push_back(probe.substr(0, dash + 1) + std::to_string(n));
    writeBytes(squatters.back(), "someone else's");
  }
  ASSERT_TRUE(writeFileAtomically(path, std::string_view("mine")));
  EXPECT_EQ(fileBytes(path), "mine");
  for (const fs::path& s : squatters) EXPECT_EQ(fileBytes(s), "someone else's") << s;
  EXPECT_EQ(names().size(), 1 + squatters.size());
}

TEST_F(AtomicFile, ConcurrentSavesOfOneTargetLeaveOneWholeVersion) {
  const std::string path = (dir_ / "shared.txt").string();
  constexpr int kWriters = 8;
  auto contents = [](int w) { return std::string(50000 + size_t(w), char('a' + w)); };
  std::vector<std::thread> writers;
  std::vector<int> ok(kWriters, 0);
  for (int w = 0; w < kWriters; ++w)
    writers.emplace_back([&, w] {
      for (int k = 0; k < 10; ++k) ok[size_t(w)] += writeFileAtomically(path, contents(w)) ? 1 : 0;
    });
  for (std::thread& t : writers) t.join();
  for (int w = 0; w < kWriters; ++w) EXPECT_EQ(ok[size_t(w)], 10) << w;
  const std::string final = fileBytes(path);
  ASSERT_FALSE(final.empty());
  EXPECT_EQ(final, contents(final[0] - 'a'));  // one writer's bytes, whole
  EXPECT_EQ(names(), std::set<std::string>{"shared.txt"});
}

TEST_F(AtomicFile, CommitTemporaryFileRenamesOverTheTargetKeepingItsPermissions) {
  const fs::path target = dir_ / "session.imps";
  writeBytes(target, "old");
  fs::permissions(target, fs::perms::owner_read | fs::perms::owner_write);
  const std::string temp = temporarySibling(target.string());
  writeBytes(temp, "recorded");
  const auto committed = commitTemporaryFile(temp, target.string());
  ASSERT_TRUE(committed) << committed.error().message;
  EXPECT_EQ(fileBytes(target), "recorded");
  EXPECT_EQ(modeOf(target), mode_t{0600});
  EXPECT_EQ(names(), std::set<std::string>{"session.imps"});
}

TEST_F(AtomicFile, AFailedCommitRemovesTheTemporaryFile) {
  const fs::path target = dir_ / "occupied";
  fs::create_directories(target / "child");
  const std::string temp = temporarySibling(target.string());
  writeBytes(temp, "recorded");
  const auto committed = commitTemporaryFile(temp, target.string());
  ASSERT_FALSE(committed);
  const std::string error = committed.error().message;
  EXPECT_EQ(error.rfind("cannot save '" + target.string() + "': renaming the temporary file over it: ", 0), 0u)
      << error;
  EXPECT_FALSE(fs::exists(temp));
  EXPECT_TRUE(fs::is_directory(target / "child"));
}

}  // namespace
}  // namespace imps
