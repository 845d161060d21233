#include "engine/stage_context.h"

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cstdio>
#include <mutex>
#include <thread>

#include "base/env.h"

namespace pb {
namespace {

using Clock = std::chrono::steady_clock;

class ContextImpl : public StageContext {
 public:
  ContextImpl(const JobSpec& job, const ProgressFn& progress, bool log_warnings)
      : job_(job), progress_(progress), log_warnings_(log_warnings), start_(Clock::now()) {}

  const nlohmann::json& params() const override { return job_.params; }
  bool has_input(std::string_view port) const override {
    return job_.inputs.count(std::string(port)) > 0;
  }
  const ArtifactView& input(std::string_view port) const override {
    auto it = job_.inputs.find(std::string(port));
    assert(it != job_.inputs.end() && "stage asked for an input it did not declare or check");
    return it->second;
  }
  std::string output_path(std::string_view port, std::string_view file_name) override {
    const std::string dir = JoinPath(job_.staging_dir, port);
    (void)Env::Default()->CreateDirs(dir);
    const std::string path = JoinPath(dir, file_name);
    outputs_[std::string(port)].files[std::string(file_name)] = path;
    return path;
  }
  void set_output_meta(std::string_view port, nlohmann::json meta) override {
    outputs_[std::string(port)].meta = std::move(meta);
  }
  void progress(double fraction) override {
    if (progress_) progress_(std::clamp(fraction, 0.0, 1.0));
  }
  void counter(std::string_view name, double value) override { counters_[std::string(name)] = value; }
  void begin_phase(std::string_view name) override {
    open_phases_.push_back({std::string(name), Seconds()});
  }
  void end_phase(std::string_view name) override {
    for (auto it = open_phases_.rbegin(); it != open_phases_.rend(); ++it) {
      if (it->first != name) continue;
      phases_.push_back({{"name", it->first}, {"start_s", it->second}, {"dur_s", Seconds() - it->second}});
      open_phases_.erase(std::next(it).base());
      return;
    }
  }
  int threads() const override {
    if (job_.threads > 0) return job_.threads;
    return std::max(1u, std::thread::hardware_concurrency());
  }
  void warning(std::string_view message) override {
    std::string text(message);
    while (!text.empty() && std::isspace(static_cast<unsigned char>(text.back()))) text.pop_back();
    for (char& c : text)
      if (c == '\n' || c == '\r') c = ' ';  // one line each on the progress line and in the report
    if (text.empty()) return;
    std::lock_guard<std::mutex> lock(warnings_mu_);  // stages may warn from worker threads
    if (log_warnings_) std::fprintf(stderr, "warning: %s\n", text.c_str());
    if (static_cast<int>(warnings_.size()) < kMaxStageWarnings)
      warnings_.push_back(std::move(text));
    else
      ++dropped_warnings_;
  }

  double Seconds() const {
    return std::chrono::duration<double>(Clock::now() - start_).count();
  }

  JobResult Finish(Status status) {
    JobResult result;
    if (status.ok()) {
      for (const PortSpec& port : job_.type->outputs) {
        auto it = outputs_.find(port.name);
        if (it == outputs_.end() || it->second.files.empty()) {
          status = Status::Internal("stage type '" + job_.type->id + "' did not write its output '" +
                                    port.name + "' (a bug in the stage)");
          break;
        }
        for (const auto& [name, path] : it->second.files)
          if (!Env::Default()->Exists(path)) {
            status = Status::Internal("stage type '" + job_.type->id + "' declared output file " +
                                      port.name + "/" + name + " but did not write it");
          }
        it->second.type = port.type;
      }
    }
    result.status = status;
    if (status.ok()) result.outputs = outputs_;
    result.counters = counters_;
    result.phases = phases_;
    result.wall_s = Seconds();
    result.warnings = warnings_;
    if (dropped_warnings_ > 0)
      result.warnings.push_back("... and " + std::to_string(dropped_warnings_) +
                                " more warnings (see the stage's log)");
    return result;
  }

 private:
  const JobSpec& job_;
  const ProgressFn& progress_;
  const bool log_warnings_;
  Clock::time_point start_;
  std::mutex warnings_mu_;
  std::vector<std::string> warnings_;
  int dropped_warnings_ = 0;
  std::map<std::string, Cache::StagedOutput> outputs_;
  nlohmann::json counters_ = nlohmann::json::object();
  nlohmann::json phases_ = nlohmann::json::array();
  std::vector<std::pair<std::string, double>> open_phases_;
};

}  // namespace

JobResult RunStageHere(const JobSpec& job, const ProgressFn& progress, bool log_warnings) {
  ContextImpl ctx(job, progress, log_warnings);
  Status status;
  try {
    status = job.type->run(ctx);
  } catch (const std::bad_alloc&) {
    status = Status::Internal("out of memory");
  } catch (const std::exception& e) {
    status = Status::Internal(std::string("uncaught exception: ") + e.what());
  }
  return ctx.Finish(status);
}

}  // namespace pb
