#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <string>
#include <thread>
#include <vector>

#include "io/progress.h"

using namespace chlorovdb;

namespace {

std::string contents(std::FILE* f) {
  std::rewind(f);
  std::string s;
  for (int c; (c = std::fgetc(f)) != EOF;) s += char(c);
  return s;
}

int count_lines(const std::string& s) { return int(std::count(s.begin(), s.end(), '\n')); }

}  // namespace

TEST(Progress, PlainLinesEveryTenPercent) {
  std::FILE* f = std::tmpfile();  // not a terminal
  ASSERT_NE(f, nullptr);
  {
    Progress p(100, "render", "tiles", f);
    for (int i = 0; i < 100; ++i) p.add(1);
    p.finish();
  }
  const std::string out = contents(f);
  std::fclose(f);
  EXPECT_NE(out.find("render: 40% (40/100 tiles) elapsed "), std::string::npos) << out;
  EXPECT_NE(out.find(", eta "), std::string::npos) << out;
  EXPECT_NE(out.find("render: 100% (100/100 tiles) in "), std::string::npos) << out;
  EXPECT_EQ(count_lines(out), 10) << out;  // 10 %, ..., 90 %, then the final line
  EXPECT_EQ(out.find('\r'), std::string::npos);
}

TEST(Progress, ThreadSafeIncrements) {
  std::FILE* f = std::tmpfile();
  ASSERT_NE(f, nullptr);
  Progress p(4000, "voxelize", "slices", f);
  std::vector<std::thread> threads;
  for (int t = 0; t < 4; ++t)
    threads.emplace_back([&p] {
      for (int i = 0; i < 1000; ++i) p.add(1);
    });
  for (auto& t : threads) t.join();
  EXPECT_EQ(p.done(), 4000);
  p.finish();
  p.finish();  // idempotent
  const std::string out = contents(f);
  std::fclose(f);
  EXPECT_LE(count_lines(out), 11) << out;
  EXPECT_EQ(out.substr(out.rfind("voxelize:")).rfind("voxelize: 100% (4000/4000 slices) in ", 0), 0u) << out;
}

TEST(Progress, DestructorFinishes) {
  std::FILE* f = std::tmpfile();
  ASSERT_NE(f, nullptr);
  {
    Progress p(10, "merge", "files", f);
    p.update(3);
  }
  const std::string out = contents(f);
  std::fclose(f);
  EXPECT_NE(out.find("merge: 30% (3/10 files) in "), std::string::npos) << out;
}
