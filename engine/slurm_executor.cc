#include "engine/slurm_executor.h"

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstring>
#include <set>
#include <sstream>
#include <thread>

#include "base/env.h"

extern char** environ;

namespace pb {
namespace {

using Clock = std::chrono::steady_clock;

// Set by the signal handler; read by every waiting job thread. A signal
// handler can only reach process-wide state.
std::atomic<bool> g_interrupted{false};
std::atomic<int> g_executors{0};
struct sigaction g_old_int, g_old_term;

void OnInterrupt(int) { g_interrupted.store(true); }

struct CommandResult {
  int exit_status = -1;  // -1: did not exit normally
  std::string output;    // stdout and stderr together
};

// Runs argv[0] (looked up in PATH) with stdout+stderr captured.
Expected<CommandResult> RunCommand(const std::vector<std::string>& args) {
  int fds[2];
  if (::pipe2(fds, O_CLOEXEC) != 0) return Status::Errno("pipe", "create");
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, fds[1], 1);
  posix_spawn_file_actions_adddup2(&actions, fds[1], 2);
  std::vector<char*> argv;
  std::vector<std::string> copy = args;
  for (std::string& a : copy) argv.push_back(a.data());
  argv.push_back(nullptr);
  pid_t pid = 0;
  const int rc = ::posix_spawnp(&pid, argv[0], &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  ::close(fds[1]);
  if (rc != 0) {
    ::close(fds[0]);
    return Status::Invalid("cannot run '" + args[0] + "': " + std::strerror(rc) +
                           (rc == ENOENT ? " (is Slurm installed and in PATH?)" : ""));
  }
  CommandResult result;
  char buf[4096];
  for (;;) {
    const ssize_t n = ::read(fds[0], buf, sizeof buf);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    result.output.append(buf, static_cast<size_t>(n));
  }
  ::close(fds[0]);
  int wstatus = 0;
  while (::waitpid(pid, &wstatus, 0) < 0 && errno == EINTR) {
  }
  if (WIFEXITED(wstatus)) result.exit_status = WEXITSTATUS(wstatus);
  return result;
}

std::string Trim(std::string s) {
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.pop_back();
  size_t i = 0;
  while (i < s.size() && std::isspace(static_cast<unsigned char>(s[i]))) ++i;
  return s.substr(i);
}

// The value of "Key=" in a `scontrol -o` line (values hold no spaces, except
// Reason's free text, which is read up to the next " Key=").
std::string Field(const std::string& line, const std::string& key) {
  const std::string needle = " " + key + "=";
  size_t at = (" " + line).find(needle);
  if (at == std::string::npos) return "";
  const size_t start = at + needle.size() - 1;  // in `line`
  size_t end = line.find(' ', start);
  return line.substr(start, end == std::string::npos ? std::string::npos : end - start);
}

std::string LastLines(const std::string& text, int count) {
  size_t end = text.size();
  while (end > 0 && text[end - 1] == '\n') --end;
  size_t start = end;
  for (int i = 0; i < count && start > 0; ++i) {
    const size_t nl = text.rfind('\n', start - 1);
    if (nl == std::string::npos) {
      start = 0;
      break;
    }
    start = nl;
  }
  if (start < end && text[start] == '\n') ++start;
  return text.substr(start, end - start);
}

std::string JsonText(const nlohmann::json& j) {
  return j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

std::string ShellQuote(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

std::string SlurmDuration(double seconds) {
  const long minutes = static_cast<long>(std::ceil(seconds / 60.0));
  char buf[32];
  std::snprintf(buf, sizeof buf, "%ld:%02ld:00", minutes / 60, minutes % 60);
  return buf;
}

}  // namespace

bool SlurmJobState::Terminal() const {
  static const std::set<std::string> kLive = {"PENDING",    "CONFIGURING", "RUNNING",   "COMPLETING",
                                              "SUSPENDED",  "REQUEUED",    "RESIZING",  "SIGNALING",
                                              "STAGE_OUT",  "REQUEUE_HOLD", "REQUEUE_FED",
                                              "RESV_DEL_HOLD", "STOPPED"};
  return !state.empty() && !kLive.count(state);
}

std::optional<SlurmJobState> ParseScontrolJob(const std::string& line) {
  SlurmJobState s;
  s.state = Field(line, "JobState");
  if (s.state.empty()) return std::nullopt;
  // Reason may be free text with spaces: everything up to " Dependency=".
  const size_t r = line.find(" Reason=");
  if (r != std::string::npos) {
    const size_t start = r + 8;
    const size_t end = line.find(" Dependency=", start);
    s.reason = line.substr(start, end == std::string::npos ? std::string::npos : end - start);
  }
  s.exit_code = Field(line, "ExitCode");
  s.node = Field(line, "BatchHost");
  return s;
}

uint64_t SlurmMemMiB(const SlurmOptions& o, uint64_t estimate_bytes, int attempt) {
  double bytes = estimate_bytes > 0
                     ? static_cast<double>(estimate_bytes) * o.mem_factor + static_cast<double>(o.mem_margin_bytes)
                     : static_cast<double>(o.default_mem_bytes);
  if (attempt > 1) bytes *= 2;
  return std::max<uint64_t>(1, static_cast<uint64_t>(std::ceil(bytes / (1 << 20))));
}

std::string SlurmTimeLimit(const SlurmOptions& o, double learned_wall_s) {
  if (!o.time.empty()) return o.time;
  if (learned_wall_s <= 0) return o.unknown_time;
  return SlurmDuration(3 * learned_wall_s + 600);
}

bool SlurmKilledForMemory(const SlurmJobState& state, const std::string& slurm_output) {
  return state.state == "OUT_OF_MEMORY" ||
         slurm_output.find("exceeded memory limit") != std::string::npos ||
         slurm_output.find("oom-kill") != std::string::npos;
}

nlohmann::json JobResultToJson(const JobResult& r) {
  nlohmann::json outs = nlohmann::json::object();
  for (const auto& [port, out] : r.outputs)
    outs[port] = {{"type", out.type}, {"files", out.files}, {"meta", out.meta}};
  return {{"ok", r.status.ok()},          {"error", r.status.message()},
          {"outputs", outs},              {"counters", r.counters},
          {"phases", r.phases},           {"wall_s", r.wall_s},
          {"user_s", r.user_s},           {"sys_s", r.sys_s},
          {"peak_rss_bytes", r.peak_rss_bytes}, {"read_bytes", r.read_bytes},
          {"write_bytes", r.write_bytes}, {"log_tail", r.log_tail},
          {"warnings", r.warnings}};
}

JobResult JobResultFromJson(const nlohmann::json& j) {
  JobResult r;
  if (!j.value("ok", false)) r.status = Status::Invalid(j.value("error", std::string("stage failed")));
  r.counters = j.value("counters", nlohmann::json::object());
  r.phases = j.value("phases", nlohmann::json::array());
  r.wall_s = j.value("wall_s", 0.0);
  r.user_s = j.value("user_s", 0.0);
  r.sys_s = j.value("sys_s", 0.0);
  r.peak_rss_bytes = j.value("peak_rss_bytes", uint64_t{0});
  r.read_bytes = j.value("read_bytes", uint64_t{0});
  r.write_bytes = j.value("write_bytes", uint64_t{0});
  r.log_tail = j.value("log_tail", std::string());
  if (j.contains("warnings") && j["warnings"].is_array())
    for (const auto& w : j["warnings"])
      if (w.is_string()) r.warnings.push_back(w.get<std::string>());
  const nlohmann::json outputs = j.value("outputs", nlohmann::json::object());
  for (const auto& [port, out] : outputs.items()) {
    Cache::StagedOutput staged;
    staged.type = out.value("type", "");
    staged.files = out.value("files", std::map<std::string, std::string>{});
    staged.meta = out.value("meta", nlohmann::json::object());
    r.outputs[port] = std::move(staged);
  }
  return r;
}

SlurmExecutor::SlurmExecutor(std::string self_exe, SlurmOptions options)
    : self_exe_(std::move(self_exe)), options_(std::move(options)) {
  if (g_executors.fetch_add(1) == 0) {
    g_interrupted.store(false);
    struct sigaction sa {};
    sa.sa_handler = OnInterrupt;
    sigemptyset(&sa.sa_mask);
    ::sigaction(SIGINT, &sa, &g_old_int);
    ::sigaction(SIGTERM, &sa, &g_old_term);
  }
}

SlurmExecutor::~SlurmExecutor() {
  if (g_executors.fetch_sub(1) == 1) {
    ::sigaction(SIGINT, &g_old_int, nullptr);
    ::sigaction(SIGTERM, &g_old_term, nullptr);
  }
}

bool SlurmExecutor::Interrupted() { return g_interrupted.load(); }

void SlurmExecutor::Cancel(const std::string& job_id) {
  (void)RunCommand({options_.scancel, job_id});
}

JobResult SlurmExecutor::Run(const JobSpec& job, const ProgressFn& progress) {
  bool killed_for_memory = false;
  JobResult result = RunAttempt(job, 1, &killed_for_memory);
  if (killed_for_memory && !Interrupted()) {
    const std::string first = result.status.message();
    result = RunAttempt(job, 2, &killed_for_memory);
    if (!result.status.ok())
      result.status = Status::Invalid(result.status.message() + " (retried once with twice the memory after: " +
                                      first + ")");
  }
  if (progress && result.status.ok()) progress(1.0);
  return result;
}

JobResult SlurmExecutor::RunAttempt(const JobSpec& job, int attempt, bool* killed_for_memory) {
  *killed_for_memory = false;
  JobResult result;
  Env* env = Env::Default();
  if (Interrupted()) {
    result.status = Status::Invalid("not submitted: interrupted (Ctrl-C)");
    return result;
  }
  // A retry starts from an empty staging folder: nothing of the killed job
  // is kept.
  if (attempt > 1) {
    Status st = env->RemoveAll(job.staging_dir);
    if (st.ok()) st = env->CreateDirs(job.staging_dir);
    if (!st.ok()) {
      result.status = st;
      return result;
    }
  }
  const std::string job_path = JoinPath(job.staging_dir, "_slurm_job.json");
  const std::string result_path = JoinPath(job.staging_dir, "_slurm_result.json");
  const std::string slurm_out = JoinPath(job.staging_dir, "_slurm.out");
  const std::string stage_log = JoinPath(job.staging_dir, "_log.txt");
  const int cpus = job.threads > 0 ? job.threads : 1;
  nlohmann::json spec = job.ToJson();
  spec["threads"] = cpus;
  Status st = env->WriteFileAtomic(job_path, JsonText(spec));
  if (!st.ok()) {
    result.status = st;
    return result;
  }
  const uint64_t mem_mib = SlurmMemMiB(options_, job.peak_estimate_bytes, attempt);
  std::vector<std::string> args = {options_.sbatch,
                                   "--parsable",
                                   "--job-name=pb:" + job.stage_id,
                                   "--output=" + slurm_out,
                                   "--mem=" + std::to_string(mem_mib) + "M",
                                   "--cpus-per-task=" + std::to_string(cpus),
                                   "--ntasks=1",
                                   "--time=" + SlurmTimeLimit(options_, job.wall_estimate_s),
                                   "--chdir=" + job.staging_dir};
  if (!options_.partition.empty()) args.push_back("--partition=" + options_.partition);
  if (!options_.account.empty()) args.push_back("--account=" + options_.account);
  if (!options_.qos.empty()) args.push_back("--qos=" + options_.qos);
  for (const std::string& a : options_.sbatch_args) args.push_back(a);
  args.push_back("--wrap=exec " + ShellQuote(self_exe_) + " __job " + ShellQuote(job_path));

  const auto submitted_at = Clock::now();
  std::string job_id;
  {
    Expected<CommandResult> sub = RunCommand(args);
    if (!sub.ok()) {
      result.status = sub.status();
      return result;
    }
    // --parsable prints "id[;cluster]" last; a site's sbatch may warn before it.
    std::string last = Trim(sub->output);
    last = last.substr(last.rfind('\n') == std::string::npos ? 0 : last.rfind('\n') + 1);
    job_id = Trim(last.substr(0, last.find(';')));
    if (sub->exit_status != 0 || job_id.empty() ||
        job_id.find_first_not_of("0123456789") != std::string::npos) {
      result.status = Status::Invalid("sbatch failed for stage '" + job.stage_id + "': " + Trim(sub->output));
      return result;
    }
  }

  // Wait: the result file appears when the job is done; Slurm is asked
  // whether the job died without one. Both polls slow down as the job ages
  // (a long stage need not be seen ending within 50 ms, and hundreds of jobs
  // in flight must not flood slurmctld): the file every 50 ms growing to 1 s,
  // Slurm every second growing to 30 s.
  SlurmJobState state;
  bool cancelled_by_us = false;
  auto last_query = Clock::now();
  std::optional<Clock::time_point> ended_at;
  for (;;) {
    if (env->Exists(result_path)) break;
    if (Interrupted() && !cancelled_by_us) {
      Cancel(job_id);
      cancelled_by_us = true;
    }
    const auto now = Clock::now();
    const double age_s = std::chrono::duration<double>(now - submitted_at).count();
    if (!ended_at && now - last_query >= std::chrono::duration<double>(std::min(30.0, 1.0 + age_s / 20))) {
      last_query = now;
      Expected<CommandResult> q = RunCommand({options_.scontrol, "show", "job", "-o", job_id});
      if (q.ok()) {
        std::optional<SlurmJobState> parsed = ParseScontrolJob(q->output);
        if (parsed) {
          state = *parsed;
          if (state.Terminal()) ended_at = now;
        } else if (q->output.find("Invalid job id") != std::string::npos) {
          // Purged from slurmctld's memory (MinJobAge) before we looked.
          state.state = "UNKNOWN";
          state.reason = "the job is no longer known to Slurm";
          ended_at = now;
        }
      }
    }
    // A job that exited by itself wrote its result; give a shared file
    // system's caches time to show it. A killed one never will.
    const bool exited = (state.state == "COMPLETED" || state.state == "FAILED") &&
                        state.exit_code.size() > 2 &&
                        state.exit_code.compare(state.exit_code.size() - 2, 2, ":0") == 0;
    if (ended_at && (!exited || now - *ended_at > std::chrono::duration<double>(options_.result_grace_s)))
      break;
    std::this_thread::sleep_for(std::chrono::duration<double>(std::min(1.0, options_.poll_s + age_s / 100)));
  }
  const double elapsed_s = std::chrono::duration<double>(Clock::now() - submitted_at).count();

  // The stage's log into the run's log folder, with where the job ran.
  Expected<std::string> stage_text = env->ReadFile(stage_log);
  Expected<std::string> slurm_text = env->ReadFile(slurm_out);
  if (!job.log_path.empty()) {
    (void)env->CreateDirs(DirName(job.log_path));
    // The retry's log follows the killed attempt's.
    Expected<std::string> before = attempt > 1 ? env->ReadFile(job.log_path) : Expected<std::string>("");
    std::string text = (before.ok() ? *before : "") + (stage_text.ok() ? *stage_text : "");
    text += "--- slurm job " + job_id + " (attempt " + std::to_string(attempt) + ", --mem=" +
            std::to_string(mem_mib) + "M), " + std::to_string(elapsed_s) + " s from submission to result\n";
    if (slurm_text.ok() && !slurm_text->empty()) text += *slurm_text;
    (void)env->WriteFileAtomic(job.log_path, text);
  }

  Expected<std::string> text = env->ReadFile(result_path);
  if (text.ok()) {
    nlohmann::json j = nlohmann::json::parse(*text, nullptr, false);
    if (!j.is_discarded() && j.is_object()) return JobResultFromJson(j);
  }
  // No result: Slurm's word on why.
  std::string why = "Slurm job " + job_id;
  if (!state.node.empty() && state.node != "(null)") why += " on " + state.node;
  why += " ended " + (state.state.empty() ? std::string("without a result") : state.state);
  if (!state.reason.empty() && state.reason != "None") why += " (reason: " + state.reason + ")";
  if (!state.exit_code.empty()) why += ", exit code " + state.exit_code;
  const std::string slurm_lines = slurm_text.ok() ? LastLines(*slurm_text, 3) : "";
  if (cancelled_by_us) {
    why += "; cancelled because pointbake was interrupted";
  } else if (SlurmKilledForMemory(state, slurm_text.ok() ? *slurm_text : "")) {
    *killed_for_memory = true;
    why += "; out of memory at --mem=" + std::to_string(mem_mib) + "M";
  } else if (state.state == "COMPLETED") {
    why += " but its result file " + result_path +
           " never appeared (is the cache on a file system the compute nodes share?)";
  }
  if (!slurm_lines.empty()) why += "\n" + slurm_lines;
  result.status = Status::Invalid(why);
  result.wall_s = elapsed_s;
  result.log_tail = stage_text.ok() ? LastLines(*stage_text, 20) : "";
  return result;
}

int RunSlurmJobSubcommand(const std::string& job_path, Registry& registry) {
  Expected<LoadedJob> loaded = LoadJobFile(job_path, registry);
  if (!loaded.ok()) {
    std::fprintf(stderr, "pointbake __job: %s\n", loaded.status().message().c_str());
    return 2;
  }
  JobSpec& job = loaded->job;
  JobResult result;
  result.status = loaded->status;
  if (job.staging_dir.empty()) {
    std::fprintf(stderr, "pointbake __job: %s: no staging_dir\n", job_path.c_str());
    return 2;
  }
  if (result.status.ok()) {
    // The stage runs as our child, measured exactly as by the local executor.
    job.log_path = JoinPath(job.staging_dir, "_log.txt");
    LocalProcessExecutor local("/proc/self/exe");
    result = local.Run(job, nullptr);
  }
  Status st = Env::Default()->WriteFileAtomic(JoinPath(job.staging_dir, "_slurm_result.json"),
                                              JsonText(JobResultToJson(result)));
  if (!st.ok()) {
    std::fprintf(stderr, "pointbake __job: %s\n", st.message().c_str());
    return 2;
  }
  if (!result.status.ok()) std::fprintf(stderr, "pointbake __job: stage failed: %s\n", result.status.message().c_str());
  return result.status.ok() ? 0 : 1;
}

}  // namespace pb
