#pragma once
// Progress report for long loops (render tiles, voxelisation slices). On a
// terminal: one bar redrawn in place at most ~10 times a second, with percentage,
// elapsed time and ETA. Otherwise (logs, CI): plain lines such as
//   render: 40% (40/100 tiles) elapsed 3.2 s, eta 4.8 s
// at most every 10 % of the work or every 5 s.
#include <atomic>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <mutex>
#include <string>

namespace chlorovdb {

class Progress {
 public:
  // `out` defaults to stderr; whether it is a terminal picks the style.
  Progress(int64_t total_work, std::string label, std::string unit = "tiles", std::FILE* out = stderr);
  ~Progress();  // finishes the report if finish() was not called
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;

  void update(int64_t done);  // absolute amount done
  void add(int64_t n);        // thread-safe increment
  void finish();              // final line with the total time; idempotent
  int64_t done() const { return done_.load(std::memory_order_relaxed); }

 private:
  using Clock = std::chrono::steady_clock;
  void report(bool final);
  std::string line(int64_t done, double elapsed_s, bool final) const;

  const int64_t total_;
  const std::string label_, unit_;
  std::FILE* const out_;
  const bool terminal_;
  const Clock::time_point start_;
  std::atomic<int64_t> done_{0};
  std::mutex mutex_;  // guards the fields below and the output
  Clock::time_point last_report_;
  int64_t last_tenth_ = 0;  // plain mode: the last 10 % step printed
  bool finished_ = false;
};

}  // namespace chlorovdb
