// Progress on the terminal: a live line per running stage (with its
// stage-reported fraction) when stderr is a terminal; plain lines, one per
// finished stage, when it is not (logs, CI).
#pragma once

#include <chrono>
#include <map>
#include <mutex>
#include <string>

#include "engine/scheduler.h"

namespace pb {

class ProgressPrinter : public RunObserver {
 public:
  // `interactive`: redraw live lines (a terminal). `quiet`: failures only.
  ProgressPrinter(bool interactive, bool quiet) : interactive_(interactive), quiet_(quiet) {}
  void OnStageStart(const std::string& id, const std::string& type) override;
  void OnStageWaiting(const std::string& id, const std::string& why) override;
  void OnStageProgress(const std::string& id, double fraction) override;
  void OnStageEnd(const StageOutcome& outcome, int done, int total) override;

 private:
  struct Live {
    std::string type;
    double fraction = -1;
    std::chrono::steady_clock::time_point start;
  };
  void Redraw();  // holds mu_
  void ClearLive();

  bool interactive_;
  bool quiet_;
  std::mutex mu_;
  std::map<std::string, Live> live_;
  int drawn_lines_ = 0;
  std::chrono::steady_clock::time_point last_draw_{};
};

std::string FormatSeconds(double s);

}  // namespace pb
