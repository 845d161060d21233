#include "engine/executor.h"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstring>
#include <fstream>
#include <sstream>

#include "base/env.h"
#include "engine/stage_context.h"

extern char** environ;

namespace pb {
namespace {

using Clock = std::chrono::steady_clock;

std::string LastLines(const std::string& path, int count) {
  Expected<std::string> text = Env::Default()->ReadFile(path);
  if (!text.ok()) return "";
  const std::string& s = *text;
  size_t end = s.size();
  if (end > 0 && s[end - 1] == '\n') --end;
  size_t start = end;
  for (int i = 0; i < count && start > 0; ++i) {
    const size_t nl = s.rfind('\n', start - 1);
    start = nl == std::string::npos ? 0 : nl;
    if (nl == std::string::npos) break;
  }
  if (start < end && s[start] == '\n') ++start;
  return s.substr(start, end - start);
}

nlohmann::json ResultToJson(const JobResult& r) {
  nlohmann::json outs = nlohmann::json::object();
  for (const auto& [port, out] : r.outputs)
    outs[port] = {{"type", out.type}, {"files", out.files}, {"meta", out.meta}};
  return {{"ok", r.status.ok()},    {"error", r.status.message()}, {"outputs", outs},
          {"counters", r.counters}, {"phases", r.phases},          {"warnings", r.warnings},
          {"wall_s", r.wall_s}};
}

void ReadProcIo(pid_t pid, JobResult& result) {
  std::ifstream io("/proc/" + std::to_string(pid) + "/io");
  std::string key;
  uint64_t value;
  while (io >> key >> value) {
    if (key == "rchar:") result.read_bytes = value;
    if (key == "wchar:") result.write_bytes = value;
  }
}

}  // namespace

nlohmann::json JobSpec::ToJson() const {
  nlohmann::json inputs_json = nlohmann::json::object();
  for (const auto& [port, view] : inputs)
    inputs_json[port] = {{"type", view.type}, {"files", view.files}, {"meta", view.meta}};
  return {{"stage_id", stage_id}, {"type", type->id},      {"params", params},
          {"inputs", inputs_json}, {"staging_dir", staging_dir}, {"plugins", plugins},
          {"threads", threads}};
}

JobResult InProcessExecutor::Run(const JobSpec& job, const ProgressFn& progress) {
  struct rusage before, after;
  ::getrusage(RUSAGE_THREAD, &before);
  JobResult result = RunStageHere(job, progress);
  ::getrusage(RUSAGE_THREAD, &after);
  auto secs = [](const timeval& a, const timeval& b) {
    return static_cast<double>(b.tv_sec - a.tv_sec) + 1e-6 * static_cast<double>(b.tv_usec - a.tv_usec);
  };
  result.user_s = secs(before.ru_utime, after.ru_utime);
  result.sys_s = secs(before.ru_stime, after.ru_stime);
  return result;
}

JobResult LocalProcessExecutor::Run(const JobSpec& job, const ProgressFn& progress) {
  JobResult result;
  Env* env = Env::Default();
  const std::string job_path = JoinPath(job.staging_dir, "_job.json");
  const std::string result_path = JoinPath(job.staging_dir, "_result.json");
  Status st = env->WriteFileAtomic(job_path, job.ToJson().dump(-1, ' ', false,
                                                               nlohmann::json::error_handler_t::replace));
  if (!st.ok()) {
    result.status = st;
    return result;
  }
  const std::string log_path = job.log_path.empty() ? JoinPath(job.staging_dir, "_log.txt") : job.log_path;
  (void)env->CreateDirs(DirName(log_path));
  const int log_fd = ::open(log_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (log_fd < 0) {
    result.status = Status::Errno(log_path, "open log");
    return result;
  }
  int pipe_fds[2];
  if (::pipe2(pipe_fds, O_CLOEXEC) != 0) {
    ::close(log_fd);
    result.status = Status::Errno("pipe", "create");
    return result;
  }
  // Everything the child needs is prepared before fork(): between fork and
  // exec only async-signal-safe calls are allowed in a threaded parent.
  std::vector<std::string> env_strings;
  for (char** e = environ; *e; ++e)
    if (std::strncmp(*e, "PB_PROGRESS_FD=", 15) != 0) env_strings.emplace_back(*e);
  env_strings.push_back("PB_PROGRESS_FD=3");
  std::vector<char*> envp;
  for (auto& s : env_strings) envp.push_back(s.data());
  envp.push_back(nullptr);
  std::string arg0 = "pointbake", arg1 = "__stage", arg2 = job_path;
  char* argv[] = {arg0.data(), arg1.data(), arg2.data(), nullptr};
  const pid_t parent = ::getpid();

  const auto start = Clock::now();
  const pid_t pid = ::fork();
  if (pid < 0) {
    ::close(log_fd);
    ::close(pipe_fds[0]);
    ::close(pipe_fds[1]);
    result.status = Status::Errno("fork", "stage " + job.stage_id);
    return result;
  }
  if (pid == 0) {
    ::prctl(PR_SET_PDEATHSIG, SIGKILL);
    if (::getppid() != parent) ::_exit(127);
    if (pipe_fds[1] == 3) ::fcntl(3, F_SETFD, 0);  // dup2 onto itself keeps CLOEXEC
    else ::dup2(pipe_fds[1], 3);
    ::dup2(log_fd, 1);
    ::dup2(log_fd, 2);
    ::execve(self_exe_.c_str(), argv, envp.data());
    ::_exit(127);
  }
  ::close(log_fd);
  ::close(pipe_fds[1]);

  // Progress lines "P <fraction>\n" until the child closes the pipe.
  std::string pending;
  char buf[512];
  for (;;) {
    ssize_t n = ::read(pipe_fds[0], buf, sizeof buf);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    pending.append(buf, static_cast<size_t>(n));
    size_t nl;
    while ((nl = pending.find('\n')) != std::string::npos) {
      const std::string line = pending.substr(0, nl);
      pending.erase(0, nl + 1);
      if (line.size() > 2 && line[0] == 'P' && progress) progress(std::atof(line.c_str() + 2));
    }
  }
  ::close(pipe_fds[0]);

  // Read /proc/<pid>/io while the child is a zombie, then reap it.
  siginfo_t info;
  while (::waitid(P_PID, static_cast<id_t>(pid), &info, WEXITED | WNOWAIT) != 0 && errno == EINTR) {
  }
  ReadProcIo(pid, result);
  int wstatus = 0;
  struct rusage ru {};
  for (;;) {
    if (::wait4(pid, &wstatus, 0, &ru) >= 0) break;
    if (errno != EINTR) {
      result.status = Status::Errno("wait4", "stage " + job.stage_id);
      return result;
    }
  }
  result.wall_s = std::chrono::duration<double>(Clock::now() - start).count();
  result.user_s = static_cast<double>(ru.ru_utime.tv_sec) + 1e-6 * static_cast<double>(ru.ru_utime.tv_usec);
  result.sys_s = static_cast<double>(ru.ru_stime.tv_sec) + 1e-6 * static_cast<double>(ru.ru_stime.tv_usec);
  result.peak_rss_bytes = static_cast<uint64_t>(ru.ru_maxrss) * 1024;

  if (WIFSIGNALED(wstatus)) {
    const int sig = WTERMSIG(wstatus);
    result.status = Status::Internal("stage process killed by signal " + std::to_string(sig) + " (" +
                                     strsignal(sig) + ")" +
                                     (sig == SIGKILL ? "; out of memory?" : ""));
    result.log_tail = LastLines(log_path, 20);
    return result;
  }
  Expected<std::string> text = env->ReadFile(result_path);
  nlohmann::json j = text.ok() ? nlohmann::json::parse(*text, nullptr, false) : nlohmann::json();
  if (!text.ok() || j.is_discarded()) {
    result.status = Status::Internal("stage process exited with status " +
                                     std::to_string(WEXITSTATUS(wstatus)) + " without a result");
    result.log_tail = LastLines(log_path, 20);
    return result;
  }
  result.counters = j.value("counters", nlohmann::json::object());
  result.phases = j.value("phases", nlohmann::json::array());
  if (j.contains("warnings") && j["warnings"].is_array())
    for (const auto& w : j["warnings"])
      if (w.is_string()) result.warnings.push_back(w.get<std::string>());
  if (!j.value("ok", false)) {
    result.status = Status::Invalid(j.value("error", std::string("stage failed")));
    result.log_tail = LastLines(log_path, 20);
    return result;
  }
  for (const auto& [port, out] : j["outputs"].items()) {
    Cache::StagedOutput staged;
    staged.type = out.value("type", "");
    staged.files = out.value("files", std::map<std::string, std::string>{});
    staged.meta = out.value("meta", nlohmann::json::object());
    result.outputs[port] = std::move(staged);
  }
  return result;
}

Expected<LoadedJob> LoadJobFile(const std::string& job_path, Registry& registry) {
  PB_ASSIGN_OR_RETURN(const std::string text, Env::Default()->ReadFile(job_path));
  const nlohmann::json j = nlohmann::json::parse(text, nullptr, false);
  if (j.is_discarded() || !j.is_object()) return Status::Invalid(job_path + ": not JSON");
  LoadedJob loaded;
  JobSpec& job = loaded.job;
  job.plugins = j.value("plugins", std::vector<std::string>{});
  for (const auto& plugin : job.plugins) {
    Status st = registry.LoadPlugin(plugin);
    if (!st.ok()) loaded.status = st;
  }
  job.stage_id = j.value("stage_id", "");
  job.type = registry.Find(j.value("type", ""));
  job.params = j.value("params", nlohmann::json::object());
  job.staging_dir = j.value("staging_dir", "");
  job.threads = j.value("threads", 0);
  const nlohmann::json inputs = j.value("inputs", nlohmann::json::object());
  for (const auto& [port, in] : inputs.items()) {
    ArtifactView view;
    view.type = in.value("type", "");
    view.files = in.value("files", std::map<std::string, std::string>{});
    view.meta = in.value("meta", nlohmann::json::object());
    job.inputs[port] = std::move(view);
  }
  if (loaded.status.ok() && !job.type)
    loaded.status = Status::NotFound("unknown stage type '" + j.value("type", "") + "'");
  return loaded;
}

int RunStageSubcommand(const std::string& job_path, Registry& registry) {
  Expected<LoadedJob> loaded = LoadJobFile(job_path, registry);
  if (!loaded.ok()) {
    std::fprintf(stderr, "pointbake __stage: %s\n", loaded.status().message().c_str());
    return 2;
  }
  const JobSpec& job = loaded->job;
  JobResult result;
  result.status = loaded->status;
  if (result.status.ok()) {
    // Progress to fd 3, at most every 100 ms or 1 %.
    const char* fd_text = std::getenv("PB_PROGRESS_FD");
    const int fd = fd_text ? std::atoi(fd_text) : -1;
    double last_fraction = -1;
    auto last_time = Clock::now() - std::chrono::seconds(1);
    ProgressFn progress = [&](double f) {
      if (fd < 0) return;
      const auto now = Clock::now();
      if (f < 1.0 && f - last_fraction < 0.01 && now - last_time < std::chrono::milliseconds(100))
        return;
      last_fraction = f;
      last_time = now;
      char line[32];
      const int n = std::snprintf(line, sizeof line, "P %.4f\n", f);
      (void)!::write(fd, line, static_cast<size_t>(n));
    };
    result = RunStageHere(job, progress, /*log_warnings=*/true);
  }
  if (!result.status.ok()) std::fprintf(stderr, "error: %s\n", result.status.message().c_str());
  Status st = Env::Default()->WriteFileAtomic(
      JoinPath(job.staging_dir, "_result.json"),
      ResultToJson(result).dump(-1, ' ', false, nlohmann::json::error_handler_t::replace));
  if (!st.ok()) {
    std::fprintf(stderr, "pointbake __stage: %s\n", st.message().c_str());
    return 2;
  }
  return result.status.ok() ? 0 : 1;
}

}  // namespace pb
