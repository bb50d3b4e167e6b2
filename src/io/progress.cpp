#include "io/progress.h"

#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>

namespace chlorovdb {

namespace {

constexpr auto kTerminalInterval = std::chrono::milliseconds(100);
constexpr auto kPlainInterval = std::chrono::seconds(5);
constexpr int kBarWidth = 30;

std::string format_duration(double s) {
  if (s < 60) return fmt::format("{:.1f} s", s);
  if (s < 3600) return fmt::format("{} min {:02} s", int(s) / 60, int(s) % 60);
  return fmt::format("{} h {:02} min", int(s) / 3600, int(s) / 60 % 60);
}

}  // namespace

Progress::Progress(int64_t total_work, std::string label, std::string unit, std::FILE* out)
    : total_(std::max<int64_t>(total_work, 1)),
      label_(std::move(label)),
      unit_(std::move(unit)),
      out_(out),
      terminal_(::isatty(::fileno(out)) != 0),
      start_(Clock::now()),
      last_report_(start_) {}

Progress::~Progress() { finish(); }

void Progress::update(int64_t done) {
  done_.store(done, std::memory_order_relaxed);
  report(false);
}

void Progress::add(int64_t n) {
  done_.fetch_add(n, std::memory_order_relaxed);
  report(false);
}

void Progress::finish() { report(true); }

std::string Progress::line(int64_t done, double elapsed_s, bool final) const {
  const double fraction = std::clamp(double(done) / double(total_), 0.0, 1.0);
  const int percent = int(std::floor(100.0 * fraction));
  const std::string counts = fmt::format("({}/{} {})", done, total_, unit_);
  const std::string time = final ? fmt::format("in {}", format_duration(elapsed_s))
                           : done > 0 ? fmt::format("elapsed {}, eta {}", format_duration(elapsed_s),
                                                    format_duration(elapsed_s * double(total_ - done) / double(done)))
                                      : fmt::format("elapsed {}", format_duration(elapsed_s));
  if (!terminal_) return fmt::format("{}: {}% {} {}\n", label_, percent, counts, time);
  const int filled = int(fraction * kBarWidth);
  // '\r' redraws in place; trailing spaces clear a longer previous line.
  return fmt::format("\r{} [{}{}] {:3}% {} {}   {}", label_, std::string(size_t(filled), '#'),
                     std::string(size_t(kBarWidth - filled), '.'), percent, counts, time, final ? "\n" : "");
}

void Progress::report(bool final) {
  // Workers never wait for the printer: if another thread is printing, skip.
  std::unique_lock lock(mutex_, std::defer_lock);
  if (final) lock.lock();
  else if (!lock.try_lock()) return;
  if (finished_) return;

  const Clock::time_point now = Clock::now();
  const int64_t done = done_.load(std::memory_order_relaxed);
  if (!final) {
    if (terminal_ && now - last_report_ < kTerminalInterval) return;
    const int64_t tenth = std::min<int64_t>(10, done * 10 / total_);
    // Plain mode leaves 100 % to the final line, which gives the total time.
    if (!terminal_ && (done >= total_ || (tenth <= last_tenth_ && now - last_report_ < kPlainInterval))) return;
    last_tenth_ = std::max(last_tenth_, tenth);
  }
  last_report_ = now;
  finished_ = final;
  std::fputs(line(done, std::chrono::duration<double>(now - start_).count(), final).c_str(), out_);
  std::fflush(out_);
}

}  // namespace chlorovdb
