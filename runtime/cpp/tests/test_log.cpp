// The broker's own log rotated by size (log.max_bytes, log.keep; docs/reliability.md).
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <unistd.h>

#include "modd/util/log.hpp"

namespace {

std::vector<std::string> lines_of(const std::string& path) {
  std::ifstream f(path);
  std::vector<std::string> out;
  for (std::string l; std::getline(f, l);) out.push_back(l);
  return out;
}

}  // namespace

TEST(Log, RotatedBySizeKeepingTheNewestFiles) {
  auto dir = std::filesystem::temp_directory_path() / ("modd-log-" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  std::string path = (dir / "pubbroker.log").string();
  // In a child process: the log sink is process-wide and the other tests log to stderr.
  EXPECT_EXIT(
      {
        modd::log_to_file(path, 4096, 2);
        for (int i = 0; i < 500; ++i) modd::log_line("line %04d of a broker that logs a lot", i);
        std::exit(0);
      },
      ::testing::ExitedWithCode(0), "");
  EXPECT_TRUE(std::filesystem::exists(path + ".1"));
  EXPECT_TRUE(std::filesystem::exists(path + ".2"));
  EXPECT_FALSE(std::filesystem::exists(path + ".3"));  // the oldest dropped: bounded disk use
  std::vector<std::string> all;
  for (const std::string& p : {path + ".2", path + ".1", path}) {
    EXPECT_LE(std::filesystem::file_size(p), 4096u) << p;
    auto l = lines_of(p);
    all.insert(all.end(), l.begin(), l.end());
  }
  ASSERT_FALSE(all.empty());
  // The newest lines, in order, none torn: the last one is line 499.
  EXPECT_NE(all.back().find("line 0499 "), std::string::npos);
  for (size_t i = 1; i < all.size(); ++i) {
    int prev = std::atoi(all[i - 1].c_str() + all[i - 1].find("line ") + 5);
    int cur = std::atoi(all[i].c_str() + all[i].find("line ") + 5);
    EXPECT_EQ(cur, prev + 1);
  }
  std::filesystem::remove_all(dir);
}
