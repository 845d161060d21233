#include "engine/progress.h"

#include <cstdio>

#include "base/env.h"

namespace pb {

std::string FormatSeconds(double s) {
  char buf[32];
  if (s < 1) std::snprintf(buf, sizeof buf, "%.0f ms", s * 1000);
  else if (s < 120) std::snprintf(buf, sizeof buf, "%.1f s", s);
  else std::snprintf(buf, sizeof buf, "%dm%02ds", static_cast<int>(s) / 60, static_cast<int>(s) % 60);
  return buf;
}

void ProgressPrinter::ClearLive() {
  for (int i = 0; i < drawn_lines_; ++i) std::fputs("\x1b[1A\x1b[2K", stderr);
  drawn_lines_ = 0;
}

void ProgressPrinter::Redraw() {
  if (!interactive_) return;
  ClearLive();
  const auto now = std::chrono::steady_clock::now();
  for (const auto& [id, live] : live_) {
    const double secs = std::chrono::duration<double>(now - live.start).count();
    if (live.fraction >= 0) {
      const int width = 24, filled = static_cast<int>(live.fraction * width);
      std::fprintf(stderr, "  %-20s [%s%s] %3.0f%%  %s\n", id.c_str(), std::string(filled, '#').c_str(),
                   std::string(width - filled, '.').c_str(), live.fraction * 100,
                   FormatSeconds(secs).c_str());
    } else {
      std::fprintf(stderr, "  %-20s %s  running %s\n", id.c_str(), live.type.c_str(),
                   FormatSeconds(secs).c_str());
    }
    ++drawn_lines_;
  }
  std::fflush(stderr);
  last_draw_ = now;
}

void ProgressPrinter::OnStageStart(const std::string& id, const std::string& type) {
  std::lock_guard<std::mutex> g(mu_);
  live_[id] = Live{type, -1, std::chrono::steady_clock::now()};
  if (interactive_) Redraw();
  else if (!quiet_) std::fprintf(stderr, "start  %s (%s)\n", id.c_str(), type.c_str());
}

void ProgressPrinter::OnStageWaiting(const std::string& id, const std::string& why) {
  std::lock_guard<std::mutex> g(mu_);
  if (interactive_) ClearLive();
  if (!quiet_) std::fprintf(stderr, "wait   %s: %s\n", id.c_str(), why.c_str());
  if (interactive_) Redraw();
}

void ProgressPrinter::OnStageProgress(const std::string& id, double fraction) {
  std::lock_guard<std::mutex> g(mu_);
  auto it = live_.find(id);
  if (it == live_.end()) return;
  it->second.fraction = fraction;
  if (interactive_ && std::chrono::steady_clock::now() - last_draw_ > std::chrono::milliseconds(100))
    Redraw();
}

void ProgressPrinter::OnStageEnd(const StageOutcome& o, int done, int total) {
  std::lock_guard<std::mutex> g(mu_);
  live_.erase(o.id);
  if (interactive_) ClearLive();
  const bool failed = o.state == StageOutcome::State::kFailed;
  if (!quiet_ || failed) {
    std::string figures;
    if (o.state == StageOutcome::State::kRan)
      figures = "  " + FormatSeconds(o.result.wall_s) + ", cpu " +
                FormatSeconds(o.result.user_s + o.result.sys_s) + ", peak " +
                FormatBytes(o.result.peak_rss_bytes);
    if (!o.warnings.empty())
      figures += std::string(figures.empty() ? "  " : "; ") + std::to_string(o.warnings.size()) +
                 (o.warnings.size() == 1 ? " warning" : " warnings") +
                 (o.state == StageOutcome::State::kHit ? " (from the cached run)" : "");
    std::fprintf(stderr, "[%d/%d] %-7s %s (%s)%s\n", done, total, StateName(o.state), o.id.c_str(),
                 o.type.c_str(), figures.c_str());
    if (!quiet_)
      for (const std::string& w : o.warnings)
        std::fprintf(stderr, "        warning: %s\n", w.c_str());
    if (!o.error.empty() && o.state != StageOutcome::State::kSkipped)
      std::fprintf(stderr, "        error: %s\n", o.error.c_str());
    if (failed && !o.result.log_tail.empty())
      std::fprintf(stderr, "        last lines of its log:\n%s\n", o.result.log_tail.c_str());
  }
  if (interactive_) Redraw();
}

}  // namespace pb
